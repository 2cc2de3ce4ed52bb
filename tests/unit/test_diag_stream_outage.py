"""The decision core when one observer's residuals stop for longer than ``max_lag_s`` and come back
(what a killed and restarted observer does in the live graph, tests/ros/test_graph_restart.py)."""

import numpy as np

from bearing_common.bearings import CATALOG, fault_frequency
from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser import Diagnoser
from bearing_diagnoser.front_ends import config_for
from bearing_diagnoser.synthetic import burst_train, white_noise

FS = 48000.0
OR, IR = FaultState.OUTER_RACE, FaultState.INNER_RACE
BPFO = fault_frequency(CATALOG["6205"], OR, 1800.0)
BPFI = fault_frequency(CATALOG["6205"], IR, 1800.0)
OUTAGE = (1.5, 3.5)  # s without outer-race residuals; max_lag_s is 1 s


def test_a_stream_back_after_an_outage_is_used_at_once():
    """No decision while the outer-race stream is away (the published state stands), and the
    resumed stream is used from its first chunk: every window after it is OUTER_RACE again."""
    y = burst_train(6.0, FS, BPFO, amplitude=10.0, rng=np.random.default_rng(3)) + \
        white_noise(6.0, FS, 4.5e-3, np.random.default_rng(1))
    dg = Diagnoser(config_for("sim_48k"))
    out = []
    for i in range(0, y.size, 480):
        if not OUTAGE[0] <= i / FS < OUTAGE[1]:
            out += dg.update(OR, i, FS, y[i:i + 480], None, None, BPFO)
        out += dg.update(IR, i, FS, y[i:i + 480], None, None, BPFI)
    assert all(d.state == OR for d in out)  # the state held through the outage
    assert not [d for d in out if OUTAGE[0] + 0.05 < d.window_end <= OUTAGE[1]]  # nothing decided without it
    resumed = [d for d in out if d.window_end >= OUTAGE[1] + 0.2]
    assert resumed and all(d.detail == "" for d in resumed)
    wrong = [(round(d.window_start, 2), d.state.name) for d in resumed if d.state != OR]
    assert not wrong, f"{len(wrong)} windows after the outage not OUTER_RACE, first {wrong[:3]}"
