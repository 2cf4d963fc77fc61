"""The waveform recording format: read like every recording (comments, units, dialects), exc_v
optional, the sample times checked; written and read back unchanged."""

import numpy as np
import pytest

from flann.errors import RecordingsError
from flann.recordings.waveform import Waveforms, format_waveforms, parse_waveforms, read_waveforms, write_waveforms

CANONICAL = """# a bench with a DAQ
time_s,exc_v,sec_a_v,sec_b_v,displacement_mm,temperature_c
0,5,0.5,-0.25,-1,20
1e-05,4.5,0.25,-0.5,-1,20
2e-05,4,0.125,-0.75,-1,21
"""


def test_canonical_file():
    w = parse_waveforms(CANONICAL)
    np.testing.assert_array_equal(w.sec_a_v, [0.5, 0.25, 0.125])
    np.testing.assert_array_equal(w.sec_b_v, [-0.25, -0.5, -0.75])
    np.testing.assert_array_equal(w.exc_v, [5, 4.5, 4])
    np.testing.assert_array_equal(w.temperature_c, [20, 20, 21])
    assert w.sample_rate_hz == pytest.approx(1e5) and len(w) == 3
    assert w.comments == ("a bench with a DAQ",) and w.recognised == ""


def test_exc_v_and_temperature_are_optional():
    text = "time_s,sec_a_v,sec_b_v,displacement_mm\n0,1,2,0\n0.001,3,4,0\n"
    w = parse_waveforms(text)
    assert w.exc_v is None and w.temperature_c is None
    np.testing.assert_array_equal(w.sec_b_v, [2, 4])


def test_a_logger_dialect_units_and_decimal_commas():
    text = ("sep=;\nTime (ms);Sec A (mV);Sec B (mV);Position (um)\n"
            "0;1000,5;-250;100\n0,01;1500;-500;100\n0,02;2000;-750;200\n")
    w = parse_waveforms(text)
    np.testing.assert_allclose(w.time_s, [0, 1e-5, 2e-5])
    np.testing.assert_allclose(w.sec_a_v, [1.0005, 1.5, 2.0])
    np.testing.assert_allclose(w.sec_b_v, [-0.25, -0.5, -0.75])
    np.testing.assert_allclose(w.displacement_mm, [0.1, 0.1, 0.2])
    assert "'Sec A (mV)' as sec_a_v (x 0.001)" in w.recognised


def test_unit_line_under_the_header():
    text = "time\tsec_a\tsec_b\tdisplacement\ns\tmV\tV\tmm\n0\t500\t1\t0\n0.5\t250\t2\t0\n"
    w = parse_waveforms(text)
    np.testing.assert_allclose(w.sec_a_v, [0.5, 0.25])
    np.testing.assert_allclose(w.sec_b_v, [1, 2])


@pytest.mark.parametrize("text, words", [
    ("time_s,sec_a_v,displacement_mm\n0,1,0\n1,2,0\n", "missing column(s) sec_b_v"),
    ("sec_a_v,sec_b_v,displacement_mm\n1,2,0\n2,3,0\n", "time_s"),
    ("time_s,sec_a_v,sec_b_v\n0,1,2\n1,2,3\n", "displacement_mm"),
    ("time_s,sec_a_v,sec_b_v,displacement_mm\n0,1,2,0\n0,2,3,0\n", "line 3: time_s 0 s does not follow"),
    ("time_s,sec_a_v,sec_b_v,displacement_mm\n0,1,x,0\n1,2,3,0\n", "line 2"),
    ("time_s,sec_a_v,sec_a (mV),sec_b_v,displacement_mm\n0,1,1,2,0\n1,2,2,3,0\n", "duplicate column sec_a_v"),
    ("# only a comment\n", "no header line"),
])
def test_bad_files_name_the_problem(text, words):
    with pytest.raises(RecordingsError, match=None) as info:
        parse_waveforms(text, source="w.csv")
    assert words in str(info.value) and str(info.value).startswith("w.csv")


def test_unknown_column_is_warned_once():
    text = "time_s,sec_a_v,sec_b_v,displacement_mm,gain_code\n0,1,2,0,7\n1,2,3,0,7\n"
    with pytest.warns(UserWarning, match="ignoring unknown column.*gain_code") as seen:
        parse_waveforms(text)
    assert len(seen) == 1


def test_write_then_read_round_trip(tmp_path):
    rng = np.random.default_rng(5)
    n = 50
    w = Waveforms(time_s=np.arange(n) / 1e5, sec_a_v=rng.normal(size=n), sec_b_v=rng.normal(size=n),
                  displacement_mm=np.linspace(-1, 1, n), exc_v=rng.normal(size=n), temperature_c=np.full(n, 25.0))
    path = tmp_path / "w.csv"
    write_waveforms(path, w, comments=("made here",))
    assert path.read_text().splitlines()[1] == "time_s,exc_v,sec_a_v,sec_b_v,displacement_mm,temperature_c"
    back = read_waveforms(path)
    for col in ("time_s", "exc_v", "sec_a_v", "sec_b_v", "displacement_mm", "temperature_c"):
        np.testing.assert_allclose(getattr(back, col), getattr(w, col), rtol=1e-8)
    assert back.comments == ("made here",)
    assert format_waveforms(back, ("made here",)) == path.read_text()
