import subprocess
import sys
import warnings

import numpy as np
import pytest

from flann.errors import RecordingsError
from flann.recordings import estimate_noise_v, parse_recordings, read_recordings


def test_paper_table_reads_with_provenance():
    rec = read_recordings("data/paper_table1.csv")
    assert len(rec) == 13
    assert rec.voltage_v[8] == pytest.approx(1.810)
    assert rec.displacement_mm[0] == -30
    assert rec.comments and "Table 1" in rec.comments[0]


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("displacement_mm\n1\n", "missing column"),
        ("displacement_mm,voltage_v\n1,abc\n", "not a number"),
        ("displacement_mm,voltage_v\n1,nan\n", "not finite"),
        ("displacement_mm,voltage_v\n1,inf\n", "not finite"),
        ("displacement_mm,voltage_v,direction\n1,2,0\n", r"not \+1 or -1"),
        ("displacement_mm,voltage_v\n", "no data rows"),
        ("displacement_mm,voltage_v\n1,2,3\n", "cells"),
    ],
)
def test_bad_recordings_name_the_problem(text, fragment):
    with pytest.raises(RecordingsError, match=fragment):
        parse_recordings(text, source="x.csv")


def test_unknown_column_warns_and_is_ignored():
    with pytest.warns(UserWarning, match="ignoring unknown column"):
        rec = parse_recordings("displacement_mm,voltage_v,humidity\n1,2,3\n")
    assert set(rec.columns()) == {"displacement_mm", "voltage_v"}
    np.testing.assert_array_equal(rec.voltage_v, [2.0])


def _sweeps_text(second_pass_offset_v: float, with_time: bool) -> str:
    """Two forward passes over a smooth curve; the second shifted by an offset."""
    x = np.arange(-10, 11, 1.0)
    v = np.tanh(x / 8.0)
    rows = ["displacement_mm,voltage_v,direction" + (",time_s" if with_time else "")]
    t = 0
    for off in (0.0, second_pass_offset_v):
        for xi, vi in zip(x, v + off):
            rows.append(f"{xi},{vi:.6f},1" + (f",{t}" if with_time else ""))
            t += 1
    return "\n".join(rows) + "\n"


def test_repeated_sweeps_within_noise_are_accepted_with_time_column():
    from flann.recordings import prepare_for_fit

    rec = parse_recordings(_sweeps_text(0.0005, with_time=True))
    assert len(prepare_for_fit(rec)) == 42


@pytest.mark.parametrize("with_time", [False, True])
def test_repeats_beyond_noise_are_refused_with_or_without_time(with_time):
    from flann.recordings import prepare_for_fit

    rec = parse_recordings(_sweeps_text(0.3, with_time=with_time), source="r.csv")
    with pytest.raises(RecordingsError, match="appears twice"):
        prepare_for_fit(rec)


def test_repeated_sweeps_within_noise_are_data_without_time_column():
    from flann.recordings import prepare_for_fit

    rec = parse_recordings(_sweeps_text(0.0005, with_time=False), source="r.csv")
    assert len(prepare_for_fit(rec)) == 42


# -- files as people export them ---------------------------------------------------------
EXCEL_LIKE = ("\ufeff# bench 3, LVDT #17\r\n"
              "Displacement (in);Voltage (mV);Temperature (°C)\r\n"
              "-0,5;-1234,5;21,5\r\n"
              "0;0,25;21,5\r\n"
              "0,5;1250;21,6\r\n")


def test_spreadsheet_export_bom_crlf_semicolon_decimal_comma_units(tmp_path, capsys):
    p = tmp_path / "export.csv"
    p.write_bytes(EXCEL_LIKE.encode("utf-8"))
    rec = read_recordings(p)
    # inches -> mm (25.4 mm/in), millivolts -> volts, worked out by hand
    np.testing.assert_allclose(rec.displacement_mm, [-12.7, 0.0, 12.7], rtol=0, atol=1e-12)
    np.testing.assert_allclose(rec.voltage_v, [-1.2345, 0.00025, 1.25], rtol=0, atol=1e-15)
    np.testing.assert_allclose(rec.temperature_c, [21.5, 21.5, 21.6])
    assert rec.comments == ("bench 3, LVDT #17",)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    for word in ("byte-order mark", "semicolon", "decimal comma", "'Displacement (in)' as displacement_mm",
                 "'Voltage (mV)' as voltage_v"):
        assert word in err[0]


