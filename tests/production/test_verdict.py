"""Verdicts against a production spec, the spec file, traceability and the uncertainty."""

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from datetime import date

import pytest

from flann.errors import FlannError
from flann.production.spec import ProductionSpec, build_spec, load_spec
from flann.production.traceability import Station, comment_fields, traceability
from flann.production.traceability import certificate_number, parse_due
from flann.production.verdict import FAIL, NOT_JUDGED, NOT_JUDGED_WHY, PASS, judge, noise_v, rejected, uncertainty

X = np.linspace(-10, 10, 201)


def _err(peak_at: float, peak: float) -> np.ndarray:
    """An error of 0.01 mm everywhere except ``peak`` at ``peak_at`` mm."""
    e = np.full(X.size, 0.01)
    e[np.argmin(np.abs(X - peak_at))] = peak
    return e


def test_tolerance_in_mm_over_the_whole_stroke_and_a_working_range():
    err = _err(9.5, 0.08)   # the worst point is outside -8..8
    v = judge(ProductionSpec(max_error_mm=0.05), X, err, 2.0, ())
    assert v.verdict == FAIL and v.max_error_mm == pytest.approx(0.08)
    assert "0.08 mm > tolerance 0.05 mm" in v.reasons[0]
    v = judge(ProductionSpec(max_error_mm=0.05, working_range_mm=(-8, 8)), X, err, 2.0, ())
    assert v.verdict == PASS and v.max_error_mm == pytest.approx(0.01) and v.reasons == ()
    assert v.full_scale_mm == 8 and v.max_error_pct_fs == pytest.approx(100 * 0.01 / 8)


def test_tolerance_in_percent_of_full_scale():
    err = _err(0.0, 0.05)   # 0.05 mm of a +-10 mm stroke (FS 10 mm) = 0.5 % FS
    assert judge(ProductionSpec(max_error_pct_fs=0.6), X, err, None, ()).verdict == PASS
    v = judge(ProductionSpec(max_error_pct_fs=0.4), X, err, None, ())
    assert v.verdict == FAIL and "0.5 % FS > tolerance 0.4 % FS" in v.reasons[0]


def test_a_working_range_the_recording_does_not_cover_fails():
    v = judge(ProductionSpec(max_error_mm=1.0, working_range_mm=(-12, 8)), X, _err(0, 0.01), None, ())
    assert v.verdict == FAIL and "not the whole working range" in v.reasons[0]


def test_marginal_within_the_uncertainty_passes_and_says_so():
    v = judge(ProductionSpec(max_error_mm=0.05), X, _err(0, 0.049), None, (), expanded_mm=0.003)
    assert v.verdict == PASS and v.reasons[0].startswith("marginal")


def test_ratio_and_named_effects_and_confounded_alternatives():
    spec = ProductionSpec(max_ratio_to_limit=10, fail_on_effects=("backlash",))
    assert judge(spec, X, _err(0, 0.01), 12.0, ()).verdict == FAIL
    v = judge(spec, X, _err(0, 0.01), 5.0, ("null_offset", "backlash"))
    assert v.verdict == FAIL and "names backlash" in v.reasons[0]
    # an alternative explanation that includes a forbidden effect cannot be ruled out
    v = judge(spec, X, _err(0, 0.01), 5.0, (), (("null_offset",), ("backlash",)))
    assert v.verdict == FAIL and "cannot rule out backlash" in v.reasons[0]
    assert judge(spec, X, _err(0, 0.01), 5.0, ("null_offset",)).verdict == PASS


def test_no_spec_judges_nothing_and_rejected_is_a_fail():
    """Without a specification a calibrated sensor is NOT JUDGED (its weights still written),
    never PASS: a certificate reading PASS against nothing would be signed as a pass."""
    v = judge(ProductionSpec(), X, _err(0, 5.0), 100.0, ("backlash",))
    assert v.verdict == NOT_JUDGED and not v.passed and v.shipped
    assert v.reasons == (NOT_JUDGED_WHY,)
    assert judge(ProductionSpec(max_error_mm=10.0), X, _err(0, 5.0), 100.0, ()).verdict == PASS
    r = rejected(ProductionSpec(max_error_mm=0.1), "no voltage column")
    assert r.verdict == FAIL and r.rejected and r.reasons == ("rejected: no voltage column",)


