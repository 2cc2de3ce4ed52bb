"""The diagnoser session's health (what /diagnostics says), without ROS."""

import numpy as np
import pytest

from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser_node_config import LEVEL_OK, LEVEL_STALE, LEVEL_WARN, PARAMETERS
from bearing_diagnoser.session import SPEED_UNKNOWN, DiagnoserSession

FS = 12000.0


def session(**values):
    logged = []
    v = {p.name: p.default for p in PARAMETERS} | values
    return DiagnoserSession(v, lambda level, text: logged.append((level, text))), logged


def feed(s, seconds=0.5, now=0.0):
    """Gaussian noise as both observers' pass-through residuals (model set none)."""
    x = np.random.default_rng(1).normal(0.0, 1.0, int(seconds * FS))
    for h in (FaultState.OUTER_RACE, FaultState.INNER_RACE):
        s.on_residual(h, 0.0, 0, FS, x, np.zeros_like(x), np.zeros_like(x), 100.0, "none", now)


def test_stale_before_any_residual():
    s, _ = session()
    assert s.health(0.0).level == LEVEL_STALE


def test_unknown_speed_is_warned_once_and_clears_when_a_speed_is_told():
    s, logged = session(rpm=0.0)
    feed(s)
    health = s.health(0.1)
    assert health.level == LEVEL_WARN and SPEED_UNKNOWN in health.message
    assert logged.count(("warning", SPEED_UNKNOWN)) == 1
    s.on_speed(1800.0 * 2 * np.pi / 60.0)
    assert s.health(0.1).level == LEVEL_OK


@pytest.mark.parametrize("values", [dict(rpm=1797.0), dict(rpm=0.0, model_set="sim_12k")])
def test_no_speed_warning_with_a_nominal_speed_or_a_simulator_model_set(values):
    s, logged = session(**values)
    feed(s)
    assert s.health(0.1).level == LEVEL_OK
    assert not any(SPEED_UNKNOWN in text for _, text in logged)
