"""The live graph on a simulated run-up (issue 27): 900 -> 1800 rev/min over 10 s with an outer-race fault.

Simulator, two model-free observers and the diagnoser as separate processes on
``config/run_up.yaml``. The diagnoser follows ``shaft_speed`` in the shaft-angle domain once the
speed leaves its start by 2 %; it must publish OUTER_RACE before the ramp ends and never another part.
/diagnostics says that the condition indicators are held out of the trend while the speed changes.
"""

import pytest
from graph_helpers import wait_quiet, wait_spec

from bearing_bringup.graph import GRAPH, config_path
from bearing_common import topics
from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser_session import SPEED_CHANGING_HELD

pytestmark = pytest.mark.ros

RAMP_S = 10.0  # s of signal: the profile "0:900,10:1800"
WRONG_PARTS = {FaultState.INNER_RACE, FaultState.BALL}


def seconds(stamp):
    return stamp.sec + stamp.nanosec * 1e-9


def test_run_up_is_outer_race_before_the_ramp_ends(ros_graph):
    params = config_path("run_up.yaml")
    states = ros_graph.subscribe(topics.FAULT_STATE)
    vib = ros_graph.subscribe(topics.VIBRATION)
    diagnostics = ros_graph.subscribe(topics.DIAGNOSTICS)
    members = {spec.name: ros_graph.start(spec.package, spec.executable, name=spec.name, params_file=params)
               for spec in GRAPH if spec.executable != "simulator"}
    ros_graph.wait_until(lambda: ros_graph.node.count_publishers(topics.FAULT_STATE.name) >= 1, 60.0,
                         "the diagnoser's fault_state publisher")
    wait = wait_spec({topics.VIBRATION: 3, topics.RESIDUAL_OUTER_RACE: 1, topics.RESIDUAL_INNER_RACE: 1,
                      topics.FAULT_STATE: 1})
    sim = ros_graph.start("bearing_sim", "simulator", name="simulator", params_file=params,
                          params={"wait_for_subscribers": wait})
    ros_graph.wait_until(lambda: sim.returncode is not None, timeout=60.0, what="the run-up to end")
    assert sim.returncode == 0, ros_graph.output()
    start = min(seconds(m.header.stamp) for m in vib)
    end = max(seconds(m.header.stamp) + len(m.samples) / m.sample_rate for m in vib)
    assert end - start == pytest.approx(RAMP_S, abs=0.011)
    wait_quiet(ros_graph, states, "the diagnoser to decide the last windows")
    for name, member in members.items():
        assert member.returncode in (None, 0), f"{name} died\n{ros_graph.output()}"
    published = [(FaultState(m.state), seconds(m.header.stamp) - start) for m in list(states)]
    outer = [t for s, t in published if s == FaultState.OUTER_RACE]
    print(f"first OUTER_RACE at {outer[0] if outer else None} s of the run-up; {len(published)} states "
          f"{sorted({s.name for s, _ in published})}, the last at {published[-1][1]:.3f} s")
    assert outer and outer[0] < RAMP_S, (published, ros_graph.output())
    assert not {s for s, _ in published} & WRONG_PARTS, (published, ros_graph.output())
    # the speed left its start: the decision went on in the shaft-angle domain
    assert any("restarts in the shaft-angle domain" in line for line in members["diagnoser"].lines), \
        ros_graph.output()
    messages = [status.message for array in list(diagnostics) for status in array.status]
    assert any(m.endswith(SPEED_CHANGING_HELD) for m in messages), messages
