"""The spectral decision's cost per second of signal, as a ratio to the textbook SES on the same signal; where it goes.

Per rate (12 and 48 kHz: the CWRU records of ``shared_data.yaml`` at that rate, 097 decimated to
12 kHz as the manifest gives it), in one run, record by record:

* the decision: :func:`~bearing_diagnoser.recording_diagnosis.diagnose_recording` with model set
  ``none`` (the spectral decision on the measurement, as for a real sensor: no observers), the
  speed and bearing as the manifest states them, 0.01 s chunks (the simulator's, the finest a live
  graph runs); and the same at the offline chunk (``bearing-diagnose``'s:
  :data:`~bearing_diagnoser.recording_diagnosis.OFFLINE_CHUNK_S`, the same decisions);
* the reference: :func:`benchmarks.textbook_ses.textbook_ses` on the same samples (the mean of
  :data:`SES_REPEATS` runs: it is short);
* CPU time of this process (``time.process_time``, one BLAS thread), after the decision's warm-up
  (:func:`bearing_diagnoser.warm_up.warm_up`: numba kernels, p-value tables) and one run.

Rows: CPU seconds per second of signal of each, their ratio (the decision's over the SES's), and,
from a profile (cProfile) of the decision on the record of each rate it spent the most CPU on per
second, the share of the
decision's time per part (:data:`PARTS`: a function's own time counts for the part of the module
it is in; NumPy's, SciPy's and the standard library's for the parts of their callers, in
proportion to the time each caller spent in them). cProfile's overhead falls on Python calls, so
the shares weigh the parts made of many small calls somewhat high.

``python -m benchmarks.decision_cost`` prints the rows.
"""

from __future__ import annotations

import cProfile
import pathlib
import pstats
import time
from collections import defaultdict

from bearing_common.bearings import load_bearing
from bearing_diagnoser.accuracy import load_manifest
from bearing_diagnoser.recording_diagnosis import CHUNK_S, OFFLINE_CHUNK_S, diagnose_recording
from bearing_diagnoser.warm_up import warm_up

from .textbook_ses import textbook_ses

MANIFEST = pathlib.Path(__file__).resolve().parent / "shared_data.yaml"
RATES = (12000.0, 48000.0)
SES_REPEATS = 3

#: The decision's parts: (name, paths of the modules whose own time is the part's).
PARTS = (
    ("envelope spectra and band choice", ("spectral/envelope_spectrum.py", "spectral/envelope_view.py",
                                          "spectral/band_choice.py")),
    ("comb search (term bins, sums, best scale)", ("spectral/fault_combs.py",)),
    ("significance (Gamma-tail p-values)", ("spectral/significance.py", "spectral/gamma_tail.py")),
    ("long-horizon accumulation", ("spectral/accumulation.py",)),
    ("distinct evidence (series, explain-away)", ("spectral/distinct_evidence.py",)),
    ("shaft speed and machine reference", ("spectral/shaft_speed.py", "spectral/machine_reference.py")),
    ("windows, verdicts and front end", ("spectral/evidence_stream.py", "spectral/front_end.py",
                                         "spectral/window_label.py", "spectral/settings.py")),
    ("condition indicators (health)", ("bearing_diagnoser/health/",)),
    ("sessions, states and chunk checks", ("bearing_diagnoser/decision/", "bearing_diagnoser/diagnoser",
                                           "bearing_diagnoser/pipeline.py", "bearing_common/",
                                           "bearing_observer/")),
)
OTHER = "other (recording set-up, segments)"


def _records(rate: float) -> list:
    """(name, recording, bearing) of the CWRU records of the manifest at ``rate``."""
    out = []
    for entry in load_manifest(MANIFEST):
        if entry.dataset.startswith("CWRU"):
            rec = entry.load()
            if rec.sample_rate == rate:
                out.append((entry.name, rec, load_bearing(entry.bearing)))
    return out


