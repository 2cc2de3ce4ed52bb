"""The fleet summary without ROS: motors from topic names, staleness, the text table."""

from __future__ import annotations

from bearing_fleet.fleet_table import FleetTable, motor_of

from bearing_common import topics
from bearing_common.states import FaultState


def test_motor_is_the_namespace_of_the_fault_state_topic():
    state = topics.FAULT_STATE
    assert motor_of(topics.qualified("motor_7", state)) == "motor_7"
    assert motor_of(topics.qualified("plant/line_2/motor_7", state)) == "plant/line_2/motor_7"
    assert motor_of(topics.qualified("", state)) == ""
    assert motor_of(topics.qualified("motor_7", topics.FLEET_STATE)) is None
    assert motor_of(topics.qualified("motor_7", state) + "_x") is None


def test_updates_changes_and_staleness():
    t = FleetTable(stale_timeout=5.0)
    t.add_motor("m2")
    assert t.update("m1", 0, 0.9, 0.0, 1.0, now=10.0)  # first decision: a change
    assert not t.update("m1", 0, 0.95, 0.0, 1.5, now=11.0)
    assert t.update("m1", 2, 0.8, 1.2, 2.0, now=12.0)  # NORMAL -> INNER_RACE
    assert [r.motor for r in t.rows()] == ["m1", "m2"]
    m1, m2 = t.rows()
    assert m1.state == FaultState.INNER_RACE and m1.age(13.0) == 1.0
    assert not t.is_stale(m1, 16.9) and t.is_stale(m1, 17.1)
    assert t.is_stale(m2, 0.0)  # never heard of: stale


def test_table_lists_the_worst_first():
    t = FleetTable(stale_timeout=5.0)
    t.update("a_normal", 0, 0.99, 0.0, 3.0, now=10.0)
    t.update("b_outer", 1, 0.8, 1.0, 3.0, now=10.0)
    t.update("c_old", 2, 0.8, 1.0, 3.0, now=1.0)
    text = t.render(now=10.0).splitlines()
    assert [line.split()[0] for line in text[1:4]] == ["b_outer", "c_old", "a_normal"]
    assert "STALE" in text[2] and "OUTER_RACE" in text[1]
    assert text[-1] == "3 motors, 1 not normal, 1 stale"
