"""The documentation: a short front page that names the two commands, a README per package, links that
resolve (files and headings), the command-line options documented, and the blocks benchmarks write."""

from __future__ import annotations

import re

import pytest
from data_paths import REPO_ROOT

from bearing_diagnoser.diagnose_cli import build_parser as diagnose_parser
from bearing_diagnoser.health.trend_cli import build_parser as trend_parser
from benchmarks.doc_tables import nested, read_block, write_block

README = REPO_ROOT / "README.md"
DOCS = sorted((REPO_ROOT / "docs").glob("*.md"))
PACKAGES = sorted(p.parent for p in (REPO_ROOT / "src").glob("*/setup.py")) + [REPO_ROOT / "msgs"]
PAGES = [README, *DOCS, *(p / "README.md" for p in PACKAGES)]

#: The front page's length, at most (issue 28: "at most about 200 lines").
FRONT_PAGE_LINES = 200


def test_the_front_page_is_short_and_gives_the_two_commands():
    text = README.read_text()
    assert len(text.splitlines()) <= FRONT_PAGE_LINES
    assert "make demo" in text and "make test" in text
    for doc in DOCS:  # every docs page is reachable from the front page
        assert f"(docs/{doc.name})" in text, doc.name


@pytest.mark.parametrize("package", PACKAGES, ids=lambda p: p.name)
def test_every_package_has_a_readme_that_names_it(package):
    readme = package / "README.md"
    assert readme.is_file()
    name = "bearing_msgs" if package.name == "msgs" else package.name
    assert readme.read_text().startswith(f"# {name}\n")


def slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def anchors(path) -> set:
    text = re.sub(r"```.*?```", "", path.read_text(), flags=re.S)
    return {slug(m) for m in re.findall(r"^#+ (.+)$", text, re.M)}


def test_slug_follows_github():
    assert slug("Live: the health topic, /diagnostics and snapshot sensors") == \
        "live-the-health-topic-diagnostics-and-snapshot-sensors"
    assert slug("Speed (`make bench`)") == "speed-make-bench"
    assert slug("bearing-trend's input") == "bearing-trends-input"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(REPO_ROOT)))
def test_every_relative_link_resolves_to_a_file_and_heading(page):
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    links = re.findall(r"\]\(([^)\s]+)\)", text)
    assert links or page.parent.name in ("bearing_common",), page
    for link in links:
        if re.match(r"[a-z]+://", link):
            continue
        target, _, anchor = link.partition("#")
        path = (page.parent / target).resolve() if target else page
        assert path.exists(), f"{page.name}: {link} (no {path})"
        if anchor:
            assert path.suffix == ".md" and anchor in anchors(path), f"{page.name}: {link} (no such heading)"


@pytest.mark.parametrize("parser", [diagnose_parser, trend_parser], ids=["bearing-diagnose", "bearing-trend"])
def test_every_option_of_the_diagnosis_tools_is_documented(parser):
    tools = (REPO_ROOT / "docs" / "tools.md").read_text()
    for action in parser()._actions:
        for option in action.option_strings:
            if option.startswith("--") and option != "--help":
                assert option in tools, option


def test_every_generated_block_is_closed_and_named_once():
    for doc in DOCS:
        text = doc.read_text()
        begins = re.findall(r"<!-- begin generated: ([\w-]+) \(by make ([\w-]+); do not edit by hand\) -->", text)
        ends = re.findall(r"<!-- end generated: ([\w-]+) -->", text)
        assert [b for b, _ in begins] == ends, doc.name
        assert len(set(ends)) == len(ends), doc.name


def test_the_makefile_targets_write_into_existing_blocks():
    """Each benchmark's ``--docs FILE`` in the Makefile names a docs file holding the blocks it writes."""
    makefile = (REPO_ROOT / "Makefile").read_text()
    targets = dict(re.findall(r"benchmarks/(\w+)\.py [^\n]*--docs (docs/[\w.]+)", makefile))
    assert set(targets) == {"run", "accuracy_report", "false_alarm_matrix", "false_alarms", "trend_report", "soak"}
    for script, doc in targets.items():
        source = (REPO_ROOT / "benchmarks" / f"{script}.py").read_text()
        names = re.findall(r'write_block\(args\.docs, "([\w-]+)"', source) + \
            re.findall(r'\("(trend-[\w]+)", \w+\)', source)
        assert names, script
        for name in names:
            assert f"<!-- begin generated: {name} (" in (REPO_ROOT / doc).read_text(), (script, name)


def test_write_block_replaces_only_its_block_and_refuses_a_missing_one(tmp_path):
    doc = tmp_path / "d.md"
    doc.write_text("# Title\n\nprose\n<!-- begin generated: t (by make x; do not edit by hand) -->\nold\n"
                   "<!-- end generated: t -->\nmore prose\n")
    write_block(doc, "t", "| a |\n|---|\n| 1 |\n", "make x")
    text = doc.read_text()
    assert text.startswith("# Title\n\nprose\n<!-- begin generated: t (")
    assert text.endswith("| a |\n|---|\n| 1 |\n<!-- end generated: t -->\nmore prose\n") and "old" not in text
    assert read_block(doc, "t").startswith("*Written by `make x` on ")
    with pytest.raises(ValueError, match="no block 'u'"):
        write_block(doc, "u", "x", "make x")


def test_a_report_nests_under_the_block_heading():
    assert nested("# Report\n\n## Part\n\n```\n# not a heading\n```\n", 2) == "#### Part\n\n```\n# not a heading\n```"
