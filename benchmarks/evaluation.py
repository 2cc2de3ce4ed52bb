"""Evaluation helpers shared by the benchmarks and the tests: the thesis' cases, scored against truth."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from bearing_common.states import FaultState
from bearing_diagnoser.decision.segments import Segment
from bearing_recordings.recording import Recording

N, O, I = FaultState.NORMAL, FaultState.OUTER_RACE, FaultState.INNER_RACE
#: The thesis' eight cases (section 3.2): two segments each.
THESIS_CASES = {"or": (O, O), "ir": (I, I), "or-ir": (O, I), "ir-or": (I, O), "or-normal": (O, N),
                "normal-or": (N, O), "ir-normal": (I, N), "normal-ir": (N, I)}


#: The steady simulated runs of the long benchmarks (detection curves, false alarms): Hz, rev/min.
STEADY_RATE, STEADY_RPM = 12000.0, 1800.0


@lru_cache(maxsize=4)
def steady_run(state: FaultState, duration_s: float) -> np.ndarray:
    """One noise-free simulator run of ``state`` for ``duration_s`` at STEADY_RPM and STEADY_RATE (m/s²)."""
    from bearing_sim.simulator import SimulationConfig, simulate
    d = simulate(SimulationConfig(rpm=STEADY_RPM, sample_rate=STEADY_RATE), [(state, duration_s)])
    return np.asarray(d["accel"], float)


def simulate_case(name: str, rpm: float = 1800.0, noise_density: float = 0.0, segment_s: float = 0.2,
                  sample_rate: float = 48000.0, seed: int = 0) -> Recording:
    """Simulate thesis case ``name`` with bearing_sim; returns a Recording with truth."""
    from bearing_sim.simulator import SimulationConfig, simulate
    d = simulate(SimulationConfig(rpm=rpm, sample_rate=sample_rate, noise_density=noise_density, seed=seed),
                 [(s, segment_s) for s in THESIS_CASES[name]])
    return Recording(np.asarray(d["accel"], float), float(d["sample_rate"]), float(d["rpm"]), "simulator",
                     np.asarray(d["truth"], int), "accel", f"sim:{name}")


def true_segments(truth: np.ndarray, fs: float) -> list[tuple[float, float, FaultState]]:
    """Maximal runs of the truth array: (start s, end s, state)."""
    truth = np.asarray(truth)
    edges = np.flatnonzero(np.diff(truth)) + 1
    starts = np.r_[0, edges]
    ends = np.r_[edges, truth.size]
    return [(s / fs, e / fs, FaultState(int(truth[s]))) for s, e in zip(starts, ends)]


def score_case(segments: list[Segment], truth: np.ndarray, fs: float) -> list[dict]:
    """Per true segment: was its state detected inside it, when, and how late.

    A true segment [a, b) with state S counts as detected when some diagnosed segment
    with state S was *detected* (``detected_at``) in [a, b + 0.05) and, after that, no
    other state is published before b.  ``delay`` = detected_at − a (s).
    """
    rows = []
    for a, b, st in true_segments(truth, fs):
        hit = None
        for seg in segments:
            if seg.state == st and a - 1e-9 <= seg.detected_at < b + 0.05 and seg.end >= b - 0.05:
                hit = seg
                break
        later_wrong = hit is not None and any(
            s.state != st and hit.detected_at < s.detected_at < b - 1e-9 for s in segments)
        rows.append({"start": a, "end": b, "state": st.label, "detected": hit is not None and not later_wrong,
                     "delay": (hit.detected_at - a) if hit else float("nan"),
                     "onset_error": (hit.start - a) if hit else float("nan")})
    return rows
