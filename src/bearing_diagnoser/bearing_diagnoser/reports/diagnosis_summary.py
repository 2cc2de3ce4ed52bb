"""A recording's diagnosis in physical terms: the verdict, and per segment the evidence behind its state.

:func:`summarise` turns an :class:`~bearing_diagnoser.recording_diagnosis.OfflineResult` into
a plain, JSON-able dict (it crosses from a worker process to the one that prints):

* ``record``: duration (s), rate recorded and decided at (Hz), channel, bearing name and
  fault orders (multiples of the shaft rate, eqs. 2.51-2.54), model set, method, the told
  speed (rpm; None: none told), windows not diagnosed;
* ``segments``, one per JSON segment of the run: ``windows`` decided in it, ``speed_hz``
  (the shaft rate the decision used, median), ``told_speed_hz`` (None: none told), ``band_hz``
  (demodulation band, median; None for a front end without one) and per hypothesis
  ``significance`` (median over the windows, as the JSON segment's), ``peak`` (the largest),
  ``expected_hz`` (its fundamental at ``speed_hz``, kinematic) and ``line_hz`` (at the scale
  ρ where its comb matched best in the window of the peak; None without ρ).

The numbers are read from each window's published scores (``WindowScores.as_dict``), so
that this module depends on the names the decision publishes, not on its insides.
"""

from __future__ import annotations

import math

import numpy as np

from bearing_common.states import FaultState

#: The fault hypotheses, in the order they are shown.
HYPOTHESES = (FaultState.OUTER_RACE, FaultState.INNER_RACE, FaultState.BALL)


def bearing_orders(bearing) -> dict:
    """The bearing's characteristic frequencies as multiples of the shaft rate (eqs. 2.51-2.54), by name."""
    o = bearing.orders()
    return {"shaft": 1.0, "ftf": o.ftf, "bsf": o.bsf, "bpfo": o.bpfo, "bpfi": o.bpfi}


def fundamental_orders(orders: dict) -> dict:
    """{hypothesis: (name, fundamental in shaft orders, what its comb adds)} from :func:`bearing_orders`."""
    return {FaultState.OUTER_RACE: ("BPFO", orders["bpfo"], "and its harmonics"),
            FaultState.INNER_RACE: ("BPFI", orders["bpfi"], "and its harmonics, with shaft-rate sidebands"),
            FaultState.BALL: ("2×BSF", 2.0 * orders["bsf"], "and its harmonics, with cage-rate (FTF) sidebands")}


def _finite(v) -> float | None:
    return float(v) if v is not None and math.isfinite(v) else None


def _median(values) -> float | None:
    v = [x for x in values if x is not None and math.isfinite(x)]
    return float(np.median(v)) if v else None


def members(decisions, segments) -> list[list]:
    """The diagnosed windows published while each segment's state was current: decided from the
    segment's ``detected_at`` until the next one's."""
    times = [s.detected_at for s in segments[1:]] + [math.inf]
    out: list[list] = [[] for _ in segments]
    for d in decisions:
        if d.diagnosed:
            out[int(np.searchsorted(times, d.time, side="right"))].append(d.scores.as_dict())
    return out


def segment_evidence(windows: list[dict], orders, speed_hz: float | None) -> dict:
    """One segment's evidence (module docstring) from its windows' published scores."""
    speed = _median(w.get("speed_hz") for w in windows) or speed_hz
    low, high = _median(w.get("band_low_hz") for w in windows), _median(w.get("band_high_hz") for w in windows)
    out = {"windows": len(windows), "speed_hz": speed,
           "told_speed_hz": _median(w.get("told_speed_hz") for w in windows),
           "band_hz": [low, high] if low is not None and high is not None else None, "hypotheses": {}}
    for h, (_name, order, _comb) in fundamental_orders(orders).items():
        values = [w.get(h.label) for w in windows]
        known = [(v, w) for v, w in zip(values, windows) if v is not None and math.isfinite(v)]
        if not known:
            continue
        peak, best = max(known, key=lambda item: item[0])
        rho = _finite(best.get(f"{h.label}_rho"))
        out["hypotheses"][h.label] = {
            "significance": _median(values), "peak": float(peak),
            "expected_hz": None if speed is None else order * speed,
            "line_hz": None if speed is None or rho is None else order * rho * speed}
    return out


def verdict(segments: list[dict]) -> int:
    """Index of the verdict among the JSON segments: the state covering most of the record (as
    ``bearing-accuracy`` scores a record), the later one on a tie; -1 when there is none."""
    if not segments:
        return -1
    cover: dict[str, float] = {}
    for s in segments:
        cover[s["state"]] = cover.get(s["state"], 0.0) + s["end"] - s["start"]
    best = max(cover.values())
    return max(i for i, s in enumerate(segments) if cover[s["state"]] >= best - 1e-9)


def summarise(result, rec, bearing) -> dict:
    """The summary (module docstring) of ``result`` (an OfflineResult) of recording ``rec`` for ``bearing``."""
    orders = bearing_orders(bearing)
    speed_hz = None if result.rpm is None else result.rpm / 60.0
    record = {"duration_s": rec.duration, "recorded_rate_hz": rec.sample_rate,
              "decided_rate_hz": result.sample_rate, "channel": rec.channel, "source": rec.source,
              "bearing": bearing.name, "orders": orders,
              "model_set": result.model_set, "method": result.method,
              "told_rpm": result.rpm, "not_diagnosed": len(result.not_diagnosed)}
    segments = [segment_evidence(w, orders, speed_hz) for w in members(result.decisions, result.segments)]
    return {"record": record, "segments": segments}
