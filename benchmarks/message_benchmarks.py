"""`make bench` rows of what the residuals put on the wire (Residual.msg), before and after
float32 arrays and absent estimate / train (model set none).

* bytes per second of signal of one residual stream at 12 and 48 kHz, 0.01 and 0.1 s chunks:
  the CDR size of a message (encapsulation and header included) times the messages per
  second, for the former definition (three float64 arrays), today's with a model set (three
  float32 arrays) and without one (the residual alone);
* CPU per message, publisher and subscriber processes together, for messages of those sizes
  at 0.1 s chunks and 48 kHz, 10 messages a second over DDS on this host (the bytes carried
  by a ``VibrationChunk`` of as many bytes of samples: the per-message cost depends on the
  size, not the type), each as a ratio to the smallest in the same run.
"""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

import numpy as np

PUBSUB = pathlib.Path(__file__).resolve().parent / "message_pubsub.py"
RATES = (12000.0, 48000.0)
CHUNKS = (0.01, 0.1)

#: Residual.msg before its arrays became float32 and optional.
RESIDUAL_FLOAT64 = """std_msgs/Header header
float64 sample_rate
uint64 first_sample_index
uint8 fault_hypothesis
string model_set
float64 fault_frequency
float64[] residual
float64[] estimate
float64[] impulse_train
"""
LAYOUTS = ("before: 3 float64 arrays", "model set: 3 float32 arrays", "none: residual alone, float32")


def residual_bytes(layout: str, n: int) -> int:
    """CDR bytes of one residual message of ``n`` samples in ``layout``."""
    from rosbags.typesys import get_types_from_msg

    from bearing_recordings.bag_types import project_typestore
    store = project_typestore()
    name = "bearing_msgs/msg/Residual"
    if layout == LAYOUTS[0]:
        store.types.pop(name, None)
        store.fielddefs.pop(name, None)
        store.register(get_types_from_msg(RESIDUAL_FLOAT64, name))
    T = store.types
    dtype = np.float64 if layout == LAYOUTS[0] else np.float32
    full = layout != LAYOUTS[2]
    msg = T[name](header=T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=1, nanosec=0),
                                                  frame_id="drive_end"),
                  sample_rate=48000.0, first_sample_index=0, fault_hypothesis=1, model_set="sim_48k",
                  fault_frequency=107.5, residual=np.zeros(n, dtype),
                  estimate=np.zeros(n if full else 0, dtype), impulse_train=np.zeros(n if full else 0, dtype))
    return len(store.serialize_cdr(msg, name))


def bench_residual_bytes() -> list:
    """Bytes per second of signal of one residual stream, per layout, rate and chunk."""
    rows = []
    for rate in RATES:
        for chunk in CHUNKS:
            n = int(round(rate * chunk))
            per_s = {layout: residual_bytes(layout, n) / chunk for layout in LAYOUTS}
            before = per_s[LAYOUTS[0]]
            rows.append((f"residual stream at {rate / 1000:g} kHz, {chunk:g} s chunks: bytes per second of signal, "
                         + " / ".join(LAYOUTS) + " (each / before)",
                         " / ".join(f"{v / 1e3:.0f} kB ({v / before:.2f})" for v in per_s.values()), ""))
    return rows


def cpu_per_message(payload_bytes: int, hz: float = 10.0, seconds: float = 8.0) -> float:
    """CPU seconds per message of a publisher and a subscriber process (µs)."""
    n = max(1, payload_bytes // 8)
    env = dict(os.environ, ROS_DOMAIN_ID=str(200 + os.getpid() % 30 + 1), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    sub = subprocess.Popen([sys.executable, str(PUBSUB), "sub", str(n), str(hz), str(seconds)], env=env,
                           stdout=subprocess.PIPE, text=True)
    pub = subprocess.run([sys.executable, str(PUBSUB), "pub", str(n), str(hz), str(seconds)], env=env,
                         capture_output=True, text=True, timeout=120)
    out, _ = sub.communicate(timeout=60)
    return float(pub.stdout.split()[-1]) + float(out.split()[-1])


def bench_residual_cpu() -> list:
    """CPU per message for the layouts' sizes at 48 kHz, 0.1 s chunks."""
    n = 4800
    sizes = {layout: residual_bytes(layout, n) for layout in LAYOUTS}
    cpu = {layout: cpu_per_message(size) for layout, size in sizes.items()}
    low = min(cpu.values())
    return [(f"residual message of {sizes[layout] / 1e3:.0f} kB (48 kHz, 0.1 s chunk; {layout}): CPU of publisher + "
             "subscriber per message, 10 Hz (/ the smallest, same run)", f"{cpu[layout]:.0f} ({cpu[layout] / low:.2f})",
             "µs (ratio)") for layout in LAYOUTS]


def observer_callback_us(rate: float, chunk: float, repeat: int = 300) -> dict:
    """µs per chunk of the observer's own work (model set none): ``before`` = the observer run
    for a train nobody read and three ``.tolist()`` arrays, ``now`` = the session's pass-through
    and one float32 array from bytes."""
    import timeit

    from bearing_common.bearings import CATALOG
    from bearing_common.states import FaultState
    from bearing_msgs.msg import Residual
    from bearing_observer.node import float32_array
    from bearing_observer.observer import FaultObserver
    from bearing_observer.observer_session import ObserverSession

    n = int(round(rate * chunk))
    y = np.random.default_rng(0).normal(size=50 * n)
    observer = FaultObserver.from_model_set("none", "outer_race", 1800.0, rate)
    session = ObserverSession(FaultState.OUTER_RACE, CATALOG["6205"], "", 1800.0)
    calls = {"before": 0, "now": 0}

    def before():
        i = calls["before"] % 50
        calls["before"] += 1
        out = observer.process(y[i * n:(i + 1) * n])
        msg = Residual()
        msg.residual, msg.estimate = out.residual.tolist(), out.estimate.tolist()
        msg.impulse_train = out.impulse_train.tolist()

    def now():
        i = calls["now"]
        calls["now"] += 1
        out = session.on_chunk(i * n / rate, i * n, rate, "accelerometer", y[(i % 50) * n:(i % 50 + 1) * n])
        Residual().residual = float32_array(out.residual)

    before(), now()  # compiled kernels loaded, models built
    return {name: timeit.timeit(fn, number=repeat) / repeat * 1e6 for name, fn in (("before", before), ("now", now))}


def bench_observer_callback() -> list:
    """The observer's own work per chunk with model set none, before and now, in the same run."""
    rows = []
    for rate, chunk in ((48000.0, 0.01), (48000.0, 0.1), (12000.0, 0.1)):
        t = observer_callback_us(rate, chunk)
        rows.append((f"observer callback work per chunk, model set none, {rate / 1000:g} kHz, {chunk:g} s chunks: "
                     "before / now (now / before, same run)",
                     f"{t['before']:.0f} / {t['now']:.0f} ({t['now'] / t['before']:.2f})", "µs (ratio)"))
    return rows