def test_spec_file_and_flags(tmp_path):
    p = tmp_path / "line.toml"
    p.write_text('name = "A"\n[tolerance]\nmax_error_pct_fs = 0.5\nworking_range_mm = [-5, 5]\n'
                 '[limits]\nmax_ratio_to_limit = 50\nfail_on_effects = ["backlash"]\n')
    s = load_spec(p)
    assert (s.name, s.max_error_pct_fs, s.working_range_mm, s.max_ratio_to_limit, s.fail_on_effects) == \
        ("A", 0.5, (-5.0, 5.0), 50.0, ("backlash",))
    # a flag replaces the file's tolerance (mm instead of % FS)
    s2 = build_spec(p, max_error_mm=0.02, working_range="-4:4")
    assert s2.max_error_mm == 0.02 and s2.max_error_pct_fs is None and s2.working_range_mm == (-4, 4)
    assert s2.source.endswith("+ flags")


def test_a_spec_file_without_a_tolerance_is_refused(tmp_path):
    """An empty or name-only spec passed every sensor with "none (no specification given)"."""
    for text in ("", 'name = "x"\n', "[limits]\nmax_ratio_to_limit = 50\n"):
        p = tmp_path / "s.toml"
        p.write_text(text)
        with pytest.raises(FlannError, match="states no tolerance"):
            build_spec(p)
    assert build_spec(p, max_error_mm=0.1).max_ratio_to_limit == 50.0


@pytest.mark.parametrize("text, words", [
    ("[tolerance]\nmax_error_mm = -1\n", "must be > 0"),
    ("[tolerance]\nmax_error_mm = 0.1\nmax_error_pct_fs = 1\n", "not both"),
    ("[tolerance]\nworking_range_mm = [5, -5]\n", "below high"),
    ("[limits]\nfail_on_effects = [\"gremlins\"]\n", "unknown effect"),
    ("[tolerance]\nmax_eror_mm = 0.1\n", "unknown key"),
    ("[tolerance\n", "not valid TOML"),
])
def test_bad_spec_files_are_one_line_errors(tmp_path, text, words):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(FlannError, match=words):
        load_spec(p)


def test_traceability_from_comments_flags_and_columns(tmp_path):
    assert comment_fields(["serial: SN-1", "Operator = Ann", "simulated by x", "station:  B2"]) == \
        {"serial": "SN-1", "operator": "Ann", "station": "B2"}
    rec = SimpleNamespace(comments=("serial: SN-7", "operator: Ann"), temperature_c=np.array([22.0, 24.0]))
    t = traceability(tmp_path / "f.csv", rec, Station(station="L1", operator="Bob", fixture="F2"))
    assert (t.serial, t.operator, t.station, t.fixture) == ("SN-7", "Ann", "L1", "F2")
    assert t.temperature_c == 23.0 and "mean" in t.temperature_from
    assert t.calibrated_at[10] == "T" and t.calibrated_at[-6] in "+-"   # ISO 8601 with offset
    t = traceability(tmp_path / "g.csv", None, Station(temperature_c=20.5))
    assert (t.serial, t.serial_from, t.temperature_c) == ("g", "file name", 20.5)
    csvp = tmp_path / "h.csv"
    csvp.write_text("# a comment\ndisplacement_mm;voltage_v;sn\n0;1;ABC-9\n1;2;ABC-9\n")
    assert traceability(csvp, None, Station(serial_column="sn")).serial == "ABC-9"
    with pytest.raises(FlannError, match="no column 'serial'"):
        traceability(csvp, None, Station(serial_column="serial"))


def test_expanded_uncertainty_follows_noise_and_positions():
    rng = np.random.default_rng(1)
    x = np.linspace(-10, 10, 400)
    rec = SimpleNamespace(voltage_v=0.5 * x + rng.normal(0, 0.002, x.size), displacement_mm=x, direction=None)
    u = uncertainty(rec, np.full(x.size, 2.0), terms=15, output_lsb_mm=0.0)
    assert u.noise_v == pytest.approx(0.002, rel=0.15)
    # sigma_x = 2 mm/V x 2 mV = 4 um; U = 2 sigma_x sqrt(1 + 15/400)
    assert u.expanded_mm == pytest.approx(2 * 0.004 * math.sqrt(1 + 15 / 400), rel=0.15)


NOISE_V = 0.002


