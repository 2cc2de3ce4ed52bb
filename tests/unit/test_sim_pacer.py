"""The simulator node's start gate and wall-clock pacing, without ROS or a clock."""

import pytest

from bearing_common import topics
from bearing_sim.pacer import Pacer, SubscriberGate

VIB, RES = topics.VIBRATION.name, topics.RESIDUAL_OUTER_RACE.name
COUNTS = {VIB: 1, RES: 1}


def test_gate_waits_for_every_topic_then_opens():
    gate = SubscriberGate([(VIB, 2), (RES, 1)], timeout=30.0, now=100.0)
    count = lambda topic: COUNTS.get(topic, 0)
    assert gate.missing(count) == [(VIB, 2, 1)]
    assert not gate.is_open(count, now=110.0)
    COUNTS[VIB] = 2
    try:
        assert gate.is_open(count, now=110.0) and gate.missing(count) == []
    finally:
        COUNTS[VIB] = 1


def test_gate_opens_at_the_timeout_and_an_empty_gate_at_once():
    gate = SubscriberGate([(VIB, 5)], timeout=30.0, now=100.0)
    assert not gate.is_open(lambda _: 0, now=129.9)
    assert gate.is_open(lambda _: 0, now=130.0)
    assert SubscriberGate([], timeout=30.0, now=0.0).is_open(lambda _: 0, now=0.0)


def test_pacer_keeps_simulated_time_with_wall_time():
    pacer = Pacer(realtime=True)
    pacer.start(now=10.0)
    pacer.chunk_done(0.01, busy=0.002)
    assert pacer.ahead(now=10.003) == pytest.approx(0.007)  # wait 7 ms before the next chunk
    assert pacer.ahead(now=10.5) == pytest.approx(-0.49)  # behind
    for _ in range(99):
        pacer.chunk_done(0.01, busy=0.002)
    assert pacer.simulated == pytest.approx(1.0) and pacer.realtime_factor == pytest.approx(5.0)


def test_pacer_not_realtime_never_waits_and_switching_on_restarts_the_pacing():
    pacer = Pacer(realtime=False)
    pacer.start(now=0.0)
    for _ in range(100):
        pacer.chunk_done(0.01, busy=0.001)  # 1 s of signal in 0.1 s of wall time
    assert pacer.ahead(now=0.1) == 0.0
    pacer.set_realtime(True, now=0.1)
    assert pacer.ahead(now=0.1) == 0.0  # no 0.9 s wait for the burst before the switch
    pacer.chunk_done(0.01, busy=0.001)
    assert pacer.ahead(now=0.1) == pytest.approx(0.01)
    pacer.set_realtime(False, now=0.2)
    assert pacer.ahead(now=0.2) == 0.0


def test_pacer_reports_once_per_period():
    pacer = Pacer(realtime=True, report_period=5.0)
    pacer.start(now=0.0)
    pacer.chunk_done(2.0, busy=0.5)
    assert pacer.report(now=4.9) is None
    assert pacer.report(now=5.0) == "simulated 2.00 s; compute real-time factor 4.00"
    assert pacer.report(now=6.0) is None