def test_latin1_tab_separated_export(tmp_path, capsys):
    p = tmp_path / "logger.txt"
    p.write_bytes("position_mm\tvoltage_mv\tTemperature (°C)\n1,5\t100\t20\n2,5\t200\t20\n".encode("latin-1"))
    rec = read_recordings(p)
    np.testing.assert_allclose(rec.displacement_mm, [1.5, 2.5])
    np.testing.assert_allclose(rec.voltage_v, [0.1, 0.2])
    assert "Latin-1" in capsys.readouterr().err


@pytest.mark.parametrize("header, factor_x, factor_v", [
    ("x_mm,voltage_v", 1.0, 1.0),
    ("position_mm,Voltage (V)", 1.0, 1.0),
    ("Displacement [mm],voltage_mv", 1.0, 1e-3),
    ("displacement_in,Voltage (mV)", 25.4, 1e-3),
    ("Position (cm),U (V)", 10.0, 1.0),
    ("displacement_um,voltage_uv", 1e-3, 1e-6),
    # ISO "quantity / unit", units spelled out, a space before the unit, other names
    ("x / mm,U / mV", 1.0, 1e-3),
    ("Displacement (in.),Voltage (Volts)", 25.4, 1.0),
    ("distance_mm,Signal (millivolts)", 1.0, 1e-3),
    ("position mm,Sensor output (V)", 1.0, 1.0),
    ("Position (millimetres),voltage_volts", 1.0, 1.0),
    ("mm,mV", 1.0, 1e-3),                       # bare units: the quantity is unambiguous
    ("[um],[V]", 1e-3, 1.0),
])
def test_header_aliases_and_units(header, factor_x, factor_v):
    rec = parse_recordings(f"{header}\n2,3\n4,5\n")
    np.testing.assert_allclose(rec.displacement_mm, np.array([2.0, 4.0]) * factor_x, rtol=1e-15)
    np.testing.assert_allclose(rec.voltage_v, np.array([3.0, 5.0]) * factor_v, rtol=1e-15)


def test_comma_unit_header_in_a_semicolon_file():
    rec = parse_recordings("Position, mm;Voltage, V\n1,5;0,25\n2,5;0,5\n")
    np.testing.assert_allclose(rec.displacement_mm, [1.5, 2.5])
    np.testing.assert_allclose(rec.voltage_v, [0.25, 0.5])


def test_whitespace_aligned_columns():
    # a .txt/.dat export: columns aligned with spaces, units in brackets after the names
    rec = parse_recordings("Displacement (mm)   Voltage [mV]   time_s\n  -1.5   -250.0   0\n"
                           "   0.0      0.5   1\n   1.5    500.0   2\n")
    np.testing.assert_allclose(rec.displacement_mm, [-1.5, 0.0, 1.5])
    np.testing.assert_allclose(rec.voltage_v, [-0.25, 0.0005, 0.5])
    np.testing.assert_allclose(rec.time_s, [0, 1, 2])
    assert "whitespace-separated" in rec.recognised


def test_quoted_decimal_commas_in_a_comma_file():
    rec = parse_recordings('"displacement_mm","voltage_v"\n"1,5","0,25"\n"2","-0,5"\n')
    np.testing.assert_allclose(rec.displacement_mm, [1.5, 2.0])
    np.testing.assert_allclose(rec.voltage_v, [0.25, -0.5])
    with pytest.raises(RecordingsError, match="'1.234,5' is not a number"):   # thousands: not guessed
        parse_recordings("displacement_mm;voltage_v\n1.234,5;3\n")


def test_direction_in_words():
    rec = parse_recordings("displacement_mm,voltage_v,Direction\n0,0,up\n1,1,Up\n1,1.01,down\n0,0.01,-\n")
    np.testing.assert_array_equal(rec.direction, [1, 1, -1, -1])
    with pytest.raises(RecordingsError, match="'sideways' is not a direction"):
        parse_recordings("displacement_mm,voltage_v,direction\n0,0,sideways\n")


