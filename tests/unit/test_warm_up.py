"""The nodes' warm-up compiles every kernel signature the chunk path uses.

A node warms its kernels up before it subscribes: a compile on the first chunks (about a
second per kernel after an install, when numba's cache is empty) blocks the callbacks
while the reliable queues (0.5 s) overflow, and the start of the signal is lost. That
happened once: a new kernel received a strided slice where its warm-up passed a
contiguous array, and a fresh clone's first live run dated a fault 0.4 s late. Run in a
fresh interpreter, since this process has compiled whatever other tests needed.
"""

import subprocess
import sys

CHECK = """
import sys
import numpy as np
from numba.core.registry import CPUDispatcher
from bearing_common.bearings import CATALOG
from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser import Diagnoser
from bearing_diagnoser.warm_up import warm_up as warm_up_decision
from bearing_diagnoser.front_ends import config_for
from bearing_diagnoser.synthetic import burst_train, white_noise
from bearing_observer.observer import FaultObserver, warm_up

def signatures():
    seen = {}
    for module in list(sys.modules.values()):
        if getattr(module, "__name__", "").startswith(("bearing_observer", "bearing_diagnoser")):
            for name, obj in vars(module).items():
                if isinstance(obj, CPUDispatcher):
                    seen[obj.__qualname__] = set(obj.signatures)
    return seen

warm_up()  # what the observer node runs before subscribing
warm_up_decision()  # and the diagnoser's session
before = signatures()
bearing = CATALOG["6205"]
for model_set, fs in (("sim_48k", 48000.0), ("sim_12k", 12000.0), ("none", 48000.0)):
    y = white_noise(1.5, fs, 4.5e-3) + burst_train(1.5, fs, bearing.bpfo(30.0), amplitude=30.0, start=0.5)
    core = Diagnoser(config_for(model_set), model_set, bearing, fs)
    core.tell_speed(1800.0)
    observers = {h: FaultObserver.from_model_set(model_set, h.label, 1800.0, fs)
                 for h in (FaultState.OUTER_RACE, FaultState.INNER_RACE)}
    n = int(round(0.01 * fs))
    for i in range(0, y.size - n + 1, n):
        for h, obs in observers.items():
            out = obs.process(y[i:i + n])
            core.update(h, i, fs, out.residual, None if model_set == "none" else out.estimate,
                        out.impulse_train, obs.fault_frequency)
late = {k: v - before.get(k, set()) for k, v in signatures().items() if v - before.get(k, set())}
print(late)
sys.exit(1 if late else 0)
"""


def test_no_kernel_compiles_after_the_warm_up():
    run = subprocess.run([sys.executable, "-c", CHECK], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, f"compiled on the chunk path, after the warm-up: {run.stdout}\n{run.stderr[-3000:]}"