def _decide(rec, bearing, chunk_s=CHUNK_S):
    return diagnose_recording(rec, model_set="none", rpm=rec.rpm, bearing=bearing, chunk_s=chunk_s)


def _part(path: str) -> str | None:
    return next((name for name, paths in PARTS if any(p in path for p in paths)), None)


def time_shares(stats: pstats.Stats) -> dict:
    """{part: its share of the profiled time}: own time by module, library time for its callers' parts."""
    raw = stats.stats
    memo: dict = {}

    def owners(func, depth=0) -> dict:
        if func in memo:
            return memo[func]
        part = _part(func[0])
        if part is not None:
            memo[func] = {part: 1.0}
            return memo[func]
        callers = raw[func][4]
        total = sum(c[3] for c in callers.values())
        if depth > 40 or not callers or total <= 0:
            return {OTHER: 1.0}
        out: dict = defaultdict(float)
        memo[func] = {OTHER: 1.0}  # a recursion guard while the callers are read
        for caller, c in callers.items():
            if caller in raw:
                for p, w in owners(caller, depth + 1).items():
                    out[p] += w * c[3] / total
        memo[func] = dict(out) or {OTHER: 1.0}
        return memo[func]

    shares: dict = defaultdict(float)
    for func, (_, _, own, _, _) in raw.items():
        for p, w in owners(func).items():
            shares[p] += own * w
    total = sum(shares.values())
    return {p: v / total for p, v in shares.items()}


def decision_cost(rate: float) -> list[tuple[str, float, str]]:
    """Rows for the CWRU records at ``rate`` (module docstring)."""
    records = _records(rate)
    tag = f"{rate / 1000:g} kHz, {len(records)} CWRU records"
    warm_up()  # compile / load the kernels, tabulate the p-values
    _decide(records[0][1], records[0][2])
    seconds = decision = offline = ses = 0.0
    costliest = (0.0, records[0])
    for record in records:
        _, rec, bearing = record
        seconds += rec.accel.size / rec.sample_rate
        start = time.process_time()
        _decide(rec, bearing)
        cpu = time.process_time() - start
        decision += cpu
        costliest = max(costliest, (cpu * rec.sample_rate / rec.accel.size, record), key=lambda c: c[0])
        start = time.process_time()
        _decide(rec, bearing, OFFLINE_CHUNK_S)
        offline += time.process_time() - start
        start = time.process_time()
        for _ in range(SES_REPEATS):
            textbook_ses(rec.accel, rec.sample_rate, rec.rpm, bearing)
        ses += (time.process_time() - start) / SES_REPEATS
    rows = [(f"spectral decision (model set none), {tag}, {seconds:.0f} s of signal", decision / seconds,
             "CPU s per s of signal"),
            (f"textbook SES (whole record, 3 fixed bands), same signal, {tag}", ses / seconds, "CPU s per s of signal"),
            (f"spectral decision / textbook SES, {tag}", decision / ses, "ratio (target <= 3)"),
            (f"spectral decision at the offline chunk ({OFFLINE_CHUNK_S:g} s) / textbook SES, {tag}", offline / ses,
             "ratio (target <= 3)")]
    profile = cProfile.Profile()
    name, rec, bearing = costliest[1]
    profile.runcall(_decide, rec, bearing)
    shares = time_shares(pstats.Stats(profile))
    for part, share in sorted(shares.items(), key=lambda kv: -kv[1]):
        rows.append((f"decision's time: {part}, {rate / 1000:g} kHz (record {name}, profiled)",
                     round(share, 3), "fraction"))
    return rows


def bench_decision_cost():
    """The decision against the textbook SES at 12 and 48 kHz, with its breakdown."""
    return [row for rate in RATES for row in decision_cost(rate)]


def main() -> int:
    for fig, val, unit in bench_decision_cost():
        print(f"{fig}\t{val:.4g}\t{unit}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