@pytest.mark.parametrize("text", [
    "Displacement;Voltage;Temperature\nmm;mV;°C\n1,5;250;20\n2,5;500;20\n",
    "time,position,output\ns,[in],[V]\n0,0.0590551181,0.25\n1,0.0984251969,0.5\n",
    "displacement_mm,voltage_v\nmm,V\n1.5,0.25\n2.5,0.5\n",
])
def test_units_on_the_line_under_the_names(text):
    rec = parse_recordings(text)
    np.testing.assert_allclose(rec.displacement_mm, [1.5, 2.5], rtol=1e-9)
    np.testing.assert_allclose(rec.voltage_v, [0.25, 0.5], rtol=1e-12)
    assert rec.line_of(0) == "line 3"


def test_bare_word_like_units_are_not_guessed():
    with pytest.raises(RecordingsError, match="missing column"):
        parse_recordings("in,out\n1,2\n")


def test_canonical_file_says_nothing(tmp_path, capsys):
    p = tmp_path / "r.csv"
    p.write_text("displacement_mm,voltage_v\n1,2\n3,4\n")
    assert read_recordings(p).recognised == ""
    assert capsys.readouterr().err == ""


def test_unknown_header_is_one_line_listing_accepted_names(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text("Przemieszczenie (mm);Napiecie (V)\n1;2\n")
    r = subprocess.run([sys.executable, "-m", "flann.cli", "train", str(p), "-o", str(tmp_path / "m.json")],
                       capture_output=True, text=True)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert "'Przemieszczenie (mm)'" in lines[0] and "Displacement (mm)" in lines[0] and "voltage_mv" in lines[0]
    assert "Traceback" not in r.stderr and not (tmp_path / "m.json").exists()


def test_voltage_without_unit_is_not_guessed():
    with pytest.raises(RecordingsError, match=r"missing column\(s\) voltage_v.*'voltage'"):
        parse_recordings("displacement_mm,voltage\n1,2\n")


def test_errors_name_the_file_line_not_the_data_row():
    text = "# provenance\n\ndisplacement_mm,voltage_v\n1,2\n# a note\n2,abc\n"
    with pytest.raises(RecordingsError, match=r"line 6, column 'voltage_v'"):
        parse_recordings(text, source="x.csv")
    with pytest.raises(RecordingsError, match=r"line 4, column 'direction'"):
        parse_recordings("#\n\ndisplacement_mm,voltage_v,direction\n1,2,0\n")
    with pytest.raises(RecordingsError, match=r"line 3 has 3 cells"):
        parse_recordings("displacement_mm,voltage_v\n1,2\n1,2,3\n")


def test_same_column_twice_under_two_names():
    with pytest.raises(RecordingsError, match="duplicate column"):
        parse_recordings("x_mm,displacement_mm,voltage_v\n1,1,2\n")


def test_excel_sep_line_names_the_separator(tmp_path):
    # Excel's "CSV (semicolon)" export can start with a sep= line before the header
    p = tmp_path / "excel.csv"
    p.write_bytes(b"sep=;\r\nPosition (mm);Voltage (V)\r\n-1,5;-0,25\r\n0;0\r\n1,5;0,5\r\n")
    rec = read_recordings(p, announce=False)
    np.testing.assert_allclose(rec.displacement_mm, [-1.5, 0.0, 1.5])
    np.testing.assert_allclose(rec.voltage_v, [-0.25, 0.0, 0.5])
    assert rec.line_of(0) == "line 3"


def test_trailing_separator_is_not_an_unknown_column():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rec = parse_recordings("displacement_mm,voltage_v,\n0,0,\n1,0.5,\n2,1,\n")
    np.testing.assert_allclose(rec.voltage_v, [0.0, 0.5, 1.0])


def test_noise_estimate_of_either_difference_order():
    """White noise of 2 mV on a straight line: both orders find it; on a curve sampled coarsely
    (an S-curve at 0.5 mm steps) the second difference carries the curvature, the third not."""
    rng = np.random.default_rng(3)
    x = np.arange(-30.0, 30.01, 0.5)
    noise = rng.normal(0.0, 0.002, x.size)
    line = 0.1 * x + noise
    for order in (2, 3):
        assert abs(estimate_noise_v(line, order=order) / 0.002 - 1) < 0.2
    curve = 5.6 * np.tanh(x / 6.0) + noise
    assert abs(estimate_noise_v(curve, order=3) / 0.002 - 1) < 0.25
    assert estimate_noise_v(curve, order=2) > 1.3 * estimate_noise_v(curve, order=3)
