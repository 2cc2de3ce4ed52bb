"""Regenerate the documentation's figures into docs/figures/ (run with .venv/bin/python after `make test`).

* ``or_ir_acceleration.png`` — the simulator's OR-IR case with the fault periods marked;
* the thesis' Figs. 2.11-2.16 and 3.3-3.6 from the shipped sim_48k models
  (``bearing_observer.obs_figures``);
* ``diagnosis/`` — the ``bearing-diagnose --plot`` figure set for the OR-IR case;
* ``real/`` — one MFPT inner-race record (``benchmarks/shared_data.yaml``, read in place from
  ../shared/data or $BEARING_DATA_DIR; skipped with one line when absent):
  ``mfpt_inner_race_envelope_spectrum.png``, the normalised squared envelope spectrum of one
  analysis window as the spectral decision and the textbook baseline see it, with the combs
  they test; ``mfpt_inner_race_timeline.png`` and ``mfpt_inner_race_acceleration_states.png``
  from ``bearing-diagnose --plot``.
"""

import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # `benchmarks` as a package

from bearing_common.bearings import Bearing, fault_frequency, load_bearing  # noqa: E402
from bearing_common.states import FaultState  # noqa: E402
from bearing_diagnoser.accuracy import load_manifest  # noqa: E402
from bearing_diagnoser.front_ends import config_for, envelope_baseline  # noqa: E402
from bearing_diagnoser.pipeline import choose_model_set  # noqa: E402
from bearing_diagnoser.spectral.envelope_spectrum import band_ses, normalise, window_spectrum  # noqa: E402
from bearing_diagnoser.spectral.evidence_stream import EvidenceStream, WindowEvidence  # noqa: E402
from bearing_diagnoser.spectral.fault_combs import HYPOTHESES, N_HARMONICS, comb_evidence, comb_terms  # noqa: E402
from bearing_diagnoser.spectral.settings import SpectralSettings  # noqa: E402
from bearing_diagnoser.spectral.window_label import label_window, significance_level  # noqa: E402
from bearing_sim.model_parameters import DRIVE_END  # noqa: E402
from bearing_sim.schedule import scenario  # noqa: E402
from bearing_sim.simulator import SimulationConfig, simulate  # noqa: E402
from benchmarks.obs_figures import make_figures  # noqa: E402

matplotlib.use("Agg")

OUT = ROOT / "docs" / "figures"
RPM = 1800.0
BEARING_DIAGNOSE = ROOT / ".venv" / "bin" / "bearing-diagnose"
MANIFEST = ROOT / "benchmarks" / "shared_data.yaml"
#: The real-machine record (a ``name`` of the manifest) and where its window starts (s): one
#: decision of the steady state, after the first speed and band re-estimation at 1 s.
RECORD = "Inner 3"
WINDOW_AT_S = 1.6
REAL_PREFIX = "mfpt_inner_race_"


def or_ir_figure(run: dict, path: pathlib.Path) -> None:
    """Acceleration of the OR-IR case; ticks one fault period apart from each segment's first impact."""
    t, a = run["t"], run["accel"]
    fig, ax = plt.subplots(figsize=(11, 4))
    ax.plot(t, a, lw=0.4, color="0.25")
    top = np.max(np.abs(a)) * 1.05
    for state, color in ((FaultState.OUTER_RACE, "tab:blue"), (FaultState.INNER_RACE, "tab:red")):
        inside = run["truth"] == state
        if not inside.any():
            continue
        t0, t1 = t[inside][0], t[inside][-1]
        period = 1.0 / fault_frequency(DRIVE_END, state, RPM)  # the simulator's bearing: the 6205 drive end
        first = t0 + np.argmax(np.abs(a[inside][: int(period * run["sample_rate"])])) / run["sample_rate"]
        ticks = np.arange(first, t1, period)
        ax.vlines(ticks, top * 0.9, top, color=color, lw=1.2)
        ax.axvspan(t0, t1, color=color, alpha=0.06)
        ax.text(t0 + 0.003, top * 1.02, f"{state.label}: period {period * 1e3:.3f} ms "
                f"({1 / period:.2f} Hz)", color=color, fontsize=9)
    ax.set_ylim(-top, top * 1.12)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("drive-end housing y acceleration (m/s²)")
    ax.set_title("bearing-sim --scenario or-ir (1800 rpm, 48 kHz): ticks one fault period apart")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def diagnose_figures(recording: pathlib.Path, out: pathlib.Path, keep=None, prefix: str = "") -> None:
    """``bearing-diagnose RECORDING --plot``: its PNGs (all, or those named in ``keep``) into ``out``, named
    ``prefix + name``."""
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([str(BEARING_DIAGNOSE), str(recording), "--plot", tmp], check=True, stdout=subprocess.DEVNULL)
        for png in sorted(pathlib.Path(tmp).glob("*.png")):
            if keep is None or png.name in keep:
                shutil.copyfile(png, out / f"{prefix}{png.name}")


