"""Simulated recordings (sweeps, seed, noise, ADC, temperature), the CLI, and calibration."""

import json

import numpy as np
import pytest

from flann.cli import main
from flann.errors import FlannError
from flann.physics.fit import fit_sensor
from flann.physics.lvdt import ideal_output_v
from flann.physics.sensor import default_sensor
from flann.physics.simulate import (
    adc_convert, parse_temperature_profile, simulate_output_v, simulate_recordings, sweep_positions,
)
from flann.recordings import Recordings, read_recordings


def test_sweep_positions_forward_reverse():
    x, d = sweep_positions((-2.0, 2.0), 1.0, 2)
    np.testing.assert_array_equal(x, [-2, -1, 0, 1, 2, 1, 0, -1, -2, -1, 0, 1, 2, 1, 0, -1, -2])
    np.testing.assert_array_equal(d, [1] * 5 + [-1] * 4 + [1] * 4 + [-1] * 4)


def test_recordings_columns_seed_and_noise():
    s = default_sensor().replace(adc_bits=None, adc_full_scale_v=None)
    a = simulate_recordings(s, sweeps=3, step_mm=0.5, noise_v=0.01, seed=7)
    b = simulate_recordings(s, sweeps=3, step_mm=0.5, noise_v=0.01, seed=7)
    c = simulate_recordings(s, sweeps=3, step_mm=0.5, noise_v=0.01, seed=8)
    np.testing.assert_array_equal(a.voltage_v, b.voltage_v)
    assert not np.array_equal(a.voltage_v, c.voltage_v)
    for col in ("direction", "time_s", "temperature_c"):
        assert getattr(a, col) is not None and getattr(a, col).size == len(a)
    assert set(np.unique(a.direction)) == {-1.0, 1.0}
    assert np.all(np.diff(a.time_s) == 1.0)
    resid = a.voltage_v - ideal_output_v(s, a.displacement_mm)
    assert np.std(resid) == pytest.approx(0.01, rel=0.1)
    assert abs(np.mean(resid)) < 3 * 0.01 / np.sqrt(len(a))


def test_adc_quantises_and_saturates():
    s = default_sensor()        # 16 bits, +-10 V: LSB = 20 V / 65536
    lsb = 20.0 / 65536
    y = adc_convert(s, np.array([0.3 * lsb, 0.7 * lsb, 12.0, -12.0]))
    np.testing.assert_allclose(y, [0.0, lsb, 10.0 - lsb, -10.0])
    r = simulate_recordings(s, step_mm=5.0)
    codes = r.voltage_v / lsb
    np.testing.assert_allclose(codes, np.round(codes), atol=1e-6)


def test_adc_ties_round_up_as_in_the_hardwares_converter():
    """A reading exactly between two codes takes the code above, as eval, calibrate and trace
    do (round half to even would take 0, 2, -2 here)."""
    s = default_sensor()
    lsb = 20.0 / 65536      # a power of two: the ties are exact
    ties = np.array([0.5, 1.5, -1.5, -2.5]) * lsb
    np.testing.assert_array_equal(adc_convert(s, ties) / lsb, [1, 2, -1, -2])


def test_temperature_profile_ramp_drives_thermal_drift():
    s = default_sensor().with_effect("thermal_drift", coefficient_per_c=-0.004,
                                     reference_temperature_c=20.0)
    r = simulate_recordings(s, sweeps=1, step_mm=1.0, temperature_profile="ramp:20:40")
    assert r.temperature_c[0] == 20.0 and r.temperature_c[-1] == 40.0
    ratio = r.voltage_v[-1] / ideal_output_v(s, r.displacement_mm[-1:])[0]
    assert ratio == pytest.approx(1 - 0.004 * 20, abs=2e-3)   # ADC LSB on ~5 V


@pytest.mark.parametrize("spec", ["ramp:20", "sine:1:2", "warm", "const:-300", "sine:20:1:0"])
def test_bad_temperature_profiles(spec):
    with pytest.raises(FlannError, match="temperature-profile"):
        parse_temperature_profile(spec)