def _lvdt(sweeps: int, seed: int):
    from flann.physics.sensor import load_sensor
    from flann.physics.simulate import simulate_recordings
    s = load_sensor(Path(__file__).resolve().parents[2] / "data" / "sensors" / "paper_lvdt.toml")
    return simulate_recordings(s, sweeps=sweeps, step_mm=0.5, noise_v=NOISE_V, seed=seed)


@pytest.mark.parametrize("sweeps", [2, 4])
def test_noise_of_repeated_sweeps_is_the_noise_of_one_reading(sweeps):
    """Repeated sweeps read each position several times; the noise figure is still the
    simulated 2 mV (it was 60 mV on two sweeps) and what one sweep of the sensor gives."""
    one = noise_v(_lvdt(1, seed=11))
    many = noise_v(_lvdt(sweeps, seed=11))
    assert one == pytest.approx(NOISE_V, rel=0.2)
    assert many == pytest.approx(NOISE_V, rel=0.2)
    assert many == pytest.approx(one, rel=0.2)


def test_noise_without_a_direction_column_in_no_order_and_one_way_passes():
    rec = _lvdt(2, seed=12)
    x, v, d = (np.asarray(a, dtype=float) for a in (rec.displacement_mm, rec.voltage_v, rec.direction))
    # the direction inferred from the row order
    assert noise_v(SimpleNamespace(displacement_mm=x, voltage_v=v, direction=None)) == \
        pytest.approx(NOISE_V, rel=0.2)
    # two forward passes under one direction value (the return strokes not recorded)
    fwd = d > 0
    assert noise_v(SimpleNamespace(displacement_mm=x[fwd], voltage_v=v[fwd], direction=d[fwd])) == \
        pytest.approx(NOISE_V, rel=0.2)
    # rows shuffled: the readings repeated at one position
    p = np.random.default_rng(3).permutation(x.size)
    for direction in (d[p], None):
        assert noise_v(SimpleNamespace(displacement_mm=x[p], voltage_v=v[p], direction=direction)) == \
            pytest.approx(NOISE_V, rel=0.2)
    # a dwell (each position read three times in a row) is not a step of the curve
    dw = np.repeat(np.arange(x.size), 3)
    v_dw = v[dw] + np.random.default_rng(4).normal(0, NOISE_V, dw.size) * (np.arange(dw.size) % 3 > 0)
    assert noise_v(SimpleNamespace(displacement_mm=x[dw], voltage_v=v_dw, direction=d[dw])) < 1.2 * NOISE_V


def test_two_sweeps_far_from_the_tolerance_are_not_marginal():
    """With the 60 mV figure, U was 0.6 mm at 5 mm/V and a sensor 0.05 mm inside a 0.1 mm
    tolerance read as marginal."""
    rec = _lvdt(2, seed=13)
    x = np.asarray(rec.displacement_mm, dtype=float)
    u = uncertainty(rec, np.full(x.size, 5.0), terms=15, output_lsb_mm=0.001)
    n = np.unique(x).size
    want = 2 * math.sqrt((5.0 * NOISE_V) ** 2 * (1 + 15 / n) + 0.001 ** 2 / 12)
    assert u.expanded_mm == pytest.approx(want, rel=0.2)
    v = judge(ProductionSpec(max_error_mm=0.1), x, np.full(x.size, 0.05), None, (), expanded_mm=u.expanded_mm)
    assert v.verdict == PASS and v.reasons == ()
    assert "along each pass" in u.method and "direction of travel" not in u.method


@pytest.mark.parametrize("prefix, at, key, number", [
    ("FLANN", "2026-12-03T17:15:27+00:00", "8f5dccad16b547ab", "FLANN-20261203-171527-8f5dccad"),
    ("QA.7", "2027-01-31T08:00:05-05:00", "0123456789abcdef", "QA.7-20270131-080005-01234567"),
])
def test_certificate_numbers(prefix, at, key, number):
    assert certificate_number(prefix, at, key) == number


@pytest.mark.parametrize("text, words", [
    ("2026-01-01", "calibration expired"),
    ("31.12.2030", "expected a date YYYY-MM-DD"),
])
def test_a_reference_standard_past_its_due_date_is_refused(text, words):
    with pytest.raises(FlannError, match=words):
        parse_due(text, today=date(2026, 6, 1))
    assert parse_due("2026-06-01", today=date(2026, 6, 1)) == date(2026, 6, 1)