@dataclass
class WindowView:
    """One analysis window as a spectral decision saw it.

    ``window``: the engine's evidence; ``terms``: the comb it tested per hypothesis ((c, d, carrier)
    rows, term frequency (c·ρ + d)·fr), over the scale range ``rho``; ``f`` (Hz) and ``z``: the
    normalised squared envelope spectrum (dimensionless, Exp(1) under Gaussian noise);
    ``log10p_all``: per hypothesis, the comb before ambiguous terms were dropped (what it would
    have shown had it been tested).
    """

    name: str
    settings: SpectralSettings
    window: WindowEvidence
    terms: dict
    rho: tuple[float, float]
    f: np.ndarray
    z: np.ndarray
    log10p_all: dict


def window_view(name: str, x: np.ndarray, fs: float, bearing: Bearing, rpm: float, settings: SpectralSettings,
                at_s: float, f_max: float | None = None) -> WindowView:
    """The window of the ``settings`` schedule starting nearest ``at_s`` (s) on signal ``x`` (fs Hz).

    The engine runs again up to that window's end so that its speed, band and comb are those
    of the window; the spectrum is recomputed with the engine's functions, up to ``f_max`` Hz
    (default its own highest tested line), and checked to give the engine's evidence.
    """
    def run(end: int):
        engine = EvidenceStream(fs, bearing, settings)
        engine.tell_speed(rpm / 60.0)
        return engine, engine.push(0, x[:end])

    chosen = min(run(x.size)[1], key=lambda w: abs(w.start / fs - at_s))
    engine, windows = run(chosen.end)
    w = windows[-1]
    seg = x[w.start:w.end]
    spectrum = window_spectrum(seg, settings.prewhiten)

    def normalised_ses(f_top: float):
        ses, df = band_ses(spectrum, seg.size, fs, np.array([[w.band.low, w.band.high]]), f_top)
        return normalise(ses), df

    z, df = normalised_ses(engine.f_top)  # as the engine computed it (the running median depends on the length)

    def evidence(terms: dict) -> dict:
        found = comb_evidence(z, df, w.speed_hz, terms, engine.rho, settings.mask_shaft, w.band.candidates)
        return {h: float(lp[0]) for h, (lp, *_) in found.items()}

    if any(not np.isclose(lp, w.evidence[h].log10p) for h, lp in evidence(engine.terms).items()):
        raise RuntimeError(f"{name}: the recomputed spectrum does not give the engine's evidence")
    full = evidence(comb_terms(bearing, fundamental_only=settings.fundamental_only))
    shown, df = normalised_ses(max(engine.f_top, f_max or 0.0))
    return WindowView(name, settings, w, engine.terms, engine.rho, np.arange(shown.shape[1]) * df, shown[0], full)


def _pvalues(view: WindowView) -> str:
    """'outer race 0.0, inner race -35.3, ball 0.0 (untested; -0.1 if tested)': log10 p per hypothesis."""
    parts = []
    for h in HYPOTHESES:
        e = view.window.evidence[h]
        note = "" if e.terms else f" (untested; {view.log10p_all[h]:.1f} if tested)"
        parts.append(f"{h.label.replace('_', ' ')} {e.log10p:.1f}{note}")
    return ", ".join(parts)


