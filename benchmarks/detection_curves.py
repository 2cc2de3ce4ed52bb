"""Detection against fault amplitude: how far below the recorded faults each method still finds them.

Two families of signals, both ending where a method stops finding the fault:

* *Recorded faults, scaled into healthy recordings* (:func:`recorded_curves`): a fault record
  of a rig, multiplied by g (0 dB, -3 dB, ...), added to the healthy record of the same rig,
  sensor and speed (CWRU 097 at 48 kHz and decimated to 12 kHz under the 0 hp drive-end
  faults; HIT-SM ``Normal_<rpm>`` under the faults at that speed; MFPT has no healthy record).
  The mixture keeps the healthy record's speed and its statement of it, so a HIT-SM mixture is
  labelled with a nominal speed as its faults are.
* *The simulator at rising sensor noise* (:func:`simulated_curves`): steady outer- and
  inner-race faults at 1800 rpm and 12 kHz, white noise added at rising density (the
  simulator's own noise model, applied to one noise-free run per fault).

For each signal and method (``model``: the decision the recording gets by default;
``envelope``: the textbook baseline with the same accumulation) the level is lowered in 3 dB
steps until the state covering most of the record is no longer the true one; that level, the
*limit*, is recorded with what was published instead (NORMAL, UNKNOWN, or a wrong part). The
curves are the share of signals still found at each level.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from bearing_common.states import FaultState
from bearing_diagnoser.accuracy import LabelledRecording, evaluate
from bearing_recordings.recording import MEASURED_RPM_TOLERANCE, InputError, Recording
from benchmarks.evaluation import STEADY_RATE, STEADY_RPM, steady_run

#: Resolution of a limit (dB; the search steps twice that) and the lowest fault level tried (dB).
STEP_DB, FLOOR_DB = 3.0, -60.0
#: The simulator's noise: the highest and lowest signal-to-noise ratio tried (dB, fault signal RMS over noise RMS).
SIM_SNR_DB = (24.0, -36.0)


@lru_cache(maxsize=64)
def _loaded(record: LabelledRecording) -> Recording:
    return record.load()


@dataclass(frozen=True)
class ScaledFault:
    """``fault`` scaled by ``gain`` and added to ``healthy``: a labelled recording for
    :func:`bearing_diagnoser.accuracy.evaluate` (the fault's truth and bearing, the healthy record's
    speed and rate)."""

    fault: LabelledRecording
    healthy: LabelledRecording
    gain: float

    @property
    def dataset(self) -> str:
        return self.fault.dataset

    @property
    def name(self) -> str:
        return f"{self.fault.name} in {self.healthy.name}"

    @property
    def truth(self) -> FaultState:
        return self.fault.truth

    @property
    def bearing(self) -> str:
        return self.fault.bearing

    @property
    def note(self) -> str:
        return f"{20 * np.log10(self.gain):.0f} dB"

    def load(self) -> Recording:
        fault, base = _loaded(self.fault), _loaded(self.healthy)
        if fault.sample_rate != base.sample_rate:
            raise InputError(f"{self.name}: {fault.sample_rate:g} Hz fault, {base.sample_rate:g} Hz healthy record")
        n = min(fault.accel.size, base.accel.size)
        return replace(base, accel=base.accel[:n] + self.gain * fault.accel[:n], truth=None,
                       path=f"{base.path} + {self.gain:.4g} x {fault.path}")


@dataclass(frozen=True)
class SimulatedFault:
    """A steady simulated fault (12 kHz, 1800 rpm) with white sensor noise at ``snr_db`` below its RMS."""

    truth: FaultState
    snr_db: float
    duration_s: float = 8.0
    dataset: str = "simulator"
    bearing: str = "6205"

    @property
    def name(self) -> str:
        return f"steady {self.truth.label}"

    @property
    def note(self) -> str:
        return f"SNR {self.snr_db:.0f} dB"

    def load(self) -> Recording:
        x = steady_run(self.truth, self.duration_s)
        rng = np.random.default_rng(int(self.truth) * 1000 + int(round(10 * self.snr_db)) % 1000)
        noise = rng.standard_normal(x.size) * np.sqrt(np.mean(x ** 2)) * 10 ** (-self.snr_db / 20)
        return Recording(x + noise, STEADY_RATE, STEADY_RPM, "simulator", None, "accel", f"sim:{self.name}",
                         rpm_tolerance=MEASURED_RPM_TOLERANCE)


@dataclass
class Limit:
    """Where one method stops finding one signal's fault: the lowest level (dB) still found (None: not
    found at the first level) and what was published at the next level down (or at the floor)."""

    signal: str
    family: str
    method: str
    found_down_to: float | None
    instead: str
    levels: list  # (level dB, state label covering most of the record)
    fault_to_healthy_db: float | None = None  # recorded faults: the fault record's RMS over the healthy one's


def race_pairs(records: list[LabelledRecording]) -> list[tuple[str, LabelledRecording, LabelledRecording]]:
    """(family, race fault, healthy record of the same rig, rate and speed label) for every race fault
    with such a healthy record."""
    def rig(r):
        return r.dataset.split("-")[0], r.resample_to or r.sample_rate, r.rpm

    healthy = {rig(r): r for r in records if r.truth == FaultState.NORMAL}
    out = []
    for r in records:
        if r.truth in (FaultState.OUTER_RACE, FaultState.INNER_RACE) and rig(r) in healthy:
            out.append((f"{r.dataset} {(r.resample_to or r.sample_rate) / 1000:g} kHz", r, healthy[rig(r)]))
    return out


def limit(signal_at, top: float, floor: float, method: str, family: str, name: str) -> Limit:
    """Lower the level from ``top`` (dB) in steps of 2·STEP_DB until ``signal_at(level)``'s state covering
    most of the record is not its truth, then try the level between: the limit to STEP_DB."""
    seen = []

    def found(level: float) -> bool:
        r = evaluate(signal_at(level), method)
        seen.append((level, r.state.label if r.state is not None else f"error: {r.error}"))
        return r.correct

    level = top
    while level >= floor - 1e-9:
        if not found(level):
            if level == top:
                return Limit(name, family, method, None, seen[-1][1], seen)
            if found(level + STEP_DB):
                return Limit(name, family, method, level + STEP_DB, seen[-2][1], seen)
            return Limit(name, family, method, level + 2 * STEP_DB, seen[-1][1], seen)
        level -= 2 * STEP_DB
    return Limit(name, family, method, level + 2 * STEP_DB, "found at every level", seen)


def _recorded_limit(args) -> Limit:
    family, fault, healthy, method = args
    out = limit(lambda db: ScaledFault(fault, healthy, float(10 ** (db / 20))), 0.0, FLOOR_DB, method, family,
                f"{fault.name} in {healthy.name}")
    out.fault_to_healthy_db = float(20 * np.log10(np.std(_loaded(fault).accel) / np.std(_loaded(healthy).accel)))
    return out


def _simulated_limit(args) -> Limit:
    state, method = args
    return limit(lambda snr: SimulatedFault(state, float(snr)), SIM_SNR_DB[0], SIM_SNR_DB[1], method,
                 "simulator 12 kHz (SNR dB)", f"steady {state.label}")


def curves(records: list[LabelledRecording], methods=("model", "envelope"), jobs: int = 1) -> list[Limit]:
    """Every limit: recorded faults scaled into healthy records, and the simulator at rising noise."""
    tasks = [(_recorded_limit, (fam, f, h, m)) for fam, f, h in race_pairs(records) for m in methods]
    tasks += [(_simulated_limit, (s, m)) for s in (FaultState.OUTER_RACE, FaultState.INNER_RACE) for m in methods]
    if jobs <= 1:
        return [fn(a) for fn, a in tasks]
    from concurrent.futures import ProcessPoolExecutor
    with ProcessPoolExecutor(jobs) as pool:
        return list(pool.map(_call, tasks))


def _call(task):
    fn, args = task
    return fn(args)


def markdown(limits: list[Limit], methods=("model", "envelope")) -> list[str]:
    """Per family: the share still found at each level per method, and each signal's limit."""
    lines = []
    for family in dict.fromkeys(x.family for x in limits):
        group = [x for x in limits if x.family == family]
        tried = [lv for x in group for lv, _ in x.levels]
        levels = np.arange(max(tried), min(tried) - 1e-9, -2 * STEP_DB)
        signals = list(dict.fromkeys(x.signal for x in group))
        unit = "SNR (dB)" if "SNR" in family else "fault level (dB)"
        lines += [f"**{family}** ({len(signals)} signals): share of faults still found", "",
                  f"| {unit} | " + " | ".join(f"{lv:g}" for lv in levels) + " |", "|---|" + "---|" * len(levels)]
        for m in methods:
            found = [x.found_down_to for x in group if x.method == m]
            lines.append(f"| {m} | " + " | ".join(
                f"{sum(f is not None and f <= lv + 1e-9 for f in found)}/{len(found)}" for lv in levels) + " |")
        recorded = group[0].fault_to_healthy_db is not None
        lines += ["", "| signal | " + ("fault / healthy RMS | " if recorded else "")
                  + " | ".join(f"{m}: found down to (then)" for m in methods) + " |",
                  "|---|" + "---|" * (len(methods) + recorded)]
        for s in signals:
            first = next(x for x in group if x.signal == s)
            cells = [f"{first.fault_to_healthy_db:+.1f} dB"] if recorded else []
            for m in methods:
                x = next((x for x in group if x.signal == s and x.method == m), None)
                cells.append("-" if x is None else
                             f"{'not found' if x.found_down_to is None else f'{x.found_down_to:g} dB'} ({x.instead})")
            lines.append(f"| {s} | " + " | ".join(cells) + " |")
        lines.append("")
    return lines


def figure(limits: list[Limit], path, methods=("model", "envelope")) -> None:
    """The curves: share of faults found against level, one panel per family."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    families = list(dict.fromkeys(x.family for x in limits))
    fig, axes = plt.subplots(1, len(families), figsize=(4.2 * len(families), 3.4), squeeze=False)
    for ax, family in zip(axes[0], families):
        group = [x for x in limits if x.family == family]
        tried = [lv for x in group for lv, _ in x.levels]
        levels = np.arange(max(tried), min(tried) - 1e-9, -STEP_DB)
        for m, style in zip(methods, ("-o", "--s")):
            found = [x.found_down_to for x in group if x.method == m]
            share = [np.mean([f is not None and f <= lv + 1e-9 for f in found]) for lv in levels]
            ax.plot(levels, share, style, ms=3, label={"model": "our decision", "envelope": "textbook"}.get(m, m))
        ax.set_xlabel("SNR (dB)" if "SNR" in family else "fault level (dB below the recording)")
        ax.set_title(family, fontsize=9)
        ax.set_ylim(-0.03, 1.03)
        ax.invert_xaxis()
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("share of faults found")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
