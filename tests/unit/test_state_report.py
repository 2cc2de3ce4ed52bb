"""Scoring published states against ground truth (used by make demo and the live tests)."""

import pytest

from bearing_bringup.state_report import StateChange, evaluate, format_table, truth_segments
from bearing_common.states import FaultState

N, OR, IR = FaultState.NORMAL, FaultState.OUTER_RACE, FaultState.INNER_RACE
TRUTH = [StateChange(OR, 0.0, 0.0), StateChange(IR, 0.2, 0.2)]


def test_truth_segments_merge_repeats_and_end_at_data_end():
    truth = TRUTH + [StateChange(IR, 0.3, 0.3)]
    assert truth_segments(truth, 0.4) == [(OR, 0.0, 0.2), (IR, 0.2, 0.4)]


def test_correct_detection_and_delay():
    decided = [StateChange(N, 0.0, 0.05), StateChange(OR, 0.0, 0.06), StateChange(OR, 0.0, 0.1),
               StateChange(IR, 0.21, 0.24), StateChange(IR, 0.21, 0.3)]
    first, second = evaluate(TRUTH, decided, 0.4)
    assert first.correct and first.detected_at == pytest.approx(0.06) and first.delay == pytest.approx(0.06)
    assert second.correct and second.delay == pytest.approx(0.04) and second.onset == pytest.approx(0.21)
    assert "| INNER_RACE | INNER_RACE |" in format_table([first, second])


def test_missed_change_is_reported_as_wrong():
    decided = [StateChange(OR, 0.0, 0.06), StateChange(OR, 0.0, 0.39)]
    first, second = evaluate(TRUTH, decided, 0.4)
    assert first.correct and not second.correct
    assert second.detected_state == OR and second.delay is None


def test_decision_after_segment_end_does_not_count():
    decided = [StateChange(OR, 0.0, 0.21)]  # made after the OR segment ended
    first, _ = evaluate(TRUTH, decided, 0.4)
    assert first.detected_state is None and not first.correct
