"""What a person reads: the terminal summaries of ``bearing-diagnose`` and ``bearing-trend`` (the JSON lines
unchanged with ``--json`` and in pipes), the evidence in physical terms (exact on constructed windows), the
envelope spectrum a report shows (analytic input), and the HTML pages: self-contained, with their figures,
rendered by a headless browser when one is installed."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from types import SimpleNamespace

import numpy as np
import pytest
from test_trend_cli import degrading_folder

from bearing_common.bearings import CATALOG
from bearing_diagnoser.diagnose_cli import main as diagnose
from bearing_diagnoser.health.trend_cli import main as trend
from bearing_diagnoser.reports.diagnosis_summary import bearing_orders, members, segment_evidence, verdict
from bearing_diagnoser.reports.envelope_view import envelope_view, fault_markers
from bearing_diagnoser.synthetic import burst_train, white_noise

FS = 12000.0
RPM = 1800.0
ORDERS = bearing_orders(CATALOG["6205"])
BPFO = ORDERS["bpfo"] * RPM / 60.0  # 107.54 Hz


def _npz(path, seconds=3.0, fault_hz=BPFO, amplitude=6.0):
    y = burst_train(seconds, FS, fault_hz, amplitude=amplitude, resonance_hz=3000.0) + white_noise(seconds, FS, 4.5e-3)
    np.savez(path, accel=y, sample_rate=FS, rpm=RPM)
    return path


@pytest.fixture(scope="module")
def or_recording(tmp_path_factory):
    """3 s of outer-race bursts at 12 kHz, 1800 rpm; diagnosed with model set none (the spectral decision)."""
    return _npz(tmp_path_factory.mktemp("rec") / "or_fault.npz")


def _run(main, argv, capsys, monkeypatch, tty: bool):
    monkeypatch.setattr(sys.stdout, "isatty", lambda: tty)
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


# ---------------------------------------------------------------------------------------
# the evidence in physical terms, exact on constructed windows


def test_the_verdict_is_the_state_covering_most_of_the_record():
    seg = lambda start, end, state: {"start": start, "end": end, "state": state}  # noqa: E731
    assert verdict([seg(0, 4.8, "outer_race"), seg(4.8, 10.2, "unknown")]) == 1
    assert verdict([seg(0, 1, "normal"), seg(1, 2, "outer_race"), seg(2, 3.5, "normal")]) == 2  # 2.5 s normal
    assert verdict([seg(0, 0.2, "outer_race"), seg(0.2, 0.4, "inner_race")]) == 1  # a tie: the later
    assert verdict([]) == -1


def _decision(time, scores, diagnosed=True):
    return SimpleNamespace(time=time, diagnosed=diagnosed, scores=SimpleNamespace(as_dict=lambda: scores))


def test_segment_evidence_from_the_windows_published_scores():
    speed = 29.9
    windows = [{"outer_race": 3.0, "outer_race_rho": 1.01, "inner_race": 0.0, "inner_race_rho": 0.98,
                "band_low_hz": 2000.0, "band_high_hz": 4000.0, "speed_hz": speed, "told_speed_hz": 30.0},
               {"outer_race": 9.0, "outer_race_rho": 1.004, "inner_race": 0.5, "inner_race_rho": 1.02,
                "band_low_hz": 2500.0, "band_high_hz": 4500.0, "speed_hz": speed, "told_speed_hz": 30.0},
               {"outer_race": 5.0, "outer_race_rho": 0.99, "inner_race": 0.1, "inner_race_rho": 1.0,
                "band_low_hz": 2000.0, "band_high_hz": 4000.0, "speed_hz": speed + 0.2, "told_speed_hz": 30.0}]
    ev = segment_evidence(windows, ORDERS, None)
    assert ev["windows"] == 3 and ev["speed_hz"] == speed and ev["told_speed_hz"] == 30.0
    assert ev["band_hz"] == [2000.0, 4000.0]  # medians
    outer = ev["hypotheses"]["outer_race"]
    assert outer["significance"] == 5.0 and outer["peak"] == 9.0
    assert outer["expected_hz"] == pytest.approx(ORDERS["bpfo"] * speed, rel=1e-12)
    assert outer["line_hz"] == pytest.approx(ORDERS["bpfo"] * 1.004 * speed, rel=1e-12)  # ρ of the strongest window
    assert ev["hypotheses"]["inner_race"]["line_hz"] == pytest.approx(ORDERS["bpfi"] * 1.02 * speed, rel=1e-12)
    assert "ball" not in ev["hypotheses"]  # not tested in any window


def test_a_front_end_without_band_or_slip_gives_the_kinematic_lines_at_the_told_speed():
    ev = segment_evidence([{"outer_race": 2.0, "inner_race": 0.1}], ORDERS, 30.0)
    assert ev["band_hz"] is None and ev["speed_hz"] == 30.0
    assert ev["hypotheses"]["outer_race"] == {"significance": 2.0, "peak": 2.0,
                                             "expected_hz": pytest.approx(ORDERS["bpfo"] * 30.0), "line_hz": None}


def test_windows_belong_to_the_segment_current_when_they_were_decided():
    segments = [SimpleNamespace(detected_at=0.3), SimpleNamespace(detected_at=2.0), SimpleNamespace(detected_at=5.0)]
    decisions = [_decision(t, {"t": t}, diagnosed=t != 1.0) for t in (0.3, 1.0, 1.9, 2.0, 4.0, 5.0, 6.0)]
    assert [[w["t"] for w in m] for m in members(decisions, segments)] == [[0.3, 1.9], [2.0, 4.0], [5.0, 6.0]]


def test_fault_markers_are_the_kinematic_lines():
    lines = fault_markers(ORDERS, 30.0, 400.0)
    assert [f for f, _ in lines["outer_race"]] == pytest.approx([k * ORDERS["bpfo"] * 30.0 for k in (1, 2, 3)])
    bpfi = ORDERS["bpfi"] * 30.0
    assert lines["inner_race"][:3] == [(pytest.approx(bpfi - 30.0), False), (pytest.approx(bpfi), True),
                                       (pytest.approx(bpfi + 30.0), False)]
    assert all(f <= 400.0 for h in lines.values() for f, _ in h)


def test_the_envelope_view_of_modulated_noise_peaks_at_the_modulation():
    """Noise in 2-4 kHz, its amplitude modulated at 75 Hz: the averaged normalised SES has its largest bin at
    75 Hz (within one bin) and lies about 1 (its mean under noise) elsewhere."""
    rng = np.random.default_rng(3)
    seconds, f_mod = 10.0, 75.0
    n = int(seconds * FS)
    spectrum = np.fft.rfft(rng.standard_normal(n))
    f = np.fft.rfftfreq(n, 1 / FS)
    spectrum[(f < 2000) | (f > 4000)] = 0.0
    carrier = np.fft.irfft(spectrum, n)
    x = carrier * (1.0 + 0.5 * np.cos(2 * np.pi * f_mod * np.arange(n) / FS))
    view = envelope_view(x, FS, 0.0, seconds, 30.0, ORDERS, (2000.0, 4000.0), CATALOG["6205"], True, 0.3)
    df = view.f[1] - view.f[0]
    assert view.windows == int(seconds / view.window_s) and view.window_s >= 4 / (ORDERS["ftf"] * 30.0)
    assert abs(view.f[np.argmax(view.z)] - f_mod) <= df
    away = view.z[(np.abs(view.f - f_mod) > 3 * df) & (np.abs(view.f - 2 * f_mod) > 3 * df) & (view.f > 5 * df)]
    assert 0.85 < np.mean(away) < 1.15 and view.z.max() > 20 * np.mean(away)


# ---------------------------------------------------------------------------------------
# bearing-diagnose on a terminal, in a pipe, with --json


def test_diagnose_on_a_terminal_reads_as_a_verdict_with_its_evidence(or_recording, capsys, monkeypatch):
    code, out, err = _run(diagnose, [or_recording, "--model-set", "none"], capsys, monkeypatch, tty=True)
    assert code == 0, err
    assert not any(line.startswith("{") for line in out.splitlines())
    first = out.splitlines()[0]
    assert first.startswith(f"{or_recording}: OUTER RACE fault, confidence ")
    line = re.search(r"BPFO comb at ([0-9.]+) Hz \(([0-9.]+) × the kinematic ([0-9.]+) Hz\)", out)
    assert line, out
    assert float(line.group(3)) == pytest.approx(BPFO, abs=0.1)  # 3.585 × 30 Hz
    assert float(line.group(1)) == pytest.approx(BPFO, rel=0.01)  # where the bursts are
    assert re.search(r"band\s+\d\.\d\d-\d\.\d\d kHz demodulated", out)
    assert re.search(r"speed\s+30\.0\d Hz = 1800 rpm used", out)
    assert "bearing SKF 6205" in out and "model set none" in out


def test_json_lines_on_a_terminal_with_json_equal_those_of_a_pipe(or_recording, capsys, monkeypatch):
    _, piped, _ = _run(diagnose, [or_recording, "--model-set", "none"], capsys, monkeypatch, tty=False)
    _, forced, _ = _run(diagnose, [or_recording, "--model-set", "none", "--json"], capsys, monkeypatch, tty=True)
    assert piped == forced and [json.loads(x)["state"] for x in piped.splitlines()] == ["outer_race"]


# ---------------------------------------------------------------------------------------
# the HTML report


_EXTERNAL = re.compile(r"""(?:src|href)\s*=\s*["'](?!data:|#)([^"']*)["']""", re.I)


def _check_page(path, figures: set) -> str:
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and text.rstrip().endswith("</html>")
    assert not _EXTERNAL.findall(text), _EXTERNAL.findall(text)[:3]  # nothing fetched: no file, no URL
    assert "<script" not in text and "@import" not in text and "url(" not in text.replace("url(#", "")
    found = set(re.findall(r'<figure data-figure="([^"]+)">', text))
    assert figures <= found, found
    for svg in re.findall(r"<svg.*?</svg>", text, re.S):
        ET.fromstring(svg)  # each figure well-formed
    return text


def test_report_writes_one_self_contained_page_per_file(or_recording, tmp_path, capsys, monkeypatch):
    other = _npz(tmp_path / "healthy.npz", amplitude=0.0)
    code, out, err = _run(diagnose, [or_recording, other, "--model-set", "none", "--report", tmp_path / "rep",
                                     "--jobs", "2"], capsys, monkeypatch, tty=False)  # pages written by the workers
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "rep").iterdir()) == ["healthy.html", "or_fault.html"]
    text = _check_page(tmp_path / "rep" / "or_fault.html", {"envelope-spectrum-0", "timeline", "signal-states"})
    assert "OUTER RACE fault" in text and "BPFO comb at" in text
    assert "outer race: kinematic lines at the speed used" in text  # the markers' legend, as SVG text
    own = [json.loads(x) for x in out.splitlines() if json.loads(x)["file"] == str(or_recording)]
    assert own
    for line in own:  # the page holds the file's JSON lines as a single-file run prints them
        assert json.dumps({k: v for k, v in line.items() if k != "file"}).replace('"', "&quot;") in text
    assert "NORMAL: no fault evidence" in _check_page(tmp_path / "rep" / "healthy.html", {"timeline"})


def test_trend_on_a_terminal_and_its_report(tmp_path, capsys, monkeypatch):
    folder = degrading_folder(tmp_path / "B")
    code, out, err = _run(trend, [folder, "--bearing", "femto", "--rpm", "1800", "--report", tmp_path / "rep"],
                          capsys, monkeypatch, tty=True)
    assert code == 0, err
    assert not any(line.startswith("{") for line in out.splitlines())
    assert re.search(r": \d+\.\d min WARNING", out) and re.search(r": ALARM since \d+\.\d min \(60 snapshots", out)
    assert re.search(r"first warning\s+\d+\.\d min \(\d+\.\d min before the last snapshot\)", out)
    assert re.search(r"baseline\s+the first 30 snapshots", out)
    text = _check_page(tmp_path / "rep" / "B.html", {"indicators"})
    assert ">ALARM<" in text
    _, piped, _ = _run(trend, [folder, "--bearing", "femto", "--rpm", "1800"], capsys, monkeypatch, tty=False)
    _, forced, _ = _run(trend, [folder, "--bearing", "femto", "--rpm", "1800", "--json"], capsys, monkeypatch,
                        tty=True)
    assert piped == forced and len(piped.splitlines()) == 61


# ---------------------------------------------------------------------------------------
# rendered by a headless browser


def _chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    pytest.skip("no headless browser (chromium) installed: the page is checked as text above; "
                "CI renders it where chromium is installed (apt-get install chromium)")


def _headless(browser, *args, timeout=120):
    return subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                           "--no-first-run", "--disable-extensions", *args], capture_output=True, text=True,
                          timeout=timeout)


def test_a_browser_renders_the_report_with_its_figures(or_recording, tmp_path, capsys, monkeypatch):
    import matplotlib.image as mpimg
    browser = _chromium()
    code, _, err = _run(diagnose, [or_recording, "--model-set", "none", "--report", tmp_path], capsys, monkeypatch,
                        tty=False)
    assert code == 0, err
    page = (tmp_path / "or_fault.html").resolve()
    dom = _headless(browser, "--dump-dom", page.as_uri())
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert len(re.findall(r"<svg", dom.stdout)) >= 3  # parsed and kept by the browser
    for name in ("envelope-spectrum-0", "timeline", "signal-states"):
        assert f'data-figure="{name}"' in dom.stdout
    png = tmp_path / "page.png"
    shot = _headless(browser, f"--screenshot={png}", "--window-size=1200,3600", page.as_uri())
    assert shot.returncode == 0 and png.is_file(), shot.stderr[-2000:]
    image = mpimg.imread(png)[..., :3]
    assert image.shape[:2] == (3600, 1200)
    ink = (image.min(axis=2) < 0.9).mean()  # share of pixels that are not (near) white
    assert 0.03 < ink < 0.6, ink
    badge = np.all(np.abs(image - np.array([0x15, 0x65, 0xC0]) / 255) < 0.03, axis=2)  # the OUTER RACE badge
    assert badge.sum() > 500
    drawn = [(image[y0:y0 + 600].min(axis=2) < 0.5).mean() for y0 in range(300, 3000, 600)]
    assert sum(d > 0.01 for d in drawn) >= 3, drawn  # figures drawn down the page, not only text
