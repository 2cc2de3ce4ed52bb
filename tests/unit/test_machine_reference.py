"""The machine's own healthy reference: learnt, saved, used by the decision, the CLI and the node's session."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from bearing_common.bearings import CATALOG
from bearing_common.states import FaultState
from bearing_diagnoser.diagnose_cli import main
from bearing_diagnoser.diagnoser_node_config import PARAMETERS
from bearing_diagnoser.diagnoser_session import DiagnoserSession
from bearing_diagnoser.recording_diagnosis import diagnose_recording, learn_recording_reference
from bearing_diagnoser.spectral.machine_reference import (
    BandLines,
    MachineReferenceError,
    ReferenceLine,
    learn_reference,
    load_reference,
)
from bearing_diagnoser.spectral.settings import SpectralSettings
from bearing_diagnoser.synthetic import burst_train, white_noise
from bearing_recordings.recording import Recording

FS, RPM = 12000.0, 1800.0
BEARING = CATALOG["6205"]
FR = RPM / 60.0
ORDERS = BEARING.orders()
#: A foreign stationary line: amplitude modulation of the whole signal at 0.985 BPFO, inside the
#: outer-race comb's slip search (the healthy machine of issue 25 carried one 2.5 % below 2 BPFO).
LINE_HZ = 0.985 * ORDERS.bpfo * FR


def healthy(seconds: float, seed: int, depth: float = 0.5) -> np.ndarray:
    """White noise amplitude-modulated at :data:`LINE_HZ` (a line of its own in the envelope spectrum)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    return white_noise(seconds, FS, 0.01, rng) * (1.0 + depth * np.cos(2 * np.pi * LINE_HZ * t + rng.uniform(0, 6)))


def recording(x: np.ndarray, path: str = "synthetic") -> Recording:
    return Recording(x, FS, RPM, "npz", path=path, rpm_tolerance=0.02, bearing=BEARING)


def states(result) -> list[FaultState]:
    return [s.state for s in result.segments]


def test_the_machines_own_line_alarms_blind_not_with_its_reference_and_a_new_fault_is_still_found():
    reference = learn_recording_reference(recording(healthy(10.0, 1)))
    assert any(abs(line.hz - LINE_HZ) < reference.bin_width for b in reference.envelope for line in b.lines)
    later = healthy(10.0, 2)
    blind = diagnose_recording(recording(later))
    assert FaultState.OUTER_RACE in states(blind)  # the trap: one foreign line inside the comb's slip search
    judged = diagnose_recording(recording(later), baseline=reference)
    assert states(judged) == [FaultState.NORMAL] and judged.reference == reference.describe()
    fault = later + burst_train(10.0, FS, 0.99 * ORDERS.bpfi * FR, amplitude=6.0, shaft_hz=FR,
                                rng=np.random.default_rng(3))
    assert states(diagnose_recording(recording(fault), baseline=reference)) == [FaultState.INNER_RACE]


def test_known_lines_follow_the_speed_within_its_range_and_supply_lines_stay_in_hz():
    shaft = ReferenceLine(3 * 20.0, 3.0, 40.0, 5.0)
    foreign = ReferenceLine(117.0, 117.0 / 20.0, 10.0, 2.0)
    mains = ReferenceLine(100.0, 5.0 + 0.0, 8.0, 1.0, follows_speed=False)
    ref = learn_like(envelope=(BandLines((1000.0, 3000.0), (shaft, foreign)), BandLines((2000.0, 4000.0), (mains,))))
    centres = lambda lines: lines[1::3]  # each line comes as its main lobe: three points half a bin apart
    assert np.allclose(centres(ref.known_lines(20.2)), sorted([3 * 20.2, 117.0 / 20.0 * 20.2, 100.0]))
    assert np.allclose(centres(ref.known_lines(20.2, (1000.0, 3000.0))), [3 * 20.2, 117.0 / 20.0 * 20.2])
    assert np.allclose(centres(ref.known_lines(25.0)), [100.0])  # another operating point: its own lines
    assert np.allclose(np.diff(ref.known_lines(25.0)), 0.5 * ref.bin_width)
    assert SpectralSettings().known_lines(20.0).size == 0  # blind: nothing known


def learn_like(**changes):
    """A reference learnt at 20 Hz (told 19 Hz: ratio 20/19) with ``changes``."""
    ref = learn_reference(healthy(6.0, 5), FS, BEARING, 19.0 * 60, 0.10, SpectralSettings())
    base = replace(ref, told_hz=19.0, shaft_hz=20.0, speed_ratio=20.0 / 19.0, ratio_scatter=0.001,
                   speed_range_hz=(19.6, 20.4), bin_width=3.0)
    return replace(base, **changes)


def test_the_told_speed_is_corrected_by_the_learnt_ratio():
    ref = learn_like()
    assert ref.correct_speed(19.0, 0.10, 0.02) == pytest.approx((20.0, 0.02))  # at its speed: a measured one
    assert ref.correct_speed(15.0, 0.10, 0.02) == pytest.approx((15.0 * 20 / 19, 0.10))  # elsewhere: the tolerance
    assert replace(ref, speed_ratio=None).correct_speed(19.0, 0.10, 0.02) == (19.0, 0.10)


