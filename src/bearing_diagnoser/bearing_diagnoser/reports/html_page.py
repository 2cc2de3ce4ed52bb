"""A self-contained HTML page: inline CSS, figures as inline SVG, no script and no external asset.

One page is one file a user can mail or archive: it opens offline in any browser. Figures are
matplotlib figures written as SVG with the text kept as text (``svg.fonttype`` none: the
browser's sans-serif draws it) and dense traces rasterised inside the SVG (a data: URI), so
that a page of a long recording stays small.
"""

from __future__ import annotations

import html
import io
from pathlib import Path

#: Colour of each state's badge (fault states, health states).
STATE_COLOURS = {"normal": "#2e7d32", "healthy": "#2e7d32", "outer_race": "#1565c0", "inner_race": "#c62828",
                 "ball": "#6a1b9a", "unknown": "#ef6c00", "warning": "#f9a825", "alarm": "#c62828"}

_STYLE = """
body { font-family: sans-serif; max-width: 1100px; margin: 1.5em auto; padding: 0 1em; color: #222; }
h1 { font-size: 1.4em; margin-bottom: 0.2em; word-break: break-all; }
h2 { font-size: 1.1em; margin-top: 1.6em; border-bottom: 1px solid #ccc; }
.verdict { display: inline-block; color: #fff; padding: 0.3em 0.8em; border-radius: 0.3em; font-weight: bold;
           font-size: 1.2em; }
table { border-collapse: collapse; margin: 0.5em 0; }
td, th { border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: left; font-size: 0.9em; }
th { background: #f3f3f3; }
pre { background: #f7f7f7; padding: 0.8em; white-space: pre-wrap; font-size: 0.85em; }
figure { margin: 1em 0; }
figure svg { max-width: 100%; height: auto; }
figcaption { font-size: 0.85em; color: #555; }
"""


def esc(text) -> str:
    """``text`` escaped for HTML."""
    return html.escape(str(text))


def badge(state: str, text: str) -> str:
    """A coloured label for a state."""
    return f'<span class="verdict" style="background:{STATE_COLOURS.get(state, "#555")}">{esc(text)}</span>'


def table(header: list[str], rows: list[list]) -> str:
    """An HTML table of ``rows`` (cells escaped)."""
    head = "".join(f"<th>{esc(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{esc(c)}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def svg_figure(fig, caption: str, name: str) -> str:
    """A matplotlib figure as an inline ``<figure>`` (SVG, text kept as text); closes the figure.
    ``name`` marks it (``data-figure``) for readers and tests."""
    import matplotlib

    from ..plots import pyplot

    buf = io.StringIO()
    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": name}):
        fig.savefig(buf, format="svg", bbox_inches="tight")
    pyplot().close(fig)
    text = buf.getvalue()
    svg = text[text.index("<svg"):]
    return f'<figure data-figure="{esc(name)}">{svg}<figcaption>{esc(caption)}</figcaption></figure>'


def page(title: str, body: list[str]) -> str:
    """The whole page."""
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{esc(title)}</title><style>{_STYLE}</style></head>\n<body>\n" + "\n".join(body)
            + "\n</body></html>\n")


def write_page(path, title: str, body: list[str]) -> Path:
    """Write the page to ``path`` (its folder made if missing); returns the path."""
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(page(title, body), encoding="utf-8")
    return out