def test_cli_simulate_writes_readable_recordings(tmp_path, capsys):
    out = tmp_path / "rec.csv"
    png = tmp_path / "rec.png"
    rc = main(["simulate", "data/sensors/paper_lvdt_effects.toml", "-o", str(out), "--sweeps", "2",
               "--step-mm", "2", "--noise-v", "0.002", "--seed", "3",
               "--temperature-profile", "ramp:20:30", "--plot", str(png)])
    assert rc == 0
    rec = read_recordings(out)
    assert len(rec) == 31 + 30 + 30 + 30   # -30..30 step 2, back to -30, forth, back
    assert rec.direction is not None and rec.temperature_c[-1] == pytest.approx(30.0)
    assert any("effects: null_offset" in c for c in rec.comments)
    assert png.stat().st_size > 10_000
    again = tmp_path / "again.csv"
    main(["simulate", "data/sensors/paper_lvdt_effects.toml", "-o", str(again), "--sweeps", "2",
          "--step-mm", "2", "--noise-v", "0.002", "--seed", "3", "--temperature-profile", "ramp:20:30"])
    assert again.read_text() == out.read_text()


@pytest.mark.parametrize("args, fragment", [
    (["--step-mm", "0"], "--step-mm"),
    (["--sweeps", "0"], "--sweeps"),
    (["--noise-v", "-1"], "--noise-v"),
    (["--from-mm", "5", "--to-mm", "1"], "travel"),
    (["--temperature-profile", "hot"], "temperature-profile"),
])
def test_cli_bad_options_exit_2(tmp_path, capsys, args, fragment):
    out = tmp_path / "r.csv"
    assert main(["simulate", "-o", str(out), *args]) == 2
    err = capsys.readouterr().err
    assert fragment in err and err.count("\n") == 1
    assert not out.exists()


def test_fit_recovers_known_geometry():
    truth = default_sensor().replace(primary_length_mm=6.0, secondary_length_mm=24.0,
                                     secondary_gap_mm=8.0, demodulator_gain_ratio=1.3)
    x = np.arange(-30.0, 30.5, 1.0)
    rec = Recordings(displacement_mm=x, voltage_v=ideal_output_v(truth, x))
    fit = fit_sensor(rec, starts=2)
    assert fit.rms_v < 1e-4
    assert fit.values["primary_length_mm"] == pytest.approx(6.0, rel=1e-2)
    assert fit.values["secondary_length_mm"] == pytest.approx(24.0, rel=1e-2)
    assert fit.values["secondary_gap_mm"] == pytest.approx(8.0, rel=1e-2)
    assert fit.values["demodulator_gain_ratio"] == pytest.approx(1.3, rel=1e-2)
    assert fit.excluded_rows == ()


def test_fit_table1_excludes_the_10mm_point(tmp_path, capsys):
    js = tmp_path / "fit.json"
    rc = main(["simulate", "--fit", "data/paper_table1.csv", "--json", str(js),
               "--write-sensor", str(tmp_path / "fitted.toml")])
    assert rc == 0
    rep = json.loads(js.read_text())
    assert [e["displacement_mm"] for e in rep["excluded"]] == [10.0]
    assert rep["excluded"][0]["residual_v"] < -0.8          # 1.810 V vs ~2.9 V expected
    assert rep["points_used"] == 12
    assert rep["rms_v"] < 0.1                               # docs/physics.md states the figure
    assert "excluded row 8" in capsys.readouterr().out


def test_simulate_output_matches_ideal_without_effects():
    s = default_sensor()
    x = np.linspace(-40, 40, 81)
    np.testing.assert_allclose(simulate_output_v(s, x), ideal_output_v(s, x), rtol=1e-12, atol=1e-12)


def test_fit_scales_to_a_miniature_sensor():
    from flann.physics.sensor import load_sensor

    truth = load_sensor("data/sensors/miniature_reversed.toml")
    start = truth.replace(primary_length_mm=4.0, secondary_length_mm=3.0, secondary_gap_mm=1.0,
                          demodulator_gain_ratio=-1.0)
    # past the rated stroke, through the output peaks (inside +-2.5 mm only the slope and a
    # little curvature are seen: the geometry would not be identifiable)
    x = np.linspace(-7.0, 7.0, 57)
    rec = Recordings(displacement_mm=x, voltage_v=ideal_output_v(truth, x))
    fit = fit_sensor(rec, sensor=start, starts=2)
    assert fit.rms_v < 1e-3
    assert fit.values["demodulator_gain_ratio"] < 0
    assert fit.values["secondary_gap_mm"] == pytest.approx(0.5, abs=0.1)


