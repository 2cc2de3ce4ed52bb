"""``bearing-diagnose --report DIR``: one self-contained HTML page per recording.

The page holds the verdict and its evidence in words (:mod:`.terminal_text`), the segments as
a table, the envelope spectrum of each segment with the fault frequencies marked
(:mod:`.envelope_view`: kinematic lines at the speed used, dashed; the comb where it matched
best, solid; shaft harmonics grey), the state timeline (per-window significance, band, speed,
labels and published state: :func:`bearing_diagnoser.plots.timeline_figure`), the signal
with the states (:func:`~bearing_diagnoser.plots.states_figure`) and the JSON lines.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..front_ends import config_for, envelope_baseline
from .diagnosis_summary import verdict
from .envelope_view import envelope_view, fault_markers
from .html_page import badge, esc, svg_figure, table, write_page
from .terminal_text import STATE_WORDS, diagnosis_text

#: Most segments given an envelope spectrum of their own (the longest ones).
MAX_SPECTRA = 4

#: Colour of each hypothesis' markers.
MARKER_COLOURS = {"outer_race": "tab:blue", "inner_race": "tab:red", "ball": "tab:green"}


def _prewhitens(result) -> bool:
    """Whether the decision that ran levelled the spectrum first (the spectral front end does; its
    textbook baseline and the folding front end do not)."""
    config = config_for(result.model_set)
    if result.method == "envelope":
        config = envelope_baseline(config)
    return bool(getattr(config.front_end, "prewhiten", False))


def _decision_window(result) -> float:
    """The decision's window (s), median over its windows."""
    lengths = [d.window_end - d.window_start for d in result.decisions]
    return float(np.median(lengths)) if lengths else 0.0


def spectrum_figure(view, seg: dict, ev: dict, orders: dict, file_name: str):
    """The envelope spectrum of one segment with the fault frequencies marked."""
    from ..plots import pyplot
    plt = pyplot()
    speed = ev["speed_hz"]
    fig, ax = plt.subplots(figsize=(10, 3.8))
    f_top = view.f[-1] if view.f.size else 1.0
    for m in range(1, int(f_top / speed) + 1):
        ax.axvline(m * speed, color="0.85", lw=1.0, zorder=1)
    ax.plot([], [], color="0.85", lw=1.0, label="shaft harmonics")
    for label, lines in fault_markers(orders, speed, f_top).items():
        colour = MARKER_COLOURS[label]
        found = ev["hypotheses"].get(label, {})
        rho = (found["line_hz"] / found["expected_hz"]) if found.get("line_hz") and found.get("expected_hz") else None
        for f, carrier in lines:
            ax.axvline(f, color=colour, ls="--", lw=1.1 if carrier else 0.6, alpha=0.8 if carrier else 0.5, zorder=2)
        name = label.replace("_", " ")
        ax.plot([], [], color=colour, ls="--", lw=1.1, label=f"{name}: kinematic lines at the speed used")
        if rho is not None and (label == seg["state"] or found.get("significance", 0) >= 1.0):
            for f, carrier in lines:
                if carrier and f * rho <= f_top:
                    ax.axvline(f * rho, color=colour, lw=2.0, alpha=0.7, zorder=2)
            ax.plot([], [], color=colour, lw=2.0, label=f"{name}: comb where it matched best (× {rho:.4f})")
    ax.plot(view.f, view.z, color="k", lw=0.8, zorder=3)
    ax.plot([], [], color="k", lw=0.8, label=f"mean of {view.windows} window(s) (noise: about 1)")
    ax.set_xlim(0.0, f_top)
    ax.set_ylim(0.0, 1.15 * max(float(np.max(view.z)), 2.0))
    ax.set_xlabel("envelope frequency (Hz)")
    ax.set_ylabel("normalised squared envelope spectrum")
    ax.set_title(f"{file_name}, {seg['start']:.2f}-{seg['end']:.2f} s ({STATE_WORDS.get(seg['state'], seg['state'])}): "
                 f"band {view.band[0] / 1e3:.2f}-{view.band[1] / 1e3:.2f} kHz, shaft {speed:.2f} Hz "
                 f"({60 * speed:.0f} rpm)", fontsize=9)
    ax.legend(fontsize=7, loc="upper right", framealpha=0.9)
    fig.tight_layout()
    return fig


