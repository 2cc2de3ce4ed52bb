"""Tables a benchmark writes into the documentation, between markers, so that no table there is copied by hand.

A docs file holds, for each block a benchmark owns::

    <!-- begin generated: NAME (by make TARGET; do not edit by hand) -->
    ...the table...
    <!-- end generated: NAME -->

and the benchmark, given ``--docs FILE`` (the Makefile passes it), replaces what lies between
them with what it measured, stamped with the date of the run. :func:`write_block` refuses a
file without the block's markers (a renamed or deleted block is a mistake to see, not to
paper over).
"""

from __future__ import annotations

import datetime
import pathlib
import re


def markers(name: str) -> tuple[re.Pattern, str]:
    """The begin marker's pattern and the end marker of block ``name``."""
    return re.compile(rf"<!-- begin generated: {re.escape(name)} \(.*?\) -->\n"), f"<!-- end generated: {name} -->"


def write_block(doc, name: str, markdown: str, source: str) -> None:
    """Put ``markdown`` (with a line naming ``source`` and today's date) between block ``name``'s markers in
    ``doc``; ValueError when the markers are missing."""
    path = pathlib.Path(doc)
    text = path.read_text(encoding="utf-8")
    begin, end = markers(name)
    found = begin.search(text)
    stop = text.find(end, found.end()) if found else -1
    if stop < 0:
        raise ValueError(f"{path}: no block '{name}' (markers '<!-- begin generated: {name} (...) -->' and "
                         f"'{end}')")
    stamp = f"*Written by `{source}` on {datetime.date.today().isoformat()}.*\n\n"
    path.write_text(text[:found.end()] + stamp + markdown.strip("\n") + "\n" + text[stop:], encoding="utf-8")


def read_block(doc, name: str) -> str:
    """What block ``name`` of ``doc`` holds now ("" when it is missing)."""
    text = pathlib.Path(doc).read_text(encoding="utf-8")
    begin, end = markers(name)
    found = begin.search(text)
    stop = text.find(end, found.end()) if found else -1
    return text[found.end():stop] if stop >= 0 else ""


def nested(markdown: str, depth: int = 1) -> str:
    """``markdown`` without its title line (``# ...``), its other headings ``depth`` levels deeper: a
    report's sections as subsections of the docs section that holds the block."""
    lines = markdown.strip("\n").split("\n")
    if lines and lines[0].startswith("# "):
        lines = lines[1:]
    out, fence = [], False
    for line in lines:
        fence ^= line.startswith("```")
        out.append("#" * depth + line if not fence and line.startswith("#") else line)
    return "\n".join(out).strip("\n")


def add_docs_option(parser, default_doc: str) -> None:
    """``--docs FILE``: also write the tables into FILE's generated blocks (``make`` passes it)."""
    parser.add_argument("--docs", type=pathlib.Path, default=None, metavar="FILE",
                        help=f"also write the tables into FILE's generated blocks (make passes {default_doc})")
