"""The construction's temperature model (thermal_construction) and flann simulate --temperatures."""

import numpy as np
import pytest

from flann.cli import main
from flann.physics.sensor import default_sensor, load_sensor
from flann.physics.simulate import simulate_calibration, simulate_output_v
from flann.recordings import read_recordings

X = np.linspace(-25, 25, 41)
REF = 20.0


def construction(**kw):
    p = {"reference_temperature_c": REF, "copper_tempco_per_c": 0.0, "source_resistance_ohm": 0.0,
         "permeability_tempco_per_c": 0.0, "balance_drift_per_c": 0.0, **kw}
    return plain().with_effect("thermal_construction", **p)


def plain():
    """Amplitude detector: the comparisons below do not depend on the demodulator's phase
    reference (set once, at the reference temperature, for a phase-sensitive one)."""
    return default_sensor().replace(demodulator_kind="amplitude") \
        .with_effect("secondary_loading", load_ohm=5000.0)


def test_copper_is_the_sensor_with_heated_windings_and_the_source_in_series():
    temp = 70.0
    s = construction(copper_tempco_per_c=0.00393, source_resistance_ohm=50.0)
    k = 1 + 0.00393 * (temp - REF)
    heated = plain().replace(primary_resistance_ohm=50.0 + 60.0 * k, secondary_resistance_ohm=200.0 * k)
    np.testing.assert_allclose(simulate_output_v(s, X, temperature_c=temp),
                               simulate_output_v(heated, X), rtol=1e-9, atol=1e-12)
    at_ref = plain().replace(primary_resistance_ohm=50.0 + 60.0)
    np.testing.assert_allclose(simulate_output_v(s, X, temperature_c=REF),
                               simulate_output_v(at_ref, X), rtol=1e-9, atol=1e-12)
    assert not np.allclose(simulate_output_v(heated, X), simulate_output_v(at_ref, X), rtol=1e-4)


def test_permeability_is_the_sensor_with_another_core():
    s = construction(permeability_tempco_per_c=0.001)
    core = plain().replace(core_permeability_ratio=220.0 * (1 + 0.001 * 30.0))
    np.testing.assert_allclose(simulate_output_v(s, X, temperature_c=REF + 30.0),
                               simulate_output_v(core, X), rtol=1e-9, atol=1e-12)


def test_balance_drift_is_a_secondary_imbalance_growing_with_temperature():
    s = construction(balance_drift_per_c=1e-4)
    imb = plain().with_effect("secondary_imbalance", imbalance_fraction=1e-4 * 40.0)
    np.testing.assert_allclose(simulate_output_v(s, X, temperature_c=REF + 40.0),
                               simulate_output_v(imb, X), rtol=1e-9, atol=1e-12)


def test_a_ramp_of_many_temperatures_matches_sample_by_sample():
    s = construction(permeability_tempco_per_c=0.002, copper_tempco_per_c=0.00393)
    temp = np.linspace(-20, 80, X.size)          # 41 distinct: interpolated between nodes
    y = simulate_output_v(s, X, temperature_c=temp)
    exact = np.array([simulate_output_v(s, X[i:i + 1], temperature_c=temp[i])[0] for i in range(X.size)])
    np.testing.assert_allclose(y, exact, rtol=0, atol=1e-6 * np.abs(exact).max())


def test_the_paper_lvdt_thermal_file_drifts_like_an_lvdt(data_dir):
    s = load_sensor(data_dir / "sensors" / "paper_lvdt_thermal.toml")
    y = {t: simulate_output_v(s, X, temperature_c=t) for t in (-20.0, 80.0)}
    span = {t: v[-1] - v[0] for t, v in y.items()}
    per_c = (span[80.0] / span[-20.0] - 1) / 100
    assert 1e-4 <= abs(per_c) <= 5e-4                     # 0.01 .. 0.05 % per degC
    null = {t: np.interp(0.0, X, v) for t, v in y.items()}
    assert abs(null[80.0] - null[-20.0]) / (span[-20.0] / 2) / 100 < 20e-6   # a few ppm FS/degC


def test_simulate_calibration_soaks_at_each_temperature():
    s = construction(copper_tempco_per_c=0.00393)
    rec = simulate_calibration(s, (-20.0, 25.0), step_mm=5.0, travel_mm=(-25.0, 25.0))
    assert len(rec) == 2 * 21 and list(np.unique(rec.temperature_c)) == [-20.0, 25.0]
    assert np.all(np.diff(rec.time_s) > 0)
    first = rec.subset(rec.temperature_c == -20.0)
    np.testing.assert_allclose(first.voltage_v, np.round(
        simulate_output_v(s, first.displacement_mm, temperature_c=-20.0) / (20 / 2 ** 16)) * (20 / 2 ** 16))


def test_simulate_temperatures_cli(tmp_path, capsys, data_dir):
    out = tmp_path / "cal.csv"
    rc = main(["simulate", str(data_dir / "sensors" / "paper_lvdt_thermal.toml"), "--temperatures",
               "-20,25,80", "--step-mm", "5", "--from-mm", "-25", "--to-mm", "25", "-o", str(out)])
    assert rc == 0
    rec = read_recordings(out)
    assert sorted(set(rec.temperature_c)) == [-20.0, 25.0, 80.0] and len(rec) == 3 * 21
    assert "calibration at -20, 25, 80 degC" in out.read_text()
    capsys.readouterr()
    for bad in ("-20,25,-20", "hot"):
        rc = main(["simulate", f"--temperatures={bad}", "-o", str(tmp_path / "x.csv")])
        err = capsys.readouterr().err
        assert rc == 2 and err.count("\n") == 1 and not (tmp_path / "x.csv").exists()
    rc = main(["simulate", "--temperatures", "0,50", "--temperature-profile", "ramp:0:50",
               "-o", str(tmp_path / "x.csv")])
    assert rc == 2