def _spectra(result, lines: list[dict], summary: dict, file_name: str, bearing) -> list[str]:
    orders = summary["record"]["orders"]
    longest = sorted(range(len(lines)), key=lambda i: lines[i]["end"] - lines[i]["start"], reverse=True)
    out = []
    for i in sorted(longest[:MAX_SPECTRA]):
        seg, ev = lines[i], summary["segments"][i]
        if ev.get("speed_hz") is None:
            out.append(f"<p>{seg['start']:.2f}-{seg['end']:.2f} s: no envelope spectrum (shaft speed unknown).</p>")
            continue
        band = tuple(ev["band_hz"]) if ev.get("band_hz") else None
        view = envelope_view(result.accel, result.sample_rate, seg["start"], seg["end"], ev["speed_hz"], orders,
                             band, bearing, _prewhitens(result), _decision_window(result))
        if view is None:
            out.append(f"<p>{seg['start']:.2f}-{seg['end']:.2f} s: too short for an envelope spectrum.</p>")
            continue
        caption = (f"Envelope spectrum of {view.start:.2f}-{view.end:.2f} s: {view.windows} window(s) of "
                   f"{view.window_s:.3f} s averaged, {'prewhitened, ' if view.prewhitened else ''}band "
                   f"{view.band[0]:.0f}-{view.band[1]:.0f} Hz ({view.band_source}). Each window's spectrum is divided "
                   "by its running median, so noise lies about 1 and a fault's lines stand above it.")
        out.append(svg_figure(spectrum_figure(view, seg, ev, orders, file_name), caption, f"envelope-spectrum-{i}"))
    return out


def _segment_rows(lines: list[dict], summary: dict) -> list[list]:
    rows = []
    for seg, ev in zip(lines, summary["segments"]):
        sig = ", ".join(f"{k.replace('_', ' ')} {e['significance']:.2f}" for k, e in ev["hypotheses"].items())
        band = f"{ev['band_hz'][0] / 1e3:.2f}-{ev['band_hz'][1] / 1e3:.2f} kHz" if ev.get("band_hz") else "-"
        speed = f"{60 * ev['speed_hz']:.0f} rpm" if ev.get("speed_hz") else "-"
        rows.append([f"{seg['start']:.3f}", f"{seg['end']:.3f}", STATE_WORDS.get(seg["state"], seg["state"]),
                     f"{seg['confidence']:.2f}", f"{seg['detected_at']:.3f}", sig or "-", band, speed])
    return rows


def write_diagnosis_page(result, rec, lines: list[dict], summary: dict, path) -> Path:
    """Write the page (module docstring) of ``result`` (an OfflineResult) of recording ``rec``, whose
    JSON segments are ``lines`` and summary ``summary`` (:mod:`.diagnosis_summary`), to ``path``."""
    from ..plots import states_figure, timeline_figure

    name = Path(rec.path).name or str(rec.path)
    i = verdict(lines)
    head = [f"<h1>{esc(name)}</h1>"]
    if i >= 0:
        v = lines[i]
        head.append(f"<p>{badge(v['state'], STATE_WORDS.get(v['state'], v['state']))} confidence "
                    f"{v['confidence']:.2f}; from {v['start']:.2f} s, decided at {v['detected_at']:.2f} s</p>")
    else:
        head.append("<p>No window could be decided.</p>")
    body = head + ["<h2>Verdict and evidence</h2>", f"<pre>{esc(diagnosis_text(name, lines, summary))}</pre>",
                   "<h2>Segments</h2>",
                   table(["start (s)", "end (s)", "state", "confidence", "decided at (s)",
                          "significance ÷ threshold", "band", "speed used"], _segment_rows(lines, summary)),
                   "<h2>Envelope spectrum</h2>", *_spectra(result, lines, summary, name, result.bearing)]
    timeline = timeline_figure(result)
    if timeline is not None:
        body += ["<h2>State timeline</h2>",
                 svg_figure(timeline, "Per analysis window: each hypothesis' significance ÷ its threshold (≥ 1: "
                                      "significant), the demodulation band and shaft speed used, the window's own "
                                      "label and the published state.", "timeline")]
    body += ["<h2>Signal and states</h2>",
             svg_figure(states_figure(result), "The acceleration and the diagnosed state from its estimated onset "
                                               "(dotted: when it was decided).", "signal-states"),
             "<h2>JSON lines</h2>", "<details><summary>as bearing-diagnose --json prints them</summary><pre>"
             + esc("\n".join(json.dumps(line) for line in lines)) + "</pre></details>"]
    return write_page(path, f"{name}: bearing diagnosis", body)
