"""Benchmarks of the diagnoser: rows of (figure, value, unit).

* :func:`detection_delays` — per thesis case (simulator, 0.2 s segments): delay of each
  correct detection after the true change, in seconds and in fault periods.
* :func:`false_alarm_rate` — false alarms per hour on a noise-only stream (white noise,
  or the simulator's NORMAL state with sensor noise).
* :func:`throughput` — diagnoser CPU time per second of signal, as a multiple of real time
  (start-up included).
* :func:`steady_state_throughput` — observers + decision on one motor, and the decision
  alone, in steady state (start-up excluded).
* :func:`block_contributions` — per-window accuracy of each decision block alone
  (thesis-literal cross-correlation, CFAR periodicity, model-explains, all together).

``python -m benchmarks.diag_benchmarks`` prints the rows.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from bearing_common.bearings import CATALOG, fault_frequency
from bearing_common.states import FaultState
from bearing_diagnoser.diagnoser import STREAMS, Diagnoser
from bearing_diagnoser.front_ends import config_for
from bearing_diagnoser.recording_diagnosis import diagnose_measurement, diagnose_recording
from bearing_diagnoser.warm_up import warm_up
from bearing_observer.model_sets import NONE
from bearing_recordings.recording import Recording

from .evaluation import THESIS_CASES, score_case, simulate_case

N, O = FaultState.NORMAL, FaultState.OUTER_RACE
BEARING = CATALOG["6205"]
HYPOTHESES = STREAMS


def detection_delays(noise_density: float = 4.5e-3, rpm: float = 1800.0, method: str = "model",
                     cases=None) -> list[tuple[str, float, str]]:
    """Rows (figure, value, unit): delay after each true change, per case."""
    rows = []
    for name in cases or THESIS_CASES:
        rec = simulate_case(name, rpm, noise_density)
        res = diagnose_recording(rec, method=method)
        for r in score_case(res.segments, rec.truth, rec.sample_rate):
            tag = f"{method} {name} {r['state']}@{r['start']:.1f}s"
            if not r["detected"]:
                rows.append((f"delay {tag}", float("nan"), "s (MISSED)"))
                continue
            st = FaultState[r["state"].upper()]
            period = 1.0 / fault_frequency(BEARING, st, rpm) if st in HYPOTHESES else \
                1.0 / fault_frequency(BEARING, O, rpm)
            rows.append((f"delay {tag}", round(r["delay"], 4), "s"))
            rows.append((f"delay {tag}", round(r["delay"] / period, 2),
                         "fault periods" if st in HYPOTHESES else "BPFO periods"))
    return rows


def false_alarm_rate(duration_s: float = 60.0, model_set: str = "sim_48k", fs: float = 48000.0,
                     rpm: float = 1800.0, density: float = 4.5e-3, seed: int = 7) -> list[tuple[str, float, str]]:
    """Rows: window-level and state-level false alarms per hour on white noise.

    A state-level false alarm is a published change away from NORMAL.
    """
    rng = np.random.default_rng(seed)
    y = density * np.sqrt(fs / 2) * rng.standard_normal(int(duration_s * fs))
    segs, dec = diagnose_measurement(y, fs, rpm, model_set)
    n_win = len(dec)
    bad_win = sum(d.label != N for d in dec)
    alarms = sum(d.changed and d.state != N for d in dec)
    per_h = 3600.0 / duration_s
    return [(f"false alarms ({model_set}, white noise, {duration_s:g} s)", alarms * per_h, "per hour"),
            (f"windows not NORMAL ({model_set}, white noise)", bad_win / max(n_win, 1), "fraction"),
            (f"windows evaluated ({model_set})", n_win, "windows")]


def throughput(duration_s: float = 2.0, model_set: str = "sim_48k", fs: float = 48000.0,
               with_observers: bool = True) -> list[tuple[str, float, str]]:
    """Rows: diagnoser speed as a multiple of real time (decision alone, and with observers)."""
    rng = np.random.default_rng(3)
    y = 0.7 * rng.standard_normal(int(duration_s * fs))
    dg = Diagnoser(config_for(model_set), model_set, BEARING, fs)
    dg.tell_speed(1800.0)
    dg.warm_up()  # calibration is a one-off, not part of the running cost
    warm_up()
    rows = []
    ff = {h: fault_frequency(BEARING, h, 1800.0) for h in HYPOTHESES}
    chunk = int(0.01 * fs)
    t0 = time.process_time()
    for i in range(0, y.size, chunk):
        for h in HYPOTHESES:
            part = y[i:i + chunk]
            dg.update(h, i, fs, part, np.zeros(part.size), np.zeros(part.size), ff[h])
    cpu = time.process_time() - t0
    rows.append((f"decision throughput ({model_set}, {fs / 1000:g} kHz)", round(duration_s / cpu, 1), "x real time"))
    if with_observers:
        rec = Recording(y, fs, 1800.0, "simulator")
        res = diagnose_recording(rec, model_set=model_set)
        rows.append((f"observers + decision throughput ({model_set}, {fs / 1000:g} kHz)",
                     round(duration_s / res.cpu_s, 1), "x real time"))
    return rows


def steady_state_throughput(model_set: str = "sim_48k", fs: float = 48000.0, seconds: float = 3.0,
                            repeats: int = 3, record=None) -> list[tuple[str, float, str]]:
    """Rows: observers + decision on one motor, and the decision alone, in steady state (x real time).

    The input is ``record`` (a :class:`Recording`; default: 1 + ``seconds`` s of the
    simulator's outer-race fault at 1800 rpm with sensor noise), fed in 0.01 s chunks as
    the live graph does: through the OR and IR observers of ``model_set`` into the
    diagnoser; with model set ``none`` the observers pass the measurement through (they
    cost nothing) and both streams carry it. Start-up is not timed: building the
    observers and the diagnoser, the calibration and the warm-up of p-value tables and
    kernels, and the first second of signal (first windows, folding tables, band choice).
    Each repeat starts afresh; CPU time of this process (``time.process_time``), one BLAS
    thread. Values are the best repeat, the unit gives the range over the repeats; the
    decision alone (its share of the same run) only where observers run.
    """
    from bearing_observer.observer import FaultObserver
    rec = record or simulate_case("or", 1800.0, 4.5e-3, segment_s=0.5 * (1.0 + seconds), sample_rate=fs)
    x = rec.accel
    warm = int(fs)
    chunk = int(round(0.01 * fs))
    ff = {h: fault_frequency(BEARING, h, 1800.0) for h in HYPOTHESES}
    warm_up()
    total, decision = [], []
    for _ in range(repeats):
        dg = Diagnoser(config_for(model_set), model_set, BEARING, fs)
        dg.tell_speed(1800.0)
        obs = {h: FaultObserver.from_model_set(model_set, h.label, 1800.0, fs) for h in HYPOTHESES} \
            if model_set != NONE else {}
        cpu_obs = 0.0
        start = time.process_time()
        for i in range(0, x.size - chunk + 1, chunk):
            if i == warm:
                cpu_obs, start = 0.0, time.process_time()
            y = x[i:i + chunk]
            for h in HYPOTHESES:
                if obs:
                    t0 = time.process_time()
                    out = obs[h].process(y)
                    cpu_obs += time.process_time() - t0
                    dg.update(h, i, fs, out.residual, out.estimate, out.impulse_train, obs[h].fault_frequency)
                else:
                    dg.update(h, i, fs, y, None, None, ff[h])
        cpu = time.process_time() - start
        timed = (x.size - warm) // chunk * chunk / fs
        total.append(timed / cpu)
        decision.append(timed / (cpu - cpu_obs))
    tag = f"one motor, {fs / 1000:g} kHz, steady state ({model_set})"
    unit = "x real time (best of {n}; range {lo:.0f}-{hi:.0f})"
    rows = [(f"observers + decision, {tag}", round(max(total), 1),
             unit.format(n=repeats, lo=min(total), hi=max(total)))]
    if obs:
        rows.append((f"decision alone, {tag}", round(max(decision), 1),
                     unit.format(n=repeats, lo=min(decision), hi=max(decision))))
    return rows


def block_contributions(noise_density: float = 4.5e-3, rpm: float = 1800.0, xcorr_threshold: float = 0.1,
                        explained_threshold: float = 0.3, cases=None) -> list[tuple[str, float, str]]:
    """Rows: fraction of windows labelled correctly by each block alone (model method).

    Windows entirely inside one true segment only.  Blocks: thesis-literal zero-lag
    correlation of |r| with u (fixed threshold ``xcorr_threshold``, argmax); the
    model-explains fraction alone (argmax if above ``explained_threshold``); the CFAR
    periodicity alone (no explain-away, no model); the CFAR periodicity with explain-away
    on the measurement alone (no observer); and the full decision.
    """
    counts = {k: [0, 0] for k in ("thesis xcorr", "model explains", "CFAR only", "CFAR + explain-away (no model)",
                                  "full decision")}
    normal_flag = {k: [0, 0] for k in counts}
    for name in cases or THESIS_CASES:
        rec = simulate_case(name, rpm, noise_density)
        full = diagnose_recording(rec)
        base = config_for(full.model_set)
        cfar_cfg = replace(base, front_end=replace(base.front_end, explain_away=False, explained_margin=10.0))
        cfar = diagnose_recording(rec, config=cfar_cfg)
        _, nomodel = diagnose_measurement(rec.accel, rec.sample_rate, rpm, full.model_set)
        fs = full.sample_rate
        for d_full, d_cfar, d_nm in zip(full.decisions, cfar.decisions, nomodel):
            a, b = int(d_full.window_start * fs), int(d_full.window_end * fs)
            seg = rec.truth[a:b]
            if seg.size == 0 or np.any(seg != seg[0]):
                continue
            truth = FaultState(int(seg[0]))
            sc = d_full.scores
            xc = {h: sc.xcorr.get(h, 0.0) for h in HYPOTHESES}
            ex = {h: sc.explained.get(h, 0.0) for h in HYPOTHESES}
            hx = max(xc, key=xc.get)
            he = max(ex, key=ex.get)
            labels = {"thesis xcorr": hx if xc[hx] > xcorr_threshold else N,
                      "model explains": he if ex[he] > explained_threshold else N,
                      "CFAR only": d_cfar.label, "CFAR + explain-away (no model)": d_nm.label,
                      "full decision": d_full.label}
            for k, lab in labels.items():
                counts[k][0] += int(lab == truth)
                counts[k][1] += 1
                if truth == N:
                    normal_flag[k][0] += int(lab != N)
                    normal_flag[k][1] += 1
    rows = []
    for k, (ok, n) in counts.items():
        rows.append((f"windows correct: {k}", round(ok / max(n, 1), 3), f"fraction of {n}"))
    for k, (bad, n) in normal_flag.items():
        rows.append((f"NORMAL windows flagged: {k}", round(bad / max(n, 1), 3), f"fraction of {n}"))
    return rows


def bench_diagnoser_throughput():
    return throughput() + throughput(model_set="none", with_observers=False) + \
        throughput(model_set="none", fs=12000.0, with_observers=False)


def bench_steady_state_throughput():
    """Observers + decision, one motor, steady state: both front ends at 48 kHz and 12 kHz."""
    rows = []
    for fs, sim_set in ((48000.0, "sim_48k"), (12000.0, "sim_12k")):
        rec = simulate_case("or", 1800.0, 4.5e-3, segment_s=2.0, sample_rate=fs)
        rows += steady_state_throughput(sim_set, fs, record=rec) + steady_state_throughput(NONE, fs, record=rec)
    return rows


def bench_false_alarms():
    return false_alarm_rate(duration_s=600.0) + false_alarm_rate(duration_s=600.0, model_set="none",
                                                                 fs=12000.0, rpm=1797.0)


def bench_detection_delays():
    return detection_delays()


def bench_block_contributions():
    return block_contributions()


def main(argv=None) -> int:
    """Print all benchmark rows as tab-separated text."""
    rows = bench_diagnoser_throughput() + bench_steady_state_throughput() + bench_false_alarms() + \
        bench_detection_delays() + bench_block_contributions()
    for fig, val, unit in rows:
        print(f"{fig}\t{val}\t{unit}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
