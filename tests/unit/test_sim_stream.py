"""The simulator node's chunk stream: one time axis across repeats and live speed / noise changes."""

import numpy as np
import pytest

from bearing_common.states import FaultState as F
from bearing_sim.sim_node_config import SimulationRun
from bearing_sim.sim_stream import SimulationStream, remaining_schedule
from bearing_sim.simulator import DEFAULT_NOISE_DENSITY, SimulationConfig, Simulator

FS = 48000.0
N = 480  # 0.01 s chunks


def stream(schedule, repeat=False, **config):
    return SimulationStream(SimulationRun(SimulationConfig(**config), schedule, N), repeat)


def drain(s, limit=1000):
    chunks = []
    while len(chunks) < limit and (c := s.next_chunk()) is not None:
        chunks.append(c)
    return chunks


def test_remaining_schedule():
    sched = [(F.OUTER_RACE, 0.2), (F.INNER_RACE, 0.2)]
    assert remaining_schedule(sched, 0.0, FS) == sched
    rest = remaining_schedule(sched, 0.05, FS)
    assert [s for s, _ in rest] == [F.OUTER_RACE, F.INNER_RACE]
    assert [d for _, d in rest] == pytest.approx([0.15, 0.2])
    assert remaining_schedule(sched, 0.2, FS) == [(F.INNER_RACE, pytest.approx(0.2))]
    assert remaining_schedule(sched, 0.4 - 0.1 / FS, FS) == []  # less than half a sample left


def test_without_changes_the_stream_is_the_simulator_output_and_ends():
    sched = [(F.OUTER_RACE, 0.02), (F.NORMAL, 0.015)]
    s = stream(sched)
    chunks = drain(s)
    assert [c.start_index for c in chunks] == [0, 480, 960, 1440]
    assert [len(c) for c in chunks] == [480, 480, 480, 240]
    assert all(c.t0 == c.start_index / FS for c in chunks)
    sim = Simulator(SimulationConfig(), sched)
    np.testing.assert_array_equal(np.concatenate([c.accel for c in chunks]), sim.advance(10**6).accel)
    assert s.next_chunk() is None


def test_repeat_continues_indices_and_truth_changes_carry_onsets():
    s = stream([(F.OUTER_RACE, 0.01), (F.INNER_RACE, 0.01)], repeat=True)
    changes = []
    chunks = []
    for _ in range(5):
        chunks.append(s.next_chunk())
        changes += s.truth_changes(chunks[-1])
    assert [c.start_index for c in chunks] == [0, 480, 960, 1440, 1920]
    np.testing.assert_array_equal(chunks[2].accel, chunks[0].accel)  # the schedule again, from its start
    assert changes == [(F.OUTER_RACE, 0.0), (F.INNER_RACE, 0.01), (F.OUTER_RACE, 0.02), (F.INNER_RACE, 0.03),
                       (F.OUTER_RACE, 0.04)]


def test_speed_change_restarts_at_the_next_chunk_with_the_rest_of_the_schedule():
    sched = [(F.OUTER_RACE, 0.03), (F.INNER_RACE, 0.02)]
    s = stream(sched)
    first = s.next_chunk()
    s.set_rpm(1500.0)
    assert s.rpm == 1800.0  # the last chunk's speed until the next one
    rest = drain(s)
    assert s.rpm == 1500.0
    assert [c.start_index for c in [first] + rest] == [0, 480, 960, 1440, 1920]  # same axis, same length
    truth = np.concatenate([c.truth for c in [first] + rest])
    np.testing.assert_array_equal(truth, [F.OUTER_RACE] * 1440 + [F.INNER_RACE] * 960)
    fresh = Simulator(SimulationConfig(rpm=1500.0), [(F.OUTER_RACE, 0.02), (F.INNER_RACE, 0.02)])
    want = fresh.advance(10**6).accel  # equal up to the integrator's tolerance (boundary 0.03 - 0.01 s in floats)
    np.testing.assert_allclose(np.concatenate([c.accel for c in rest]), want, rtol=0, atol=1e-4 * np.abs(want).max())


