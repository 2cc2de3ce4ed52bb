"""``bearing-trend --plot``: the trended indicators over the life, with the baseline, the limits and the states.

matplotlib (Agg) is imported only here, only when a figure is asked for. :func:`trend_figure`
also makes the figure of the HTML report (:mod:`bearing_diagnoser.reports.trend_page`).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .trend import HealthState

#: Panel title, unit shown and JSON key of each trended indicator.
PANELS = {
    "rms": ("RMS acceleration", "m/s²", "rms_m_s2"),
    "kurtosis": ("kurtosis", "", "kurtosis"),
    "envelope_rms": ("envelope RMS", "m/s²", "envelope_rms_m_s2"),
    "velocity_rms": ("velocity RMS (ISO band)", "mm/s", "velocity_rms_mm_s"),
}

STATE_COLOURS = {HealthState.HEALTHY: "#2e7d32", HealthState.WARNING: "#f9a825", HealthState.ALARM: "#c62828"}


def _time_axis(t_end: float) -> tuple[float, str]:
    """Scale and unit of the time axis for a life of ``t_end`` s."""
    if t_end >= 3 * 3600:
        return 3600.0, "h"
    if t_end >= 180:
        return 60.0, "min"
    return 1.0, "s"


def write_trend_figure(records, monitor, directory, name: str) -> Path:
    """Write ``<directory>/trend_<name>.png``; returns its path."""
    from ..plots import pyplot

    out_dir = Path(directory)
    out_dir.mkdir(parents=True, exist_ok=True)
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", Path(name).name or "trend").strip("_") or "trend"
    path = out_dir / f"trend_{stem}.png"
    fig = trend_figure(records, monitor, name)
    fig.savefig(path, dpi=110)
    pyplot().close(fig)
    return path


def trend_figure(records, monitor, name: str):
    """The figure of :func:`write_trend_figure` (a matplotlib Figure; the caller closes it)."""
    from ..plots import pyplot

    plt = pyplot()
    tracker = monitor.tracker
    names = [n for n in tracker.names if n in PANELS]
    t = np.array([r.trend.t for r in records])
    scale, unit = _time_axis(float(t[-1]) if t.size else 0.0)
    ts = t / scale
    limits = tracker.limits()
    fig, axes = plt.subplots(len(names) + 1, 1, figsize=(10, 2.1 * len(names) + 1.2), sharex=True,
                             gridspec_kw={"height_ratios": [0.35] + [1.0] * len(names)})
    _state_strip(axes[0], ts, records)
    axes[0].set_title(f"{Path(name).name}: condition trend ({len(records)} snapshots)", fontsize=10)
    for ax, n in zip(axes[1:], names):
        title, u, key = PANELS[n]
        values = np.array([_num(r.indicators.to_json().get(key)) for r in records])
        ax.semilogy(ts, values, ".", ms=2.5, color="0.55", label="snapshot", rasterized=True)
        if n in limits:
            k = _unit_scale(n)
            base, (warn, alarm), (m_warn, m_alarm) = limits[n][0] * k, limits[n][1], limits[n][2]
            warn, alarm, m_warn, m_alarm = warn * k, alarm * k, m_warn * k, m_alarm * k
            smooth = np.array([base * r.trend.level.get(n, np.nan) if not r.trend.learning else np.nan
                               for r in records])
            ax.semilogy(ts, smooth, "-", lw=1.2, color="k", label="smoothed (EWMA of median of 3)")
            t_b = tracker.baseline.end / scale
            ax.axvspan(ts[0], t_b, color="0.9", zorder=0, label="baseline")
            ax.axhline(base, color=STATE_COLOURS[HealthState.HEALTHY], lw=1, ls="--", label="baseline level")
            ax.axhline(warn, color=STATE_COLOURS[HealthState.WARNING], lw=1, label="warning limit (smoothed)")
            ax.axhline(alarm, color=STATE_COLOURS[HealthState.ALARM], lw=1, label="alarm limit (smoothed)")
            ax.axhline(m_warn, color=STATE_COLOURS[HealthState.WARNING], lw=0.8, ls=":",
                       label="warning limit (median of 3)")
            ax.axhline(m_alarm, color=STATE_COLOURS[HealthState.ALARM], lw=0.8, ls=":",
                       label="alarm limit (median of 3)")
        ax.set_ylabel(f"{title}" + (f"\n({u})" if u else ""), fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=7, ncol=3, loc="upper left")
    axes[-1].set_xlabel(f"time since the first snapshot ({unit})")
    fig.tight_layout()
    return fig


def _unit_scale(name: str) -> float:
    """Trend limits are in SI; the velocity panel shows mm/s."""
    return 1e3 if name == "velocity_rms" else 1.0


def _num(v) -> float:
    return float("nan") if v is None else float(v)


def _state_strip(ax, ts, records) -> None:
    """The state as coloured spans over time."""
    states = [r.trend.state for r in records]
    start = 0
    for i in range(1, len(states) + 1):
        if i == len(states) or states[i] != states[start]:
            end = ts[i] if i < len(states) else ts[-1]
            ax.axvspan(ts[start], end, color=STATE_COLOURS[states[start]], lw=0)
            start = i
    ax.set_yticks([])
    handles = [_patch(c, s.name.lower()) for s, c in STATE_COLOURS.items()]
    ax.legend(handles=handles, fontsize=7, ncol=3, loc="upper left", framealpha=0.9)


def _patch(colour: str, label: str):
    """A legend patch."""
    from matplotlib.patches import Patch
    return Patch(color=colour, label=label)
