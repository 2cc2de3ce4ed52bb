"""Accuracy under changing speed (issue 27, item 5): detection against fault amplitude at constant speed
and on ramps, for the decision with a tachometer, tacho-less, and the constant-speed decision.

    python -m benchmarks.speed_accuracy [--out out/speed_accuracy.md] [--figure out/speed_accuracy.png]
                                        [--docs docs/changing-speed.md] [--quick]

(``make speed-accuracy``, run by ``make accuracy``.) Three modes on every signal:

* ``tachometer``: the exact speed per sample is given: the decision follows it in the shaft-angle
  domain (:mod:`bearing_diagnoser.spectral.angle_domain`). For a warped record that is the profile
  times the record's *own* shaft speed per sample (:func:`benchmarks.speed_ramps.own_speed`, tracked on
  the constant-speed record at that level), not times its label: the label is one number, while the
  shaft's lines sit off it and wander (CWRU ±0.15 % within a second), and a tachometer on the shaft reads
  them (with the label times the profile, CWRU 105 in 097 was found on the ±20 and ±40 % ramps only at
  0 dB, its constant-speed limit −18 dB). A mixture holds two shafts: the speed is its dominant shaft
  lines' (105 in 097 at −18 dB: 097's; HIT-SM at −30 dB: the fault record's, 1 % slower than Normal_900's);
* ``tacho-less``: the speed per sample is tracked from the vibration
  (:func:`bearing_diagnoser.order_tracking.track_speed`, told the nominal speed ± (half the ramp +
  5 %) and twice the ramp's rate as :mod:`benchmarks.speed_tracking` does), then followed as a measured
  one, unless too few of its frames show a shaft comb (``SpeedTrack.unsupported``: then not decided, as
  ``bearing-diagnose --track-speed``); the table gives the tracker's error (95th percentile per sample)
  against the tachometer;
* ``constant``: the constant-speed decision, told the nominal (mean) speed to the record's own
  tolerance, no speed series.

Signals, each at constant speed and along ramps of ±10, ±20 and ±40 % of its nominal speed over
10 s (mean the nominal speed, :func:`benchmarks.speed_ramps.ramp_profiles`; ``--quick``: +20 and
−40 only):

* *synthetic* (:mod:`benchmarks.synthetic_ramps`): the 6205 at 1800 rev/min and 12 kHz, shaft
  harmonics, outer-race impacts ringing at a resonance **fixed in Hz**, as on a real ramp;
* *warped development recordings*: a race fault record scaled into the healthy record of its rig
  (as :mod:`benchmarks.detection_curves`: CWRU 12 kHz 130 and 105 into 097, HIT-SM OR5_900 and
  IR5_900 into Normal_900), then played along the profile (:mod:`bearing_recordings.speed_warp`).
  **Unlike a real ramp, a warped record's resonances move with the speed too** (and its impacts keep
  their constant-speed strength): it tests the speed handling, not the physics of a run-up.
  MFPT has no healthy record: its Outer 2 and Inner 2 are warped as recorded (0 dB only). At
  constant speed a record is "warped" along a constant profile too, so that it loses what every
  warp loses (its anti-aliasing low-pass at fs/2.2: the top 9 % of the band).

Detection: a level is *found* when the record's published states (its segments) include the true
fault and never a wrong part. The constant-speed limit L of a signal is the lowest level, in 3 dB
steps down from 0 dB, at which the constant-speed decision finds it at constant speed; each mode on
each ramp is then tried at L, L + 3 dB and 0 dB: the table gives the first level found, relative to
L (``0`` = as low as at constant speed, ``+3``, ``0 dB`` = only at the recorded level, ``—`` = not
even there). False alarms: the healthy records (synthetic; CWRU 097 at 12 kHz; HIT-SM Normal_600,
_900, _1200) along every profile, each mode: the published fault segments and the windows labelled
a fault.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time
from dataclasses import dataclass, replace

import numpy as np

from bearing_common.bearings import load_bearing
from bearing_common.shaft_angle import SpeedProfile
from bearing_common.states import FaultState
from bearing_diagnoser.order_tracking import track_speed
from bearing_diagnoser.recording_diagnosis import diagnose_recording
from bearing_recordings.recording import InputError, Recording
from bearing_recordings.speed_warp import centred_span, warp
from benchmarks.detection_curves import ScaledFault
from benchmarks.doc_tables import add_docs_option, nested, write_block
from benchmarks.speed_ramps import RAMP_SECONDS, development_records, own_speed, ramp_profiles
from benchmarks.speed_tracking import errors, rate_limit, search_range
from benchmarks.synthetic_ramps import BEARING as SYNTHETIC_BEARING
from benchmarks.synthetic_ramps import RATE as SYNTHETIC_RATE
from benchmarks.synthetic_ramps import ramp_signal

MODES = ("tachometer", "tacho-less", "constant")
PROFILES = ("const", "up10", "down10", "up20", "down20", "up40", "down40")
QUICK_PROFILES = ("const", "up20", "down40")
STEP_DB, FLOOR_DB = 3.0, -30.0
SYNTHETIC_RPM, SYNTHETIC_FAULT = 1800.0, 2.0  # rev/min; m/s², the impacts' peak at 0 dB
#: (data set, fault, healthy) scaled mixtures; MFPT records as recorded.
PAIRS = (("CWRU", "130", "097@12k"), ("CWRU", "105", "097@12k"), ("HIT-SM", "OR5_900", "Normal_900"),
         ("HIT-SM", "IR5_900", "Normal_900"))
AS_RECORDED = ("Outer 2", "Inner 2")
HEALTHY = ("097@12k", "Normal_600", "Normal_900", "Normal_1200")
WRONG = {FaultState.OUTER_RACE, FaultState.INNER_RACE, FaultState.BALL}


@dataclass
class Signal:
    """A signal family: ``at(level dB, profile name)`` → (accel, fs, speed per sample, nominal rpm, told
    tolerance, source); ``truth``; ``warped`` (a development record: resonances move with the speed)."""

    name: str
    truth: FaultState
    bearing: object
    at: object
    warped: bool
    recorded_only: bool = False


def _synthetic(truth: FaultState) -> Signal:
    def at(level, profile_name):
        profile = ramp_profiles(SYNTHETIC_RPM)[profile_name] if profile_name != "const" \
            else SpeedProfile.constant(SYNTHETIC_RPM)
        amplitude = SYNTHETIC_FAULT * 10 ** (level / 20) if truth != FaultState.NORMAL else 0.0
        x, w = ramp_signal(profile, RAMP_SECONDS, amplitude)
        return x, SYNTHETIC_RATE, w, SYNTHETIC_RPM, None, "mat"
    return Signal(f"synthetic {truth.label}", truth, SYNTHETIC_BEARING, at, False)


def _warped(name: str, truth: FaultState, bearing, load) -> Signal:
    """``load(level)``: the constant-speed record at a level (a mixture: the fault scaled into the healthy
    record), whose own shaft speed the tachometer reads."""
    cache = {}

    def at(level, profile_name):
        if level not in cache:
            cache.clear()
            rec = load(level)
            cache[level] = rec, own_speed(rec)
        rec, own = cache[level]
        profile = ramp_profiles(rec.rpm)[profile_name] if profile_name != "const" \
            else SpeedProfile.from_rpm_points([(0.0, rec.rpm), (RAMP_SECONDS, rec.rpm)])
        start, end = centred_span(profile, rec.rpm, rec.duration)
        w = warp(rec.accel, rec.sample_rate, rec.rpm, profile, start, end, own)
        stated = profile.omega(start + np.arange(w.accel.size) / w.sample_rate)  # the label's: told in mode constant
        return w.accel, w.sample_rate, w.shaft_speed, float(np.mean(stated)) * 30 / np.pi, rec.rpm_tolerance, \
            rec.source
    return Signal(name, truth, bearing, at, True)


def signals(quick: bool) -> tuple[list[Signal], list[Signal]]:
    """(fault signals, healthy signals) present (the development records found beside the repository)."""
    records = {r.name: r for r in development_records()}
    from bearing_diagnoser.accuracy import load_manifest
    from benchmarks.speed_ramps import MANIFEST
    every = {r.name: r for r in load_manifest(MANIFEST)}  # (097@12k is a resampled copy)
    faults, healthy = [_synthetic(FaultState.OUTER_RACE)], [_synthetic(FaultState.NORMAL)]
    for dataset, fault, base in PAIRS[:2] if quick else PAIRS:
        if fault in records and every.get(base) is not None and every[base].path.is_file():
            f, b = records[fault], every[base]
            faults.append(_warped(f"{dataset} {fault} in {base}", f.truth, load_bearing(f.bearing),
                                  lambda level, f=f, b=b: ScaledFault(f, b, 10 ** (level / 20)).load()))
    for name in () if quick else AS_RECORDED:
        if name in records:
            r = records[name]
            s = _warped(f"MFPT {name}", r.truth, load_bearing(r.bearing), lambda level, r=r: r.load())
            faults.append(replace(s, recorded_only=True))
    for name in HEALTHY[:2] if quick else HEALTHY:
        if name in every and every[name].path.is_file():
            r = every[name]
            healthy.append(_warped(f"{r.dataset} {name}", FaultState.NORMAL, load_bearing(r.bearing),
                                   lambda level, r=r: r.load()))
    return faults, healthy


@dataclass
class Run:
    found: bool
    states: list
    fault_windows: int
    track_p95: float | None = None


def run(signal: Signal, level: float, profile_name: str, mode: str) -> Run:
    """One decision of ``signal`` at ``level`` dB along ``profile_name`` in ``mode``."""
    x, fs, w, rpm, tolerance, source = signal.at(level, profile_name)
    rec = Recording(x, fs, rpm, source, None, "accel", signal.name, rpm_tolerance=tolerance)
    p95 = None
    if mode == "tachometer":
        rec.set_shaft_speed(w, "tachometer")
    elif mode == "tacho-less":
        if profile_name == "const":
            track = track_speed(x, fs, 0.95 * rpm, 1.05 * rpm)
        else:
            track = track_speed(x, fs, *search_range(rpm, profile_name), max_rate=rate_limit(profile_name))
        p95 = float(np.percentile(errors(track.speed, w, fs), 95))
        if track.unsupported() is not None:  # not decided on, as bearing-diagnose --track-speed
            return Run(False, [FaultState.UNKNOWN], 0, p95)
        rec.set_shaft_speed(track.speed, "tracked")
    model_set = "none" if not signal.warped else None
    res = diagnose_recording(rec, model_set=model_set, bearing=signal.bearing)
    states = [s.state for s in res.segments]
    wrong = WRONG - {signal.truth}
    found = signal.truth in states and not wrong & set(states)
    return Run(found, states, sum(d.diagnosed and d.label in WRONG for d in res.decisions), p95)


def constant_limit(signal: Signal) -> float | None:
    """The lowest level (dB) at which the constant-speed decision finds ``signal`` at constant speed."""
    if signal.recorded_only:
        return 0.0 if run(signal, 0.0, "const", "constant").found else None
    best, level = None, 0.0
    while level >= FLOOR_DB and run(signal, level, "const", "constant").found:
        best, level = level, level - STEP_DB
    return best


def ramp_result(signal: Signal, limit: float | None, profile_name: str, mode: str) -> tuple[str, float | None]:
    """(the first level found among L, L + 3 dB and 0 dB, relative to L; the tracker's p95 error there)."""
    fixed = limit is None or signal.recorded_only
    tried = [0.0] if fixed else sorted({limit, min(0.0, limit + STEP_DB), 0.0})
    p95 = None
    for level in tried:
        r = run(signal, level, profile_name, mode)
        p95 = r.track_p95
        if r.found:
            return ("0 dB" if fixed or level not in (limit, limit + STEP_DB)
                    else "0" if level == limit else f"+{STEP_DB:.0f}"), p95
    return "—", p95


def report(faults, healthy, profiles, log) -> tuple[str, dict]:
    """(the markdown report, {mode: {ramp %: [found within 3 dB, tried]}})."""
    out = ["# Accuracy under changing speed", "",
           "Detection (rows: signal and profile; per mode the first level found relative to the constant-speed "
           "limit L: `0` as low as at constant speed, `+3` within 3 dB, `0 dB` only at the recorded level, `—` not "
           "found; tacho-less: the tracker's 95th-percentile speed error in brackets). **Warped development "
           "recordings (marked ⧖): unlike a real ramp, their resonances move with the speed too.**", "",
           "| signal | L (dB) | profile | " + " | ".join(MODES) + " |", "|---|---|---|" + "---|" * len(MODES)]
    tally = {m: {k: [0, 0] for k in ("10", "20", "40")} for m in MODES}
    for s in faults:
        t0 = time.time()
        limit = constant_limit(s)
        for p in profiles:
            if p == "const":
                continue
            cells = []
            for m in MODES:
                cell, p95 = ramp_result(s, limit, p, m)
                key = p.lstrip("updown")
                tally[m][key][1] += 1
                tally[m][key][0] += cell in ("0", "+3") or (cell == "0 dB" and s.recorded_only)
                cells.append(cell + (f" ({100 * p95:.2g} %)" if p95 is not None else ""))
            mark = " ⧖" if s.warped else ""
            out.append(f"| {s.name}{mark} | {'—' if limit is None else f'{limit:.0f}'} | {p} | " + " | ".join(cells)
                       + " |")
        log(f"speed_accuracy: {s.name} in {time.time() - t0:.0f} s")
    out += ["", "Found within 3 dB of the constant-speed limit (signals found / tried):", "",
            "| mode | ±10 % | ±20 % | ±40 % |", "|---|---|---|---|"]
    for m in MODES:
        out.append(f"| {m} | " + " | ".join(f"{a}/{b}" if b else "—" for a, b in tally[m].values()) + " |")
    out += ["", "False alarms on healthy records (published fault segments / windows labelled a fault):", "",
            "| signal | profile | " + " | ".join(MODES) + " |", "|---|---|" + "---|" * len(MODES)]
    total = dict.fromkeys(MODES, 0)
    for s in healthy:
        t0 = time.time()
        for p in profiles:
            cells = []
            for m in MODES:
                r = run(s, 0.0, p, m)
                alarms = sum(st in WRONG for st in r.states)
                total[m] += alarms
                cells.append(f"{alarms} / {r.fault_windows}")
            out.append(f"| {s.name}{' ⧖' if s.warped else ''} | {p} | " + " | ".join(cells) + " |")
        log(f"speed_accuracy: {s.name} in {time.time() - t0:.0f} s")
    out += ["", "Published false alarms in all: " + ", ".join(f"{m} {n}" for m, n in total.items()) + "."]
    return "\n".join(out) + "\n", tally


def figure(tally: dict, path: pathlib.Path) -> None:
    """Share of fault signals found within 3 dB of their constant-speed limit, per ramp and mode."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ramps = [k for k in ("10", "20", "40") if any(tally[m][k][1] for m in MODES)]
    fig, ax = plt.subplots(figsize=(6.0, 3.2))
    for i, m in enumerate(MODES):
        share = [tally[m][k][0] / tally[m][k][1] for k in ramps]
        ax.bar(np.arange(len(ramps)) + (i - 1) * 0.27, share, 0.27, label=m)
    ax.set_xticks(np.arange(len(ramps)), [f"±{k} % over 10 s" for k in ramps])
    ax.set_ylabel("found within 3 dB of constant speed")
    ax.set_ylim(0, 1.05)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="speed_accuracy", description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out/speed_accuracy.md"))
    ap.add_argument("--quick", action="store_true", help="fewer signals, the +20 %% and -40 %% ramps only")
    ap.add_argument("--figure", type=pathlib.Path, help="also draw the found shares per ramp and mode (PNG)")
    add_docs_option(ap, "docs/changing-speed.md")
    args = ap.parse_args(argv)
    t0 = time.time()
    faults, healthy = signals(args.quick)

    def log(text):
        print(text, file=sys.stderr, flush=True)
    try:
        text, tally = report(faults, healthy, QUICK_PROFILES if args.quick else PROFILES, log)
    except InputError as exc:
        print(f"speed_accuracy: {exc}", file=sys.stderr)
        return 1
    text += f"\n{'Quick subset; ' if args.quick else ''}run time {time.time() - t0:.0f} s (one process).\n"
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text, encoding="utf-8")
    if args.figure:
        figure(tally, args.figure)
    print(text)
    if args.docs:
        write_block(args.docs, "speed-accuracy", nested(text, 2), "make speed-accuracy")
    return 0


if __name__ == "__main__":
    sys.exit(main())