def test_speed_change_at_the_end_applies_to_the_next_repeat():
    s = stream([(F.NORMAL, 0.01)], repeat=True)
    s.next_chunk()
    s.set_rpm(1200.0)
    c = s.next_chunk()
    assert c.start_index == 480 and s.rpm == 1200.0
    np.testing.assert_array_equal(c.accel, Simulator(SimulationConfig(rpm=1200.0), [(F.NORMAL, 0.01)]).advance(N).accel)


def test_noise_change_applies_from_the_next_chunk():
    s = stream([(F.NORMAL, 0.1)])
    quiet = s.next_chunk().accel
    s.set_noise_density(DEFAULT_NOISE_DENSITY)
    noisy = s.next_chunk().accel
    assert np.std(np.diff(noisy)) > 100 * np.std(np.diff(quiet))
    assert s.config.noise_density == DEFAULT_NOISE_DENSITY and s.rpm == 1800.0
    with pytest.raises(ValueError, match="noise_density"):
        s.set_noise_density(-1.0)


def _run(schedule, **kw):
    from bearing_sim.sim_node_config import SimulationRun
    run_kw = {k: kw.pop(k) for k in ("speed_rate", "tacho_pulses", "tacho_jitter") if k in kw}
    return SimulationStream(SimulationRun(SimulationConfig(**kw), schedule, N, **run_kw), False)


def test_shaft_speed_goes_out_at_the_stated_rate_with_the_speed_at_its_stamp():
    from bearing_common.shaft_angle import SpeedProfile
    profile = SpeedProfile.parse("0:1500,0.05:1800")
    s = _run([(F.NORMAL, 0.05)], speed_rate=250.0, sample_rate=12000.0, speed_profile=profile)
    s.chunk_samples = 90  # 7.5 ms chunks: the stamps (4 ms apart) do not line up with them
    samples = [x for c in drain(s) for x in s.speed_samples(c)]
    stamps = np.array([t for t, _ in samples])
    np.testing.assert_allclose(stamps, np.arange(13) * 0.004, atol=1e-12)  # 0 .. 0.048 s, each once
    np.testing.assert_allclose([w for _, w in samples], profile.omega(stamps), rtol=1e-12)


def test_default_speed_rate_is_one_message_per_default_chunk_at_its_stamp():
    s = _run([(F.NORMAL, 0.02)])
    c = s.next_chunk()
    assert s.speed_samples(c) == [(0.0, pytest.approx(1800 * np.pi / 30))]


def test_tachometer_pulses_mark_whole_turns_with_the_stated_jitter_whatever_the_chunking():
    from bearing_common.shaft_angle import SpeedProfile
    profile = SpeedProfile.parse("0:1200,0.5:1800")
    pulses = {}
    for chunk_samples in (480, 331):
        s = _run([(F.NORMAL, 0.5)], tacho_pulses=2, tacho_jitter=20e-6, sample_rate=12000.0,
                 speed_profile=profile, seed=7)
        s.chunk_samples = chunk_samples
        times, count = [], 0
        for c in drain(s):
            t, first = s.tacho_pulses(c)
            assert first == count and np.all((t >= c.t0) & (t < c.t0 + len(c) / 12000.0))
            count += t.size
            times.append(t)
        pulses[chunk_samples] = np.concatenate(times)
    np.testing.assert_array_equal(pulses[480], pulses[331])  # each pulse's error is its own
    t = pulses[480]
    turns = profile.angle(t) / np.pi  # 2 pulses per revolution
    assert t.size == int(np.ceil(profile.angle(0.5) / np.pi))
    np.testing.assert_array_equal(np.rint(turns), np.arange(t.size))
    timing_error = (turns - np.rint(turns)) * np.pi / profile.omega(t)
    assert np.std(timing_error) == pytest.approx(20e-6, rel=0.25) and np.max(np.abs(timing_error)) <= 5 * 20e-6
