"""Measured shaft speed in the offline inputs: a .npz's ``shaft_speed``, a .mat speed or tachometer
channel (``--speed-channel``), bags that carry ``shaft_speed`` or ``shaft_pulses`` (bearing_recordings)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.io import savemat

from bearing_common import topics
from bearing_common.shaft_angle import RPM_TO_RAD_S, SpeedProfile, pulse_times
from bearing_diagnoser.diagnose_cli import main as diagnose
from bearing_recordings.bag_read import load_bag
from bearing_recordings.bag_write import BagWriter, recording_to_bag, time_msg
from bearing_recordings.load import load_recording
from bearing_recordings.recording import SPEED_VARIATION, InputError, Recording
from bearing_recordings.speed_channel import pulse_edges, speed_from_channel

FS = 12000.0
RAMP = SpeedProfile.parse("0:1500,4:1800")


def _ramp_signal(seconds=4.0):
    t = np.arange(int(seconds * FS)) / FS
    rng = np.random.default_rng(0)
    return t, np.cos(3 * RAMP.angle(t)) + 0.1 * rng.standard_normal(t.size)


def test_npz_shaft_speed_is_a_tachometer(tmp_path):
    t, x = _ramp_signal()
    path = tmp_path / "ramp.npz"
    np.savez(path, accel=x, sample_rate=FS, rpm=1234.0, shaft_speed=RAMP.omega(t))
    rec = load_recording(path)
    np.testing.assert_array_equal(rec.shaft_speed, RAMP.omega(t))
    assert rec.rpm == pytest.approx(1650.0, rel=1e-4)  # the mean, not the file's number
    assert rec.speed_varies and rec.speed_spread == pytest.approx(300 / 1650, rel=1e-3)
    told = load_recording(path, rpm=1700.0)  # a speed given overrides the series, and says so
    assert told.shaft_speed is None and told.rpm == 1700.0 and "not used" in told.notes[0]


def test_a_constant_series_keeps_its_exact_speed_and_does_not_vary(tmp_path):
    path = tmp_path / "const.npz"
    np.savez(path, accel=np.ones(1000), sample_rate=FS, shaft_speed=np.full(1000, 1797 * RPM_TO_RAD_S))
    rec = load_recording(path)
    assert rec.rpm == 1797 * RPM_TO_RAD_S / RPM_TO_RAD_S and not rec.speed_varies


@pytest.mark.parametrize("speed, match", [(np.ones(10), "10 values for 1000 samples"),
                                          (np.r_[np.ones(999), -1.0], "positive finite"),
                                          (np.r_[np.ones(999), np.nan], "positive finite")])
def test_a_bad_shaft_speed_is_refused(tmp_path, speed, match):
    path = tmp_path / "bad.npz"
    np.savez(path, accel=np.ones(1000), sample_rate=FS, shaft_speed=speed)
    with pytest.raises(InputError, match=match):
        load_recording(path)


def test_speed_variation_threshold():
    rec = Recording(np.ones(3), FS, None, "mat")
    rec.set_shaft_speed(np.array([100.0, 100.0 * (1 + SPEED_VARIATION / 2), 100.0]), "x")
    assert not rec.speed_varies
    rec.set_shaft_speed(np.array([100.0, 100.0 * (1 + 2 * SPEED_VARIATION), 100.0]), "x")
    assert rec.speed_varies


@pytest.mark.parametrize("units, scale", [("rpm", 1 / RPM_TO_RAD_S), ("rad/s", 1.0), ("hz", 1 / (2 * np.pi))])
def test_speed_channels_in_each_unit(units, scale):
    w = np.linspace(150.0, 190.0, 50)
    np.testing.assert_allclose(speed_from_channel(w * scale, FS, units), w, rtol=1e-14)


def _tacho_signal(t, pulses_per_rev=1, width=2e-3, noise=0.05, rise=0.2e-3):
    """A 5 V key phasor: rising linearly over ``rise`` s from each of its pulses (exact times), high
    until ``width`` s after it, with noise; ``edges``: the times it passes 2.5 V."""
    starts = pulse_times(RAMP, 0.0, t[-1] + 1.0, pulses_per_rev)
    since = t - starts[np.maximum(np.searchsorted(starts, t, side="right") - 1, 0)]
    level = np.where((since >= 0) & (since < width), 5.0 * np.clip(since / rise, 0.0, 1.0), 0.0)
    return level + noise * np.random.default_rng(3).standard_normal(t.size), starts + 0.5 * rise


def test_pulse_edges_are_found_to_a_fraction_of_a_sample():
    """Edges through mid level, interpolated: exact on a linear rise (noise-free); an instantaneous step
    only tells the sample interval it lies in."""
    t = np.arange(int(2 * FS)) / FS
    sig, edges = _tacho_signal(t, noise=0.0)
    found = pulse_edges(sig, FS)
    expected = edges[edges < t[-1] - 1e-3]
    assert found.size == expected.size
    np.testing.assert_allclose(found, expected, rtol=0, atol=1e-9)
    step, edges = _tacho_signal(t, noise=0.0, rise=1e-9)
    found = pulse_edges(step, FS)
    assert np.max(np.abs(found - edges[edges < t[-1] - 1e-3])) <= 1.0 / FS


@pytest.mark.parametrize("ppr", [1, 4])
def test_a_pulse_channel_gives_the_speed_per_sample(ppr):
    t = np.arange(int(4 * FS)) / FS
    sig, _ = _tacho_signal(t, ppr, width=0.5e-3)
    speed = speed_from_channel(sig, FS, "pulses", ppr)
    inner = (t > 0.3) & (t < 3.7)
    # noise on the edges (0.05 V on a 5 V rise over 0.2 ms: about 3 us), averaged by the fit
    np.testing.assert_allclose(speed[inner], RAMP.omega(t[inner]), rtol=2e-3)


def test_a_pulse_channel_without_pulses_is_refused():
    with pytest.raises(InputError, match="tachometer pulses"):
        speed_from_channel(np.zeros(1000), FS, "pulses")
    with pytest.raises(InputError, match="unknown speed units"):
        speed_from_channel(np.zeros(10), FS, "furlongs")


def _mat_with_speed(tmp_path):
    t, x = _ramp_signal()
    path = tmp_path / "rig.mat"
    tacho, _ = _tacho_signal(t)
    savemat(path, {"vib": x / 9.80665, "rpm_trace": RAMP.rpm(t), "tach": tacho})
    return path, t


def test_a_mat_speed_channel_via_load_recording(tmp_path):
    path, t = _mat_with_speed(tmp_path)
    rec = load_recording(path, sample_rate=FS, channel="vib", units="g", speed_channel="rpm_trace",
                         speed_units="rpm")
    np.testing.assert_allclose(rec.shaft_speed, RAMP.omega(t), rtol=1e-12)
    assert rec.rpm == pytest.approx(1650.0, rel=1e-4) and rec.speed_varies
    rec = load_recording(path, sample_rate=FS, channel="vib", speed_channel="tach", speed_units="pulses")
    inner = (t > 0.3) & (t < 3.7)
    np.testing.assert_allclose(rec.shaft_speed[inner], RAMP.omega(t[inner]), rtol=2e-3)
    with pytest.raises(InputError, match="no channel 'nope'; available: .*rpm_trace"):
        load_recording(path, sample_rate=FS, channel="vib", speed_channel="nope", speed_units="rpm")
    with pytest.raises(InputError, match="not both"):
        load_recording(path, sample_rate=FS, rpm=1500.0, channel="vib", speed_channel="tach", speed_units="pulses")
    with pytest.raises(InputError, match="units"):
        load_recording(path, sample_rate=FS, channel="vib", speed_channel="tach")


def test_bearing_diagnose_reads_a_speed_channel_and_says_it_follows_the_changing_speed(tmp_path, capsys):
    path, _ = _mat_with_speed(tmp_path)
    rc = diagnose([str(path), "--sample-rate", "12000", "--channel", "vib", "--speed-channel", "rpm_trace",
                   "--speed-units", "rpm", "--method", "envelope"])
    err = capsys.readouterr().err
    assert rc == 0, err
    assert "speed varies from 1500 to 1800 rpm" in err and "shaft-angle domain" in err and "1650 rpm nominal" in err
    rc = diagnose([str(path), "--sample-rate", "12000", "--channel", "vib", "--speed-channel", "rpm_trace"])
    assert rc == 2 and "go together" in capsys.readouterr().err


def test_a_bag_carries_a_changing_shaft_speed_and_gives_it_back(tmp_path):
    t, x = _ramp_signal(2.0)
    rec = Recording(x, FS, None, "mat", channel="vib", path="ramp")
    rec.set_shaft_speed(RAMP.omega(t), "ramp")
    recording_to_bag(rec, tmp_path / "bag", chunk_duration=0.01)
    back = load_bag(tmp_path / "bag")
    # one ShaftSpeed per 10 ms chunk, linear in between: exact for a linear ramp (until the last stamp)
    inner = t < 1.99
    np.testing.assert_allclose(back.shaft_speed[inner], RAMP.omega(t[inner]), rtol=1e-12)
    assert back.speed_varies and back.rpm == pytest.approx(rec.rpm, rel=1e-4)


def test_a_constant_speed_bag_keeps_its_one_speed(tmp_path):
    rec = Recording(np.ones(2400), FS, 1797.0, "cwru", channel="vib", path="const")
    recording_to_bag(rec, tmp_path / "bag")
    back = load_bag(tmp_path / "bag")
    assert back.shaft_speed is None and back.rpm == pytest.approx(1797.0, rel=1e-15)


def test_a_bag_with_tachometer_pulses_gives_the_speed_from_them(tmp_path):
    """Tachometer messages (as the simulator node publishes them) take precedence over shaft_speed."""
    t = np.arange(int(2.0 * FS)) / FS
    edges = pulse_times(RAMP, 0.0, 2.0)
    with BagWriter(tmp_path / "bag") as bag:
        ts = bag.typestore
        header, chunk_t, tacho_t = (ts.types["std_msgs/msg/Header"], ts.types[topics.VIBRATION.msgtype],
                                    ts.types[topics.TACHOMETER.msgtype])
        vib, tach = bag.add_graph_topic(topics.VIBRATION), bag.add_graph_topic(topics.TACHOMETER)
        for i0 in range(0, t.size, 120):
            stamp = time_msg(ts, i0 / FS)
            log_ns = stamp.sec * 1_000_000_000 + stamp.nanosec
            msg = chunk_t(header=header(stamp=stamp, frame_id="drive_end"), sample_rate=FS, first_sample_index=i0,
                          source="simulator", samples=np.cos(3 * RAMP.angle(t[i0:i0 + 120])))
            bag.write(vib.topic, log_ns, bag.serialize(msg, topics.VIBRATION.msgtype))
            inside = edges[(edges >= i0 / FS) & (edges < (i0 + 120) / FS)]
            pulses = tacho_t(header=header(stamp=stamp, frame_id="shaft"), duration=0.01,
                             pulse_offsets=inside - i0 / FS, first_pulse_index=int(np.sum(edges < i0 / FS)),
                             pulses_per_revolution=1, timing_jitter=0.0, source="simulator")
            bag.write(tach.topic, log_ns, bag.serialize(pulses, topics.TACHOMETER.msgtype))
    rec = load_bag(tmp_path / "bag")
    inner = (t > 0.2) & (t < 1.8)
    np.testing.assert_allclose(rec.shaft_speed[inner], RAMP.omega(t[inner]), rtol=2e-4)
