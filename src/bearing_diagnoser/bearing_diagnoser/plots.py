"""Figures for ``bearing-diagnose --plot DIR`` (matplotlib, Agg backend; PNG files).

* ``acceleration_states.png`` — the measurement with the true state (simulator) and the
  diagnosed state (thesis Figs. 3.13, 3.18, 3.23, 3.28 with the decision added).
* ``residual_<h>.png`` — each observer's residual against its impulse train (Figs. 3.3-3.6,
  3.14-3.15).
* ``xcorr_<h>.png`` — the cross-correlation of |residual| with the train and the train
  autocorrelation as reference (section 3.2, Figs. 3.7-3.12, 3.16-3.17).
* ``timeline.png`` — per-window significance of each hypothesis (÷ threshold), the chosen
  demodulation band and the shaft speed (envelope-spectrum decision) or the model-explains
  fractions (folding decision), window labels and the published state over time.

:func:`states_figure` and :func:`timeline_figure` also make the figures of the HTML report
(:mod:`.reports.diagnosis_page`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bearing_common.states import FaultState

from .decision.thesis_blocks import train_autocorrelation, train_cross_correlation

#: Longest stretch (s) used for the cross-correlation figures (cost grows with length).
XCORR_MAX_S = 2.0


def pyplot():
    """matplotlib's pyplot on the Agg backend (imported only when a figure is made)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _state_track(decisions, attr: str):
    t = [d.window_end for d in decisions]
    v = [int(getattr(d, attr)) for d in decisions]
    return np.asarray(t), np.asarray(v)


def _save(plt, fig, path: Path, paths: list[Path]) -> None:
    """Write ``fig`` to ``path`` (PNG, 110 dpi), close it and record the path."""
    fig.savefig(path, dpi=110)
    plt.close(fig)
    paths.append(path)


def states_figure(result):
    """The measurement, with the true state (simulator) and the diagnosed state, over time."""
    plt = pyplot()
    fs = result.sample_rate
    x = result.accel
    t = np.arange(x.size) / fs
    labels = [s.label for s in FaultState]
    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(10, 6))
    ax1.plot(t, x, lw=0.4, rasterized=True)  # rasterized: a vector copy of every sample is megabytes
    ax1.set_ylabel("acceleration (m/s²)")
    ax1.set_title(f"measurement and states ({result.model_set}, method {result.method})")
    if result.truth is not None:
        ax2.step(t, result.truth, where="post", label="true", lw=2, alpha=0.6)
    for s in result.segments:
        ax2.hlines(int(s.state), s.start, s.end, colors="C3", lw=3)
        ax2.axvline(s.detected_at, color="C3", ls=":", lw=0.8)
    ax2.plot([], [], color="C3", lw=3, label="diagnosed (from estimated onset)")
    ax2.set_yticks(range(len(labels)), labels)
    ax2.set_xlabel("time (s)")
    ax2.legend(loc="upper right", fontsize=8)
    return fig


def timeline_figure(result):
    """Per window: each hypothesis' significance ÷ threshold, the chosen demodulation band and the
    shaft speed (or the model-explains fractions), the window labels and the published state;
    None when no window was decided."""
    dec = result.decisions
    if not dec:
        return None
    plt = pyplot()
    labels = [s.label for s in FaultState]
    fig, (a1, a2, a3) = plt.subplots(3, 1, sharex=True, figsize=(10, 7))
    te = np.asarray([d.window_end for d in dec])
    for h in (FaultState.OUTER_RACE, FaultState.INNER_RACE, FaultState.BALL):
        if any(h in d.scores.significance for d in dec):
            a1.plot(te, [d.scores.significance.get(h, np.nan) for d in dec],
                    label=f"{h.label} significance ÷ threshold")
    a1.axhline(1.0, color="k", ls="--", lw=0.8)
    a1.legend(fontsize=8)
    bands = [getattr(d.scores, "band", None) for d in dec]
    if any(b is not None for b in bands):
        lo = np.asarray([np.nan if b is None else b.low for b in bands])
        hi = np.asarray([np.nan if b is None else b.high for b in bands])
        a2.fill_between(te, lo / 1e3, hi / 1e3, step="pre", alpha=0.4, label="chosen demodulation band (kHz)")
        a2.set_ylabel("kHz")
        speed = a2.twinx()
        speed.plot(te, [d.scores.speed_hz * 60.0 for d in dec], color="C1", lw=0.8,
                   label="shaft speed used (rpm)")
        speed.set_ylabel("rpm")
        speed.legend(loc="lower right", fontsize=8)
    else:
        for h in (FaultState.OUTER_RACE, FaultState.INNER_RACE):
            a2.plot(te, [d.scores.explained.get(h, np.nan) for d in dec], label=f"{h.label} model explains")
        a2.set_ylim(-1.05, 1.05)
    a2.legend(loc="upper left", fontsize=8)
    tl, lab = _state_track(dec, "label")
    ts, sta = _state_track(dec, "state")
    a3.plot(tl, lab, ".", ms=3, label="window label")
    a3.step(ts, sta, where="post", label="published state")
    a3.set_yticks(range(len(labels)), labels)
    a3.set_xlabel("decision time (s)")
    a3.legend(fontsize=8)
    return fig


def write_figures(result, directory) -> list[Path]:
    """Write the figures of an :class:`~.recording_diagnosis.OfflineResult` into ``directory``; return their paths."""
    plt = pyplot()
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    fs = result.sample_rate
    t = np.arange(result.accel.size) / fs
    _save(plt, states_figure(result), out / "acceleration_states.png", paths)

    for h, st in result.streams.items():
        r, u = st["residual"], st["impulse_train"]
        fig, ax = plt.subplots(figsize=(10, 4))
        ax.plot(t[:r.size], r, lw=0.4, label="residual y − ŷ (m/s²)")
        scale = np.max(np.abs(r)) / max(np.max(np.abs(u)), 1e-12) if u.any() else 1.0
        ax.plot(t[:u.size], u * scale, lw=0.6, color="C2", label="impulse train (scaled)")
        ax.set_xlabel("time (s)")
        ax.set_title(f"{h} observer residual and its impulse train at {st['fault_frequency']:.2f} Hz")
        ax.legend(loc="upper right", fontsize=8)
        _save(plt, fig, out / f"residual_{h}.png", paths)

        n = min(r.size, int(XCORR_MAX_S * fs))
        xc = train_cross_correlation(r[:n], u[:n])
        ac = train_autocorrelation(u[:n])
        lags = (np.arange(xc.size) - (n - 1)) / fs
        fig, ax = plt.subplots(figsize=(10, 4))
        ax.plot(lags, xc, lw=0.5, label="xcorr(|residual|, train)")
        peak = np.max(np.abs(ac)) or 1.0
        ax.plot(lags, ac / peak * (np.max(np.abs(xc)) or 1.0), lw=0.5, color="C1", alpha=0.7,
                label="train autocorrelation (reference, scaled)")
        ax.set_xlabel("lag (s)")
        ax.set_title(f"{h}: cross-correlation of |residual| with the impulse train (thesis 3.2)")
        ax.legend(loc="upper right", fontsize=8)
        _save(plt, fig, out / f"xcorr_{h}.png", paths)

    timeline = timeline_figure(result)
    if timeline is not None:
        _save(plt, timeline, out / "timeline.png", paths)
    return paths
