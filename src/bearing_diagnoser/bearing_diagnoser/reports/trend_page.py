"""``bearing-trend --report DIR``: one self-contained HTML page per machine's life (PATH).

The page holds the condition state and its summary in words (:mod:`.terminal_text`), the
trended indicators over the life with the baseline, the limits and the states
(:func:`bearing_diagnoser.health.trend_plot.trend_figure`), a table of the state changes
and of the last snapshot's indicators against the baseline, and the summary line as JSON.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..health.trend_plot import trend_figure
from .html_page import badge, esc, svg_figure, table, write_page
from .terminal_text import INDICATOR_WORDS, duration, trend_text


def write_trend_page(path: str, records: list, monitor, summary: dict, out_path) -> Path:
    """Write the page of PATH ``path`` (its :class:`~bearing_diagnoser.health.monitor.HealthRecord` s
    ``records``, the monitor that scored them and its summary line) to ``out_path``."""
    lines = [r.to_json() for r in records]
    name = Path(path).name or str(path)
    state = summary["state"]
    body = [f"<h1>{esc(name)}: condition over its life</h1>",
            f"<p>{badge(state, state.upper())} since {esc(duration(summary['since']))}; "
            f"{summary['snapshots']} snapshots over {esc(duration(summary.get('end', 0.0)))}</p>",
            "<h2>Summary</h2>", f"<pre>{esc(trend_text(path, lines, summary))}</pre>"]
    body += ["<h2>Indicators</h2>",
             svg_figure(trend_figure(records, monitor, path),
                        "The trended indicators per snapshot (grey), smoothed (black), the baseline period (shaded), "
                        "its level and the warning and alarm limits; the top strip is the state over time.",
                        "indicators")]
    last = lines[-1]
    rows = []
    for key, (word, json_key, unit) in INDICATOR_WORDS.items():
        level = last["trend"].get("level", {}).get(key)
        value = last["indicators"].get(json_key)
        rows.append([word, "-" if value is None else f"{value:.4g} {unit}".strip(),
                     "-" if level is None else f"{level:.2f}"])
    body += ["<h2>Last snapshot</h2>", table(["indicator", "value", "smoothed level (× baseline)"], rows)]
    changes = [[duration(r["t"]), r["state"], r["trend"].get("moved") or "-"]
               for prev, r in zip(lines, lines[1:]) if r["state"] != prev["state"]]
    body += ["<h2>State changes</h2>",
             table(["time", "new state", "indicator that moved most"], changes) if changes else "<p>None.</p>",
             "<h2>Summary line</h2>", "<details><summary>as bearing-trend --json prints it</summary>"
             f"<pre>{esc(json.dumps({'summary': summary}))}</pre></details>"]
    return write_page(out_path, f"{name}: condition trend", body)