def spectrum_panel(ax, view: WindowView, bearing: Bearing, pfa: float, fs: float, f_max: float) -> None:
    """Normalised SES of ``view`` up to ``f_max`` Hz with the inner-race comb (dotted where not tested),
    the outer-race comb dashed and the shaft harmonics grey; title: window, band, speed, log10 p."""
    w = view.window
    fr = w.speed_hz
    ir, outer = w.evidence[FaultState.INNER_RACE], w.evidence[FaultState.OUTER_RACE]
    tested = {tuple(t) for t in view.terms[FaultState.INNER_RACE]}
    for m in range(1, int(f_max / fr) + 1):
        ax.axvline(m * fr, color="0.8", lw=1.0, zorder=1)
    for k in range(1, N_HARMONICS + 2):
        ax.axvline(k * bearing.orders().bpfo * outer.rho * fr, color="tab:blue", ls="--", lw=1.0, zorder=1)
    for row in comb_terms(bearing)[FaultState.INNER_RACE]:
        c, d, carrier = row
        ax.axvline((c * ir.rho + d) * fr, color="tab:red" if carrier else "tab:orange", lw=1.6 if carrier else 1.2,
                   ls="-" if tuple(row) in tested else ":", zorder=2)
    shown = view.f <= f_max
    ax.plot(view.f[shown], view.z[shown], color="k", lw=0.8, zorder=3)
    ax.set_xlim(0.0, f_max)
    ax.set_ylim(0.0, 1.5 * view.z[shown].max())  # room for the legend
    ax.set_ylabel("normalised SES (÷ running median · ln 2)")
    label, _, _ = label_window({h: e.log10p for h, e in w.evidence.items()}, pfa)
    ax.set_title(f"{view.name}: window {w.start / fs:.3f}-{w.end / fs:.3f} s ({(w.end - w.start) / fs:.3f} s), "
                 f"band {w.band.low / 1e3:.2f}-{w.band.high / 1e3:.2f} kHz, shaft {fr:.2f} Hz ({w.speed_source})\n"
                 f"log10 p: {_pvalues(view)}; significant below {significance_level(pfa, len(HYPOTHESES)):.1f} "
                 f"→ {label.label}", fontsize=9)
    rho = f"ρ = {ir.rho:.4f}, best match" if ir.terms else "ρ = 1, kinematic"
    untested = f"within the ρ search {view.rho[0]:.3f}-{view.rho[1]:.3f} of another fault's line"
    if view.settings.fundamental_only:
        untested = "harmonics and sidebands are not in its comb" + ("" if ir.terms else f";\nBPFI: {untested}")
    masked = "masked" if view.settings.mask_shaft else "not masked"
    ax.legend(handles=[
        Line2D([], [], color="k", lw=0.8, label="normalised SES (Gaussian noise: mean 1)"),
        Line2D([], [], color="tab:red", lw=1.6, label=f"k·BPFI·ρ, inner race ({rho})"),
        Line2D([], [], color="tab:orange", lw=1.2, label="k·BPFI·ρ ± fr"),
        Line2D([], [], color="tab:red", lw=1.2, ls=":", label=f"dotted: not tested ({untested})"),
        Line2D([], [], color="tab:blue", lw=1.0, ls="--", label=f"k·BPFO·ρ, outer race (ρ = {outer.rho:.4f})"),
        Line2D([], [], color="0.8", lw=1.0, label=f"shaft harmonics m·fr ({masked})"),
    ], loc="upper right", fontsize=7.5, framealpha=0.95)


def real_machine_figures(out: pathlib.Path) -> None:
    """``real/``: the envelope-spectrum figure and the bearing-diagnose timeline of :data:`RECORD`."""
    entry = next(e for e in load_manifest(MANIFEST, root=os.environ.get("BEARING_DATA_DIR")) if e.name == RECORD)
    if not entry.path.is_file():
        print(f"real-machine figures skipped: {entry.path} not found (set BEARING_DATA_DIR to the recordings)")
        return
    out.mkdir(parents=True, exist_ok=True)
    rec = entry.load()
    bearing = load_bearing(entry.bearing)
    config = config_for(choose_model_set(rec.source, rec.sample_rate, bearing).name)
    f_max = (N_HARMONICS * bearing.orders().bpfi + 1.5) * rec.rpm / 60.0  # Hz: 3·BPFI and its upper sideband
    ours = window_view("our decision (prewhitened, band chosen by the fault evidence)", rec.accel, rec.sample_rate,
                       bearing, rec.rpm, config.front_end, WINDOW_AT_S, f_max)
    baseline = window_view("textbook baseline (no prewhitening, kurtogram band, fundamentals only)", rec.accel,
                           rec.sample_rate, bearing, rec.rpm, envelope_baseline(config).front_end, WINDOW_AT_S, f_max)
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(11, 8.5))
    for ax, view in zip(axes, (ours, baseline)):
        spectrum_panel(ax, view, bearing, config.pfa, rec.sample_rate, f_max)
        print(f"{entry.path.name}, {view.name}: samples {view.window.start}-{view.window.end}, "
              f"log10 p {_pvalues(view)}")
    axes[-1].set_xlabel("envelope frequency (Hz)")
    fig.suptitle(f"MFPT {entry.path.stem} ({entry.note}, {rec.rpm:g} rpm told): what one analysis window shows",
                 fontsize=11)
    fig.tight_layout()
    fig.savefig(out / f"{REAL_PREFIX}envelope_spectrum.png", dpi=110)
    plt.close(fig)
    diagnose_figures(entry.path, out, keep=("timeline.png", "acceleration_states.png"), prefix=REAL_PREFIX)


def main() -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    run = simulate(SimulationConfig(rpm=RPM, sample_rate=48000.0), scenario("or-ir", 0.2))
    or_ir_figure(run, OUT / "or_ir_acceleration.png")
    with tempfile.TemporaryDirectory() as tmp:
        npz = pathlib.Path(tmp) / "or_ir.npz"
        np.savez(npz, **run, source="simulator")  # as bearing-sim writes it: read as the simulator's
        make_figures(OUT / "observer", "sim_48k", data=run)
        diagnose_figures(npz, OUT / "diagnosis")
    real_machine_figures(OUT / "real")
    print(f"figures in {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
