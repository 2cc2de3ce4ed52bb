"""What ``bearing-diagnose`` and ``bearing-trend`` print on a terminal: the verdict and its evidence in words.

The same numbers as the JSON lines (which a pipe or ``--json`` gets instead), read for a
person: the state covering most of the record, when it began and was decided, with what
confidence; then per segment the evidence in physical terms — the fault lines (at which
frequencies, against the kinematic ones at the speed used), how far above the
significance threshold, the demodulation band, the shaft speed used and told.
"""

from __future__ import annotations

import math

from .diagnosis_summary import HYPOTHESES, fundamental_orders, verdict

#: How each state reads.
STATE_WORDS = {"normal": "NORMAL: no fault evidence", "outer_race": "OUTER RACE fault",
               "inner_race": "INNER RACE fault", "ball": "BALL (rolling element) fault",
               "unknown": "UNKNOWN: abnormal, but no fault explains it"}

#: How each hypothesis reads.
HYPOTHESIS_WORDS = {h.label: h.label.replace("_", " ") for h in HYPOTHESES}


def hz(value: float | None) -> str:
    """A frequency for reading: '107.3 Hz', '2.25 kHz'."""
    if value is None or not math.isfinite(value):
        return "?"
    return f"{value / 1e3:.3g} kHz" if value >= 1e3 else f"{value:.1f} Hz"


def duration(seconds: float) -> str:
    """A span of time for reading: '12.3 s', '45.0 min', '7.8 h'."""
    if seconds >= 3 * 3600:
        return f"{seconds / 3600:.1f} h"
    if seconds >= 180:
        return f"{seconds / 60:.1f} min"
    return f"{seconds:.2f} s" if seconds < 10 else f"{seconds:.1f} s"


def _rpm(speed_hz: float | None) -> str:
    return "?" if speed_hz is None else f"{speed_hz:.2f} Hz = {60 * speed_hz:.0f} rpm"


def hypothesis_lines(label: str, e: dict, orders: dict) -> list[str]:
    """One hypothesis' evidence: how far above the threshold, and where its lines were."""
    name, _order, comb = fundamental_orders(orders)[next(h for h in HYPOTHESES if h.label == label)]
    sig = e["significance"]
    head = f"{HYPOTHESIS_WORDS[label]} {sig:.2f} × the significance threshold"
    if e.get("peak") is not None and e["peak"] > sig * 1.05:
        head += f" (median over the windows; up to {e['peak']:.2f})"
    if e.get("line_hz") is not None and e.get("expected_hz"):
        rho = e["line_hz"] / e["expected_hz"]
        where = f"{name} comb at {hz(e['line_hz'])} ({rho:.4f} × the kinematic {hz(e['expected_hz'])}) {comb}"
    else:
        where = f"{name} {comb}, expected at {hz(e.get('expected_hz'))}"
    return [head + ":", "  " + where]


def segment_block(state: str, ev: dict, orders: dict, indent: str) -> list[str]:
    """The evidence of one segment in state ``state``, a line per fact."""
    label = f"{indent}{'evidence':<11}"
    pad = " " * len(label)
    out = []
    shown = [k for k, e in ev["hypotheses"].items()
             if k == state or e["significance"] >= 1.0 or state in ("normal", "unknown")]
    for k in shown:
        for line in hypothesis_lines(k, ev["hypotheses"][k], orders):
            out.append((pad if out else label) + line)
    rest = [f"{HYPOTHESIS_WORDS[k]} {e['significance']:.2f}" for k, e in ev["hypotheses"].items() if k not in shown]
    if rest:
        out.append((pad if out else label) + ", ".join(rest) + " × the threshold (≥ 1: significant)")
    if ev.get("band_hz"):
        lo, hi = ev["band_hz"]
        out.append(f"{indent}{'band':<11}{lo / 1e3:.2f}-{hi / 1e3:.2f} kHz demodulated (where the fault evidence "
                   "was strongest)")
    speed = f"{indent}{'speed':<11}{_rpm(ev.get('speed_hz'))} used"
    told = ev.get("told_speed_hz")
    if told is not None and ev.get("speed_hz") is not None:
        off = ev["speed_hz"] / told - 1
        speed += f"; told {60 * told:.0f} rpm" + (f" ({100 * off:+.2f} %: measured from the vibration)"
                                                  if abs(off) >= 5e-4 else "")
    out.append(speed)
    if not ev["windows"]:
        out.append(f"{indent}(no window of this segment was diagnosed)")
    return out