def test_save_and_load_give_the_same_reference(tmp_path):
    ref = learn_recording_reference(recording(healthy(6.0, 1)))
    ref.save(tmp_path / "ref.json")
    assert load_reference(tmp_path / "ref.json") == ref


@pytest.mark.parametrize("text, message", [
    ("not json {", "not JSON"),
    ('{"format": "something else"}', "no format"),
    ('{"format": "bearing_diagnoser machine reference", "version": 99}', "version 99"),
    ('{"format": "bearing_diagnoser machine reference", "version": 1, "source": "x"}', "corrupt"),
])
def test_a_foreign_or_corrupt_file_is_one_clear_error(tmp_path, text, message):
    path = tmp_path / "ref.json"
    path.write_text(text)
    with pytest.raises(MachineReferenceError, match=message) as err:
        load_reference(path)
    assert "\n" not in str(err.value)
    with pytest.raises(MachineReferenceError, match="cannot read"):
        load_reference(tmp_path / "missing.json")


@pytest.mark.parametrize("x, rpm, message", [
    (np.zeros(int(10 * FS)), RPM, "sensor problem"),
    (white_noise(0.5, FS, 0.01), RPM, "too short"),
    (white_noise(5.0, FS, 0.01), None, "no shaft speed"),
])
def test_a_period_that_cannot_give_a_reference_says_why(x, rpm, message):
    with pytest.raises(MachineReferenceError, match=message):
        learn_reference(x, FS, BEARING, rpm, 0.02, SpectralSettings())


def run_cli(argv, capsys):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, [json.loads(x) for x in out.splitlines() if x.strip()], err


def test_cli_baseline_halves_of_a_healthy_record_and_a_fault_judged_against_it(cwru_record, tmp_path, capsys):
    from bearing_recordings.mat_files import load_mat

    rec = load_mat(cwru_record("097_normal_0hp_DE48k.mat"), 48000.0)
    half = rec.accel.size // 2
    for name, part in (("first", rec.accel[:half]), ("second", rec.accel[half:])):
        np.savez(tmp_path / f"{name}.npz", accel=part, sample_rate=48000.0, rpm=rec.rpm)
    ref = tmp_path / "ref.json"
    code, lines, err = run_cli([tmp_path / "second.npz", "--bearing", "6205", "--baseline", tmp_path / "first.npz",
                                "--save-baseline", ref, "--json"], capsys)
    assert code == 0 and [x["state"] for x in lines] == ["normal"]
    assert all(str(tmp_path / "first.npz") in x["reference"] for x in lines) and "machine reference:" in err
    assert load_reference(ref).bearing == "6205"
    code, lines, _ = run_cli([cwru_record("130_OR007at6_0hp_DE12k.mat"), "--sample-rate", "12000", "--baseline", ref,
                              "--json"], capsys)
    assert code == 0 and [x["state"] for x in lines] == ["outer_race"] and "reference" in lines[0]
    code, lines, err = run_cli([tmp_path / "second.npz", "--bearing", "6205", "--json"], capsys)
    assert code == 0 and "reference" not in lines[0]  # blind without one
    code, _, err = run_cli([tmp_path / "second.npz", "--save-baseline", ref], capsys)
    assert code == 2 and "--save-baseline needs --baseline" in err


def session(**values):
    logged = []
    v = {p.name: p.default for p in PARAMETERS} | {"rpm": RPM, "rpm_tolerance": 0.02, "baseline": "10s"} | values
    return DiagnoserSession(v, lambda level, text: logged.append((level, text))), logged


def feed(s, x, chunk=1200):
    for i in range(0, x.size, chunk):
        for h in (FaultState.OUTER_RACE, FaultState.INNER_RACE):
            s.on_residual(h, i / FS, i, FS, x[i:i + chunk], None, None, 100.0, "none", 0.0)


def test_the_node_learns_over_its_baseline_period_saves_it_and_a_restart_loads_it(tmp_path):
    path = tmp_path / "ref.json"
    s, logged = session(reference_file=str(path))
    feed(s, healthy(4.0, 1))
    assert s.health(0.0).values["machine reference"].startswith("learning: 4.0 of 10.0 s")
    feed(s, healthy(16.0, 1)[int(4 * FS):])
    status = s.health(0.0).values["machine reference"]
    assert path.exists() and str(path) in status and "learnt by the node over its first 10.0 s" in status
    assert s.core.config.front_end.reference == load_reference(path)
    assert s.last_report.state == FaultState.NORMAL
    again, _ = session(reference_file=str(path))
    assert again.reference.reference == load_reference(path) and not again.reference.learning
    path.write_text("{")
    broken, _ = session(reference_file=str(path))
    assert broken.health(0.0).values["machine reference"].startswith("none, deciding blind") \
        and path.read_text() == "{"  # never overwritten


def test_a_known_line_that_has_grown_well_above_its_learnt_level_counts_again():
    reference = learn_recording_reference(recording(healthy(10.0, 1, depth=0.2)))
    assert states(diagnose_recording(recording(healthy(10.0, 2, depth=0.2)), baseline=reference)) == [FaultState.NORMAL]
    grown = diagnose_recording(recording(healthy(10.0, 2, depth=0.6)), baseline=reference)  # 9 x its power
    assert FaultState.OUTER_RACE in states(grown)
