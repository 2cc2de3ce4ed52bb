"""What the ``envelope_spectrum`` topic costs the diagnoser, as ratios measured in one run.

The diagnoser's session decides 20 s of a simulated outer-race fault (bursts at BPFO in white noise,
48 kHz, 0.01 s chunks, the spectral front end); per decided window the node then takes the view and
fills the message (:func:`bearing_diagnoser.spectrum_message.fill_spectrum_message`). Printed: the
decision's CPU time per second of signal, the message's per window, and their ratio; with
``--repeat N`` the decision alone N times, for its scatter.

    .venv/bin/python benchmarks/live_view_cost.py
    PYTHONPATH=<other tree's src/* dirs> .venv/bin/python benchmarks/live_view_cost.py --decision-only
      (the same decision from another source tree: run both in turn for a before/after ratio)
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from bearing_common.bearings import CATALOG, DEFAULT_BEARING  # noqa: E402
from bearing_common.states import FaultState  # noqa: E402
from bearing_diagnoser.diagnoser_node_config import PARAMETERS  # noqa: E402
from bearing_diagnoser.diagnoser_session import DiagnoserSession  # noqa: E402
from bearing_diagnoser.synthetic import burst_train, white_noise  # noqa: E402

FS, RPM, SECONDS, CHUNK = 48000.0, 1800.0, 20.0, 480


def signal() -> np.ndarray:
    rng = np.random.default_rng(7)
    bpfo = CATALOG[DEFAULT_BEARING].orders().bpfo * RPM / 60.0
    return burst_train(SECONDS, FS, bpfo, amplitude=3.0, jitter=0.01, rng=rng) + white_noise(SECONDS, FS, 4.5e-3, rng)


def decide(y: np.ndarray, take_views: bool) -> tuple[float, list]:
    """CPU seconds of the session over ``y`` (after a 2 s warm-up of the same session), and the views taken."""
    values = {p.name: p.default for p in PARAMETERS} | {"model_set": "none", "rpm": RPM}
    session = DiagnoserSession(values, lambda level, text: None)
    session.warm_up()
    views = []
    warm = int(2.0 * FS)
    for i in range(0, warm, CHUNK):
        session.on_residual(FaultState.OUTER_RACE, i / FS, i, FS, y[i:i + CHUNK], None, None, 107.0, "none", 0.0)
    start = time.process_time()
    for i in range(warm, y.size, CHUNK):
        session.on_residual(FaultState.OUTER_RACE, i / FS, i, FS, y[i:i + CHUNK], None, None, 107.0, "none", 0.0)
        if take_views:
            taken = session.take_envelope()
            if taken is not None:
                views.append(taken)
    return time.process_time() - start, views


def fill_cost(views: list, repeat: int = 20) -> float:
    """CPU seconds per window of filling the message from a view."""
    from bearing_diagnoser.spectrum_message import fill_spectrum_message
    from bearing_msgs.msg import EnvelopeSpectrum, FaultLines
    start = time.process_time()
    for _ in range(repeat):
        for stamp, view in views:
            fill_spectrum_message(EnvelopeSpectrum(), view, stamp, "drive_end", FaultLines)
    return (time.process_time() - start) / (repeat * len(views))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--decision-only", action="store_true", help="time the decision alone (any source tree)")
    parser.add_argument("--repeat", type=int, default=1)
    args = parser.parse_args(argv)
    y = signal()
    decided_s = SECONDS - 2.0
    for _ in range(args.repeat):
        cpu, views = decide(y, take_views=not args.decision_only)
        print(f"decision: {cpu / decided_s * 1e3:.2f} ms CPU per s of signal")  # noqa: T201
    if args.decision_only:
        return 0
    per_window = fill_cost(views)
    windows_per_s = len(views) / decided_s
    print(f"spectrum message: {per_window * 1e6:.0f} us CPU per window, {len(views)} windows "  # noqa: T201
          f"({windows_per_s:.2f}/s): {per_window * windows_per_s / (cpu / decided_s) * 100:.2f} % of the decision")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
