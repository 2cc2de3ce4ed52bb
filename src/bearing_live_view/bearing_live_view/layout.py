"""The Foxglove layouts shipped in ``bearing_bringup/config/`` (generated here, never edited by hand).

* :func:`motor_layout` — one motor's graph (``namespace``: its topics' prefix): the decided state
  beside the simulator's truth, the decision's confidence and significances, the envelope
  spectrum with each hypothesis' line markers at the measured and the told speed, the vibration's
  min/max/RMS, the condition indicators and their trend, ``/diagnostics``;
* :func:`fleet_layout` — any number of motors: one state row per motor from ``fleet_state``, the
  fleet table, every motor's ``/diagnostics``.

Plots are timed by arrival (the live view's log time); the messages carry the data's stamps too
(``header.stamp``: a panel's timestamp method ``headerStamp`` plots by them).

    python -m bearing_live_view.layout --out src/bearing_bringup/config   # rewrite the shipped files
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys

import foxglove.layouts as fl

from bearing_common import topics
from bearing_common.states import FaultState
from bearing_diagnoser.health.trend import TRENDED

#: File names of the shipped layouts (in ``bearing_bringup/config``).
MOTOR_LAYOUT = "foxglove_motor.json"
FLEET_LAYOUT = "foxglove_fleet.json"

#: The fault hypotheses' colours, one per hypothesis in every panel.
COLOURS = {FaultState.OUTER_RACE: "#d62728", FaultState.INNER_RACE: "#1f77b4", FaultState.BALL: "#2ca02c"}
HYPOTHESES = tuple(COLOURS)


def _split(direction: str, *items) -> fl.SplitContainer:
    return fl.SplitContainer(direction=direction, items=[fl.SplitItem(proportion=p, content=c) for p, c in items])


def _plot(title: str, series: list, **config) -> fl.PlotPanel:
    return fl.PlotPanel(title=title, config=fl.PlotConfig(paths=series, show_legend=True, **config))


def motor_layout(namespace: str = "") -> fl.Layout:
    """The live view of the motor whose graph runs in ``namespace`` ("" = the root namespace)."""
    def topic(t: topics.Topic) -> str:
        return topics.qualified(namespace, t)

    state, truth, health = topic(topics.FAULT_STATE), topic(topics.TRUTH), topic(topics.HEALTH)
    spectrum, vibration = topic(topics.ENVELOPE_SPECTRUM), topic(topics.VIBRATION)
    states = fl.StateTransitionsPanel(title="fault state", config=fl.StateTransitionsConfig(paths=[
        fl.StateTransitionsSeries(value=f"{state}.state_name", label="decided"),
        fl.StateTransitionsSeries(value=f"{truth}.state_name", label="truth (simulator)")]))
    evidence = _plot("confidence and significance (>= 1: significant)", [
        fl.PlotSeries(value=f"{state}.confidence", label="confidence", color="#000000"),
        *(fl.PlotSeries(value=f"{state}.scores.{h.label}", label=h.label, color=c) for h, c in COLOURS.items())])
    lines = [fl.PlotSeries(value=f"{spectrum}.magnitude[:]", x_value_path=f"{spectrum}.frequency[:]",
                           label="spectrum (max-held)", color="#555555")]
    for h, c in COLOURS.items():
        for speed, style in (("measured", None), ("told", "dotted")):
            lines.append(fl.PlotSeries(value=f"{spectrum}.lines.{h.label}.{speed}_level[:]",
                                       x_value_path=f"{spectrum}.lines.{h.label}.{speed}[:]",
                                       label=f"{h.label} lines, {speed} speed", color=c, show_line=False,
                                       line_style=style))
    envelope = _plot("envelope spectrum (x local median) and fault lines", lines, x_axis_val="currentCustom",
                     x_axis_path=fl.PlotXAxisPath(value=f"{spectrum}.frequency[:]"), x_axis_label="Hz")
    waveform = _plot("vibration per block (m/s^2)", [
        fl.PlotSeries(value=f"{vibration}.{k}", label=k) for k in ("max", "min", "rms")])
    condition = _plot("condition: indicators / baseline", [
        fl.PlotSeries(value=f"{health}.level.{k}", label=k) for k in TRENDED])
    diagnostics = fl.DiagnosticsSummaryPanel(title="diagnostics", config=fl.DiagnosticsSummaryConfig(
        topic_to_render=topics.DIAGNOSTICS.name, sort_by_level=True))
    return fl.Layout(content=_split(
        "column",
        (1, _split("row", (1, _split("column", (1, states), (2, evidence))), (1, envelope))),
        (1, _split("row", (1, waveform), (1, condition), (1, diagnostics)))))


def fleet_layout() -> fl.Layout:
    """Every motor of a fleet at once, from ``fleet_state`` and ``/diagnostics``."""
    fleet = topics.qualified("", topics.FLEET_STATE)
    rows = fl.StateTransitionsPanel(title="fault state per motor", config=fl.StateTransitionsConfig(paths=[
        fl.StateTransitionsSeries(value=f"{fleet}.motors", dynamic_label_field="motor",
                                  dynamic_value_field="state_name", label="motor")]))
    table = fl.TablePanel(title="fleet", config=fl.TableConfig(topic_path=f"{fleet}.motors"))
    diagnostics = fl.DiagnosticsSummaryPanel(title="diagnostics", config=fl.DiagnosticsSummaryConfig(
        topic_to_render=topics.DIAGNOSTICS.name, sort_by_level=True))
    return fl.Layout(content=_split("column", (2, rows), (1, _split("row", (1, table), (1, diagnostics)))))


def layout_json(layout: fl.Layout) -> str:
    """A layout as the JSON file Foxglove imports, indented (a change reads as a diff)."""
    return json.dumps(json.loads(layout.to_json()), indent=1) + "\n"


def layouts() -> dict[str, str]:
    """{file name: JSON text} of the shipped layouts."""
    return {MOTOR_LAYOUT: layout_json(motor_layout()), FLEET_LAYOUT: layout_json(fleet_layout())}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bearing_live_view.layout", description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=pathlib.Path, required=True, help="directory to write the layouts to")
    parser.add_argument("--namespace", default="", help="the motor layout's namespace (default: root)")
    args = parser.parse_args(argv)
    files = layouts()
    if args.namespace:
        files[MOTOR_LAYOUT] = layout_json(motor_layout(args.namespace))
    for name, text in files.items():
        (args.out / name).write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