def test_fold_back_warning_beyond_the_output_peak(tmp_path, capsys):
    from flann.physics.simulate import fold_back_mm

    s = default_sensor()
    x = np.linspace(0, 60, 6001)
    peak = x[np.argmax(ideal_output_v(s, x))]          # independent: the output maximum
    assert fold_back_mm(s, (-60.0, 60.0)) == pytest.approx(peak, abs=0.1)
    assert fold_back_mm(s, (-0.8 * peak, 0.8 * peak)) is None
    out = tmp_path / "r.csv"
    assert main(["simulate", "-o", str(out), "--from-mm", "-60", "--to-mm", "60"]) == 0
    err = capsys.readouterr().err
    assert "warning: travel -60..60 mm goes past" in err and out.exists()


def test_cli_lists_effects(capsys):
    from flann.physics.effects import EFFECTS

    assert main(["simulate", "--list-effects"]) == 0
    out = capsys.readouterr().out
    for name, e in EFFECTS.items():
        assert f"[effects.{name}]" in out
        for p in e.params:
            assert f"{p.name} = " in out


def test_sensor_hashable_and_effects_distinguish():
    s = default_sensor()
    assert len({s, s.replace(), s.with_effect("backlash"), s.with_effect("backlash", deadband_mm=0.3)}) == 3


def test_describe_figures(capsys):
    import math as m

    from flann.physics.lvdt import describe, inductances_h

    s = default_sensor()
    d = describe(s)
    lp = inductances_h(s, [0.0])[2][0]
    w = 2 * m.pi * s.excitation_frequency_hz
    assert d["primary_current_ma_peak"] == pytest.approx(
        1e3 * 5.0 / m.hypot(s.primary_resistance_ohm, w * lp), rel=1e-9)
    assert 0 < d["core_peak_flux_density_mt"] < 1000            # far from saturation
    # decay length from the per-unit-length constants written out by hand
    mu0 = 4e-7 * m.pi
    a_core = m.pi / 4 * (5.0**2 - 4.4**2) * 1e-6
    a_air = m.pi * ((6.0 + 14.0) / 4 * 1e-3) ** 2
    r = 1 / (mu0 * (220 * a_core + a_air - a_core))
    g = 2 * m.pi * mu0 / m.log(20.0 / 5.0)
    assert d["core_decay_length_mm"] == pytest.approx(1e3 / m.sqrt(r * g), rel=1e-9)
    assert main(["simulate", "--describe"]) == 0
    assert "output_fold_back_mm = 30" in capsys.readouterr().out


def test_describe_plot(tmp_path):
    png = tmp_path / "anatomy.png"
    assert main(["simulate", "data/sensors/miniature_reversed.toml", "--describe", "--plot", str(png)]) == 0
    assert png.stat().st_size > 10_000


def test_plot_that_fails_to_render_leaves_no_file(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    from flann.physics.plots import plot_anatomy

    def broken(self, *a, **k):
        raise RuntimeError("renderer failed")

    monkeypatch.setattr(Figure, "savefig", broken)
    with pytest.raises(RuntimeError):
        plot_anatomy(default_sensor(), tmp_path / "anatomy.png")
    assert list(tmp_path.iterdir()) == []


def test_plot_of_a_sensor_without_effects_warns_nothing(tmp_path, cli):
    """No effect to draw: the panel says so, with no empty legend (matplotlib warns of one)."""
    png = tmp_path / "ideal.png"
    rc, _out, err = cli(["simulate", "data/sensors/paper_lvdt.toml", "--no-effects", "-o", tmp_path / "r.csv",
                         "--step-mm", "2", "--plot", png])
    assert rc == 0 and png.stat().st_size > 10_000
    assert "warning" not in err