def diagnosis_text(path: str, lines: list[dict], summary: dict) -> str:
    """The terminal summary of one file's diagnosis (module docstring)."""
    rec = summary.get("record", {})
    i = verdict(lines)
    if i < 0:
        return f"{path}: no decision"
    v = lines[i]
    out = [f"{path}: {STATE_WORDS.get(v['state'], v['state'])}, confidence {v['confidence']:.2f}"]
    orders = rec.get("orders")
    evidence = summary.get("segments", [])
    if len(lines) == 1:
        out.append(f"  the whole record (0-{v['end']:.2f} s), decided {v['detected_at']:.2f} s after its start")
        if orders and evidence:
            out += segment_block(v["state"], evidence[0], orders, "  ")
    else:
        out.append(f"  the state covering most of the record; {len(lines)} segments:")
        for seg, ev in zip(lines, evidence):
            out.append(f"  {seg['start']:.2f}-{seg['end']:.2f} s: {STATE_WORDS.get(seg['state'], seg['state'])}, "
                       f"confidence {seg['confidence']:.2f}, decided at {seg['detected_at']:.2f} s")
            if orders:
                out += segment_block(seg["state"], ev, orders, "    ")
    method = "" if rec.get("method", "model") == "model" else f", method {rec['method']}"
    out.append(f"  {'record':<11}{rec.get('duration_s', 0):.2f} s at {rec.get('recorded_rate_hz', 0):g} Hz, "
               f"channel {rec.get('channel', '?')}; bearing {rec.get('bearing', '?')}; model set "
               f"{rec.get('model_set', '?')}{method}")
    if rec.get("not_diagnosed"):
        out.append(f"  {rec['not_diagnosed']} windows not diagnosed (see the warning above)")
    return "\n".join(out)


#: The trended indicators as a person reads them: (name, JSON key, unit).
INDICATOR_WORDS = {"rms": ("RMS", "rms_m_s2", "m/s²"), "kurtosis": ("kurtosis", "kurtosis", ""),
                   "envelope_rms": ("envelope RMS", "envelope_rms_m_s2", "m/s²"),
                   "velocity_rms": ("velocity RMS", "velocity_rms_mm_s", "mm/s")}


def trend_change_line(path: str, record: dict) -> str:
    """A state change of ``bearing-trend`` as it happens: '<path>: 130.0 min WARNING (kurtosis moved most)'."""
    moved = record["trend"].get("moved")
    return (f"{path}: {duration(record['t'])} {record['state'].upper()}"
            + (f" ({INDICATOR_WORDS.get(moved, (moved,))[0]} moved most)" if moved else ""))


def _evidence_words(evidence: dict | None) -> str:
    if not evidence:
        return "not computed"
    if evidence.get("problem"):
        return f"none: {evidence['problem']}"
    parts = [f"{k.replace('_', ' ')} {v:.2f}" for k, v in evidence.get("significance", {}).items()]
    parts += [f"{k.replace('_', ' ')} untested" for k in evidence.get("untested", {})]
    return (", ".join(parts) + " × the threshold (≥ 1: significant)") if parts else "none"


def trend_text(path: str, records: list[dict], summary: dict) -> str:
    """The terminal summary of one PATH's life (``records``: the JSON lines of its snapshots)."""
    if not records:
        return f"{path}: no snapshot"
    last, end = records[-1], summary.get("end", records[-1]["t"])
    out = [f"{path}: {summary['state'].upper()} since {duration(summary['since'])} ({summary['snapshots']} "
           f"snapshots over {duration(end)})"]
    for key, word in (("first_warning", "first warning"), ("first_alarm", "first alarm")):
        t = summary.get(key)
        out.append(f"  {word:<15} " + ("none" if t is None else
                                       f"{duration(t)} ({duration(end - t)} before the last snapshot)"))
    level = last["trend"].get("level", {})
    parts = []
    for name, (word, key, unit) in INDICATOR_WORDS.items():
        value = last["indicators"].get(key)
        if value is None:
            continue
        text = f"{word} {value:.3g}{' ' + unit if unit else ''}"
        if level.get(name) is not None:
            text += f" ({level[name]:.2f})"
        parts.append(text)
    zone = last.get("iso_zone")
    out.append(f"  {'last snapshot':<15} " + ", ".join(parts) + (" (smoothed level ÷ baseline)" if level else ""))
    if zone:
        out.append(f"  {'ISO 20816-3':<15} zone {zone} ({summary.get('machine_class', '')}) by the velocity RMS")
    moved = last["trend"].get("moved")
    if moved:
        slope = last["trend"].get("slope_per_h", {}).get(moved)
        out.append(f"  {'moved most':<15} {INDICATOR_WORDS.get(moved, (moved,))[0]}"
                   + ("" if slope is None else f", {100 * slope:+.0f} % per hour over the recent snapshots"))
    b = summary.get("baseline")
    out.append(f"  {'baseline':<15} " + ("never completed: every state is healthy by assumption" if b is None else
                                         f"the first {b['snapshots']} snapshots (to {duration(b['end'])}), one every "
                                         f"{duration(b['interval'])}; at most {summary['false_warnings_per_day']:g} "
                                         f"false warnings and {summary['false_alarms_per_day']:g} false alarms a day"))
    out.append(f"  {'fault evidence':<15} (last snapshot) {_evidence_words(last.get('evidence'))}")
    changes = [r for prev, r in zip(records, records[1:]) if r["state"] != prev["state"]]
    if changes:
        shown = ", ".join(f"{duration(r['t'])} {r['state']}" for r in changes[:12])
        out.append(f"  {'state changes':<15} {shown}" + (f", ... ({len(changes)} in all)" if len(changes) > 12 else ""))
    if summary.get("damaged"):
        out.append(f"  {summary['damaged']} damaged snapshot(s) skipped")
    return "\n".join(out)
