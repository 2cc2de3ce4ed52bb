"""CSV/TSV and WAV recordings: what each form reads as (exact values), the units, and one clear line for
every file that cannot be read; CSV and WAV copies of a CWRU record give the .mat's decision."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.io import wavfile

from bearing_common.units import STANDARD_GRAVITY as G
from bearing_diagnoser.diagnose_cli import main as diagnose
from bearing_diagnoser.health.trend_cli import main as trend
from bearing_recordings.load import load_recording
from bearing_recordings.measurement_units import parse_sensitivity, value_scale
from bearing_recordings.recording import InputError
from bearing_recordings.table_files import read_table

FS = 12000.0
X = np.array([0.5, -0.25, 0.125, 1.0, -1.0, 0.0, 0.75, -0.5])  # in g: exact in binary and decimal


def _text(path, text: str):
    path.write_text(text)
    return path


def _rows(*columns, header: str | None = None, sep: str = ",") -> str:
    lines = [header] if header else []
    lines += [sep.join(repr(float(v)) for v in row) for row in zip(*columns)]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------
# CSV / TSV: what each form reads as


def test_one_column_with_sample_rate(tmp_path):
    rec = load_recording(_text(tmp_path / "a.csv", _rows(X)), sample_rate=FS)
    np.testing.assert_array_equal(rec.accel, X * G)  # default unit g, said in the notes
    assert rec.sample_rate == FS and rec.source == "csv" and rec.channel == "1"
    assert any("assuming g" in n for n in rec.notes)


@pytest.mark.parametrize("name, unit_s", [("time", 1.0), ("t", 1.0), ("Time (s)", 1.0), ("time_ms", 1e-3),
                                          ("t [us]", 1e-6), ("timestamp", 1.0)])
def test_a_time_column_gives_the_rate_and_the_start(tmp_path, name, unit_s):
    t = (100.0 + np.arange(X.size) / FS) / unit_s
    rec = load_recording(_text(tmp_path / "a.csv", _rows(t, X, header=f"{name},accel")))
    assert rec.sample_rate == FS  # (n - 1) / span, within 1e-6 of a whole Hz: that Hz
    assert rec.start_time == pytest.approx(100.0)
    np.testing.assert_array_equal(rec.accel, X * G)


def test_printed_stamps_rounded_to_the_microsecond_still_give_the_rate(tmp_path):
    t = np.round(np.arange(1000) / FS, 6)
    x = np.resize(X, 1000)
    path = _text(tmp_path / "a.csv", "t,a\n" + "\n".join(f"{a:.6f},{b}" for a, b in zip(t, x)) + "\n")
    assert load_recording(path).sample_rate == FS


def test_named_columns_picked_by_channel_name_or_number_and_units_in_names(tmp_path):
    path = _text(tmp_path / "a.csv", _rows(np.arange(X.size) / FS, X, 2 * X, 4 * X,
                                           header="time,accel_x (g),accel_y [m/s^2],ch3_mV"))
    np.testing.assert_array_equal(load_recording(path, channel="accel_x (g)").accel, X * G)
    np.testing.assert_array_equal(load_recording(path, channel="ACCEL_Y [m/s^2]").accel, 2 * X)  # m/s² as named
    np.testing.assert_array_equal(load_recording(path, channel="3").accel, 2 * X)  # by number, from 1
    # volts need the sensor's sensitivity: 4·X mV at 100 mV/g = 0.04·X g
    np.testing.assert_allclose(load_recording(path, channel="ch3_mV", sensitivity="100mV/g").accel,
                               4 * X * 1e-3 / 0.1 * G, rtol=1e-15)
    np.testing.assert_array_equal(load_recording(path, channel="accel_x (g)", units="m/s2").accel, X)  # override


@pytest.mark.parametrize("sep, suffix", [("\t", "tsv"), (";", "csv"), (" ", "txt")])
def test_separators_tab_semicolon_space(tmp_path, sep, suffix):
    rec = load_recording(_text(tmp_path / f"a.{suffix}", _rows(X, 2 * X, sep=sep, header=sep.join(["a", "b"]))),
                         sample_rate=FS, channel="b")
    np.testing.assert_array_equal(rec.accel, 2 * X * G)


def test_decimal_commas_with_semicolons_comments_and_quotes(tmp_path):
    text = '# logger export\n"t";"a"\n' + "".join(f'"{i / 4:g}";"{v:g}"\n'.replace(".", ",")
                                                  for i, v in enumerate(X))
    rec = load_recording(_text(tmp_path / "a.csv", text), sample_rate=FS)
    np.testing.assert_array_equal(rec.accel, X * G)


def test_a_second_column_is_readable_by_name_for_a_tachometer(tmp_path):
    """What another reader (a speed channel) uses: any column by name, from the same table."""
    table = read_table(_text(tmp_path / "a.csv", _rows(np.arange(3) / FS, [1.0, 2.0, 3.0], [188.5, 188.6, 188.7],
                                                       header="time,accel,tacho_rad_s")))
    np.testing.assert_array_equal(table.column("tacho_rad_s"), [188.5, 188.6, 188.7])
    assert table.names == ["time", "accel", "tacho_rad_s"]


@pytest.mark.parametrize("text, kwargs, message", [
    ("", {"sample_rate": FS}, "no rows"),
    ("# only a comment\n", {"sample_rate": FS}, "no rows"),
    ("time,accel\n", {}, "a header (time, accel) and no rows"),
    ("0.1\n0.2\nabc\n", {"sample_rate": FS}, "line 3: 'abc' is not a number"),
    ("1,2\n3,4\n5\n", {"sample_rate": FS, "channel": "1"}, "line 3 has 1 cells, the first row 2"),
    ("a,b\n1,2\n", {"sample_rate": FS}, "2 signal columns; give --channel (columns: a, b)"),
    ("a,b\n1,2\n", {"sample_rate": FS, "channel": "c"}, "no column 'c'; columns: a, b"),
    ("1,2\n3,4\n", {"sample_rate": FS, "channel": "3"}, "no column '3'; columns: 1, 2 (no header)"),
    ("time,a\n0,1\n1,2\n", {"channel": "time"}, "--channel 'time' is the time column"),
    ("0.1\n0.2\n", {}, "no time column (t, time, ... ) and no --sample-rate"),
    ("t,a\n0,1\n0.001,2\n0.001,3\n", {}, "does not increase at row 3"),
    ("t,a\n0,1\n0.001,2\n0.0035,3\n0.004,4\n", {}, "is not evenly spaced"),
    ("t,a\n0,1\n1,2\n", {}, "sample rate of the time column 1.0 Hz is not plausible"),
    ("a\n1\nnan\n", {"sample_rate": FS}, "non-finite samples"),
    ("a (mV)\n1\n2\n", {"sample_rate": FS}, "is stated in mV, the sensor's output voltage; give --sensitivity"),
    ("a (g)\n1\n2\n", {"sample_rate": FS, "sensitivity": "100mV/g"}, "is stated in g, an acceleration"),
])
def test_tables_that_cannot_be_read_say_why_in_one_line(tmp_path, text, kwargs, message):
    with pytest.raises(InputError) as err:
        load_recording(_text(tmp_path / "bad.csv", text), **kwargs)
    assert message in str(err.value) and "\n" not in str(err.value)
    assert str(err.value).startswith(str(tmp_path / "bad.csv")) or "--" in str(err.value)


def test_a_binary_file_named_csv_is_not_a_table(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_bytes(b"\xff\xfe\x00\x81" * 10)
    with pytest.raises(InputError, match="not a text file"):
        load_recording(path, sample_rate=FS)


# ---------------------------------------------------------------------------------------
# units and sensitivities


@pytest.mark.parametrize("text, per_m_s2, volts", [
    ("100mV/g", 0.1 / G, True), ("0.1V/g", 0.1 / G, True), ("10.2mV/(m/s2)", 10.2e-3, True),
    ("10.2 mV / m/s^2", 10.2e-3, True), ("500uV/g", 5e-4 / G, True), ("0.05/g", 0.05 / G, False),
    ("2/(m/s²)", 2.0, False)])
def test_sensitivities_read_as_numbers_per_m_s2(text, per_m_s2, volts):
    value, is_volts = parse_sensitivity(text)
    assert value == pytest.approx(per_m_s2, rel=1e-15) and is_volts is volts


@pytest.mark.parametrize("text", ["", "100", "100mV", "-5mV/g", "0/g", "1pC/g", "100mV/furlong", "nan/g", "x/g"])
def test_sensitivities_that_mean_nothing_are_refused(text):
    with pytest.raises(InputError, match="not understood"):
        parse_sensitivity(text)


def test_units_and_sensitivity_exclude_each_other():
    with pytest.raises(InputError, match="not both"):
        value_scale("g", "100mV/g", "x")


# ---------------------------------------------------------------------------------------
# WAV


def _wav(path, data, rate=int(FS)):
    wavfile.write(path, rate, data)
    return path


@pytest.mark.parametrize("dtype, full_scale", [(np.int16, 2 ** 15), (np.int32, 2 ** 31)])
def test_integer_pcm_is_a_fraction_of_full_scale(tmp_path, dtype, full_scale):
    counts = (X * (full_scale // 2)).astype(dtype)  # half of full scale at X = 1
    rec = load_recording(_wav(tmp_path / "a.wav", counts), sensitivity="0.05/g")  # ±20 g full scale
    np.testing.assert_allclose(rec.accel, counts / full_scale / 0.05 * G, rtol=1e-15)
    assert rec.sample_rate == FS and rec.source == "wav"


def test_eight_bit_pcm_is_unsigned_about_128(tmp_path):
    rec = load_recording(_wav(tmp_path / "a.wav", np.array([128, 192, 64, 0], np.uint8)), units="g")
    np.testing.assert_array_equal(rec.accel, np.array([0.0, 0.5, -0.5, -1.0]) * G)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_float_samples_as_stored_in_the_stated_unit(tmp_path, dtype):
    rec = load_recording(_wav(tmp_path / "a.wav", (X * 3).astype(dtype)), units="m/s2")
    np.testing.assert_array_equal(rec.accel, X * 3)
    rec = load_recording(_wav(tmp_path / "v.wav", (X * 0.1).astype(dtype)), sensitivity="100mV/g")  # volts
    np.testing.assert_allclose(rec.accel, X * G, rtol=1e-6)


def test_a_channel_of_several_by_number(tmp_path):
    path = _wav(tmp_path / "a.wav", np.c_[X, -X, 2 * X].astype(np.float64))
    np.testing.assert_array_equal(load_recording(path, channel="2", units="g").accel, -X * G)


@pytest.mark.parametrize("make, kwargs, message", [
    (lambda p: p.write_bytes(b"RIFF\x00\x00\x00\x00NOPE"), {"units": "g"}, "not a readable WAV file"),
    (lambda p: p.write_bytes(b"garbage"), {"units": "g"}, "not a readable WAV file"),
    (lambda p: _wav(p, X.astype(np.float64)), {}, "does not say what its samples measure; give --units"),
    (lambda p: _wav(p, (X * 1000).astype(np.int16)), {"sensitivity": "100mV/g"},
     "integer PCM samples are fractions of full scale, not volts"),
    (lambda p: _wav(p, np.c_[X, X]), {"units": "g"}, "2 channels; give --channel 1 to 2"),
    (lambda p: _wav(p, np.c_[X, X]), {"units": "g", "channel": "3"}, "no channel '3'"),
    (lambda p: _wav(p, X, rate=50), {"units": "g"}, "not plausible"),
    (lambda p: _wav(p, np.zeros(0)), {"units": "g"}, "no samples"),
    (lambda p: _wav(p, np.r_[X, np.nan]), {"units": "g"}, "non-finite"),
])
def test_wavs_that_cannot_be_read_say_why_in_one_line(tmp_path, make, kwargs, message):
    path = tmp_path / "bad.wav"
    make(path)
    with pytest.raises(InputError) as err:
        load_recording(path, **kwargs)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_a_compressed_wav_is_refused(tmp_path):
    """A WAV whose format tag is not PCM or float (here 2, Microsoft ADPCM)."""
    path = _wav(tmp_path / "a.wav", (X * 1000).astype(np.int16))
    data = bytearray(path.read_bytes())
    data[20:22] = (2).to_bytes(2, "little")
    path.write_bytes(bytes(data))
    with pytest.raises(InputError, match="not a readable WAV file"):
        load_recording(path, units="g")


# ---------------------------------------------------------------------------------------
# the command lines


def _lines(out: str) -> list:
    return [json.loads(x) for x in out.splitlines() if x.strip()]


def test_cli_errors_are_one_line_and_exit_2(tmp_path, capsys):
    bad = _text(tmp_path / "bad.csv", "a,b\n1,2\n")
    for argv, message in (([bad, "--sample-rate", 12000], "give --channel"),
                          ([bad, "--units", "g", "--sensitivity", "1/g"], "not both"),
                          ([bad, "--sensitivity", "lots"], "not understood")):
        assert diagnose([str(a) for a in argv]) == 2
        out, err = capsys.readouterr()
        assert out == "" and len([x for x in err.splitlines() if "error:" in x]) == 1 and message in err, err
        assert trend([str(a) for a in argv]) == 2
        out, err = capsys.readouterr()
        assert len([x for x in err.splitlines() if "error:" in x]) == 1 and message in err, err


def test_a_folder_walk_takes_tables_and_wavs(tmp_path):
    from bearing_recordings.recording_files import expand
    for name in ("a.csv", "b.tsv", "c.wav", "d.mat", "notes.txt", "e.xls"):
        (tmp_path / name).write_text("")
    assert [p.rsplit("/", 1)[-1] for p in expand([str(tmp_path)])[0]] == ["a.csv", "b.tsv", "c.wav", "d.mat"]


@pytest.fixture(scope="module")
def cwru_130_copies(tmp_path_factory):
    """CWRU 130 (outer race, 12 kHz, 1796 rpm) as .mat and as CSV and WAV copies of its drive-end channel."""
    from data_paths import data_dir

    from bearing_recordings.mat_files import load_mat
    mat = data_dir() / "cwru" / "130_OR007at6_0hp_DE12k.mat"
    if not mat.is_file():
        pytest.skip(f"recording cwru/{mat.name} not found in {data_dir()} (../shared/data in CI)")
    g = load_mat(mat, FS).accel / G
    out = tmp_path_factory.mktemp("copies")
    t = np.arange(g.size) / FS
    np.savetxt(out / "130.csv", np.c_[t, g], delimiter=",", header="time (s),drive_end (g)", comments="",
               fmt="%.17g")
    np.savetxt(out / "130.tsv", g, fmt="%.17g")  # one column, no header: --sample-rate
    _wav(out / "130_f64.wav", g)
    peak = float(np.abs(g).max())
    _wav(out / "130_i32.wav", np.round(g / peak * (2 ** 31 - 1)).astype(np.int32))
    return mat, out, peak


#: What the copies must be told that the .mat says itself: the speed (rig-measured, 2 %) and the
#: model set the .mat's source (cwru) picks.
TOLD = ["--rpm", "1796", "--rpm-tolerance", "0.02", "--model-set", "cwru_de_6205"]


def _diagnose(argv, capsys) -> list:
    assert diagnose([str(a) for a in argv]) == 0
    return _lines(capsys.readouterr().out)


def test_csv_and_wav_copies_give_the_mat_files_decision(cwru_130_copies, capsys):
    mat, out, peak = cwru_130_copies
    reference = _diagnose([mat, "--sample-rate", 12000], capsys)
    assert [s["state"] for s in reference] == ["outer_race"]
    for argv in ([out / "130.csv", *TOLD],  # time column gives 12 kHz; unit g from the column's name
                 [out / "130.tsv", "--sample-rate", 12000, *TOLD],  # default unit g
                 [out / "130_f64.wav", "--units", "g", *TOLD]):
        assert _diagnose(argv, capsys) == reference, argv  # float64 copies: the same lines, every score
    # 32-bit integer PCM rounds each sample by ≤ 2^-32 of full scale: the same segments and states
    quantised = _diagnose([out / "130_i32.wav", "--sensitivity", f"{1 / peak!r}/g", *TOLD], capsys)
    assert [(s["start"], s["end"], s["state"], s["detected_at"]) for s in quantised] == \
        [(s["start"], s["end"], s["state"], s["detected_at"]) for s in reference]
    for s, r in zip(quantised, reference):
        assert s["confidence"] == pytest.approx(r["confidence"], abs=1e-3)
        for k in r["scores"]:
            assert s["scores"][k] == pytest.approx(r["scores"][k], rel=1e-3, abs=1e-3), k


def test_bearing_trend_reads_a_folder_of_csv_snapshots(tmp_path, capsys):
    from bearing_diagnoser.synthetic import white_noise
    for i in range(8):
        y = white_noise(0.2, FS, 1e-2, np.random.default_rng(i)) / G
        np.savetxt(tmp_path / f"snap_{i:02d}.csv", y, fmt="%.9g")
    assert trend([str(tmp_path), "--sample-rate", "12000", "--baseline", "6"]) == 0
    lines = _lines(capsys.readouterr().out)
    assert len(lines) == 9 and "summary" in lines[-1] and lines[1]["t"] == pytest.approx(0.2)
