"""The health record in a real bearing_msgs/msg/HealthIndicators, serialised; the catalog's femto bearing."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from bearing_common.bearings import load_bearing
from bearing_diagnoser.health.monitor import FaultEvidence, HealthMonitor
from bearing_diagnoser.health.trend import HealthState, TrendConfig


def test_femto_bearing_fault_frequencies():
    # PHM 2012 challenge, Appendix A.1: 13 balls of 3.5 mm, pitch 25.6 mm, contact angle 0
    b = load_bearing("femto")
    assert (b.n_elements, b.element_diameter, b.pitch_diameter, b.contact_angle) == (13, 3.5e-3, 25.6e-3, 0.0)
    o = b.orders()
    r = 3.5 / 25.6
    assert_allclose(o.bpfo, 6.5 * (1 - r), rtol=1e-12)  # 5.611
    assert_allclose(o.bpfi, 6.5 * (1 + r), rtol=1e-12)  # 7.389
    assert_allclose(o.ftf, 0.5 * (1 - r), rtol=1e-12)  # 0.4316
    assert_allclose(o.bsf, 25.6 / 7.0 * (1 - r ** 2), rtol=1e-12)  # 3.589
    assert_allclose([o.bpfo, o.bpfi, o.ftf, o.bsf], [5.611, 7.389, 0.4316, 3.589], atol=6e-4)
    assert load_bearing("pronostia") == b


def test_monitor_record_fills_the_message():
    msgs = pytest.importorskip("bearing_msgs.msg", reason="bearing_msgs not built (make setup)")
    from rclpy.serialization import deserialize_message, serialize_message

    from bearing_diagnoser.health.message import fill_health_message

    monitor = HealthMonitor(TrendConfig(baseline_snapshots=6), "group1-rigid")
    rng = np.random.default_rng(0)
    fs = 25600.0
    for k in range(8):
        evidence = FaultEvidence({"outer_race": 6.5, "inner_race": 0.2}, {"outer_race": 9.0},
                                 {"ball": "sidebands 1.3 bins from their carriers, 4 needed"})
        rec = monitor.update(1000.0 + 60.0 * k, rng.standard_normal(2560) * (1 + 3 * (k >= 6)), fs,
                             evidence=evidence)
    msg = fill_health_message(msgs.HealthIndicators(), rec, monitor, frame_id="drive_end")
    back = deserialize_message(serialize_message(msg), msgs.HealthIndicators)
    assert back.header.stamp.sec == 1000 + 60 * 7 and back.header.frame_id == "drive_end"
    assert_allclose(back.rms, rec.indicators.rms)
    assert_allclose(back.velocity_rms, rec.indicators.velocity_rms)
    assert back.velocity_band_low == pytest.approx(20.0) and back.sample_rate == fs
    assert back.iso_class == "group1-rigid" and back.iso_zone == " ABCD".index(rec.iso_zone)
    assert back.state == int(rec.trend.state) != msgs.HealthIndicators.HEALTHY
    assert back.state_since.sec == 1000 + int(rec.trend.since)
    assert list(back.trended) == list(monitor.tracker.names) and not back.learning
    assert list(back.hypotheses) == ["outer_race", "inner_race"] and list(back.untested) == ["ball"]
    assert_allclose(back.evidence, [6.5, 0.2])
    assert back.evidence_accumulated[0] == 9.0 and math.isnan(back.evidence_accumulated[1])
    assert list(back.untested_why) == ["sidebands 1.3 bins from their carriers, 4 needed"]
    assert back.evidence_problem == ""
    problem = fill_health_message(msgs.HealthIndicators(), monitor.update(
        1480.0, rng.standard_normal(2560), fs, evidence=FaultEvidence(problem="shaft speed unknown")), monitor)
    assert problem.evidence_problem == "shaft speed unknown" and not list(problem.hypotheses)
    assert not back.speed_changing
    held = fill_health_message(msgs.HealthIndicators(), monitor.update(
        1540.0, rng.standard_normal(2560), fs, speed_changing=True), monitor)
    assert held.speed_changing and held.state == back.state  # scored, held out of the trend
    assert math.isfinite(back.score) and back.moved in monitor.tracker.names


def test_message_constants_match_the_code():
    msgs = pytest.importorskip("bearing_msgs.msg", reason="bearing_msgs not built (make setup)")
    from bearing_diagnoser.health.message import ZONE_CODES
    m = msgs.HealthIndicators
    assert {s.name: int(s) for s in HealthState} == {"HEALTHY": m.HEALTHY, "WARNING": m.WARNING, "ALARM": m.ALARM}
    assert ZONE_CODES == {"": m.ZONE_UNKNOWN, "A": m.ZONE_A, "B": m.ZONE_B, "C": m.ZONE_C, "D": m.ZONE_D}


def test_flat_sensor_is_not_scored():
    monitor = HealthMonitor()
    assert monitor.update(0.0, np.zeros(2560), 25600.0) is None
    assert monitor.summary()["sensor_problems"] == 1 and "flat" in monitor.sensor_problems[0][1]
