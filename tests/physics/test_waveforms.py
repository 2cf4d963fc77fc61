"""Simulated waveforms: demodulated by a float lock-in over whole carrier periods they give the
simulator's demodulated output; drift, quadrature, harmonics and noise as specified; the CLI."""

import math

import numpy as np
import pytest

from flann.physics.lvdt import reference_phase_rad
from flann.physics.sensor import default_sensor
from flann.physics.simulate import simulate_output_v
from flann.physics.waveforms import (WaveformSettings, parse_trajectory, simulate_waveforms)
from flann.recordings.waveform import read_waveforms

EXACT = dict(adc_bits=32, adc_range_v=20.0, sample_rate_hz=200_000.0)   # a converter far below every tolerance here


def _lockin(wave, carrier_hz, phase_rad, dwell_samples):
    """Per dwell, the in-phase and quadrature amplitudes of A and B (float, whole periods)."""
    n = len(wave) // dwell_samples
    t = wave.time_s[: n * dwell_samples]
    ref_i = 2 * np.cos(2 * math.pi * carrier_hz * t + phase_rad)
    ref_q = -2 * np.sin(2 * math.pi * carrier_hz * t + phase_rad)

    def per_dwell(v):
        return v[: n * dwell_samples].reshape(n, dwell_samples).mean(axis=1)

    a, b = wave.sec_a_v, wave.sec_b_v
    return (per_dwell(a * ref_i), per_dwell(a * ref_q), per_dwell(b * ref_i), per_dwell(b * ref_q),
            per_dwell(wave.displacement_mm))


def _sensor(**effects):
    s = default_sensor()
    for name, params in effects.items():
        s = s.with_effect(name, **params)
    return s


@pytest.mark.parametrize("effects", [{}, {"secondary_imbalance": {"imbalance_fraction": 0.02},
                                          "secondary_loading": {"load_ohm": 20000.0}}])
def test_lockin_of_the_waveforms_gives_the_dc_output(effects):
    s = _sensor(**effects)
    fs, carrier = 200_000.0, 5000.0
    wave = simulate_waveforms(s, WaveformSettings(**EXACT), parse_trajectory("steps:0.002"),
                              travel_mm=(-20.0, 20.0), step_mm=5.0)
    ia, _qa, ib, _qb, x = _lockin(wave, carrier, reference_phase_rad(s), int(0.002 * fs))
    dc = simulate_output_v(s, x)
    got = s.demodulator_gain_ratio * (ia - ib)
    np.testing.assert_allclose(got, dc, atol=1e-6 * np.max(np.abs(dc)))


def test_ratio_ignores_excitation_drift():
    s = _sensor()
    traj = parse_trajectory("steps:0.002")
    args = dict(travel_mm=(-20.0, 20.0), step_mm=10.0)
    ratios = []
    for drift in (0.0, 10.0):
        wave = simulate_waveforms(s, WaveformSettings(excitation_drift_pct=drift, **EXACT), traj, **args)
        ia, _qa, ib, _qb, _x = _lockin(wave, 5000.0, reference_phase_rad(s), 400)
        ratios.append((ia - ib) / (ia + ib))
        if drift:   # the excitation itself grew by the drift over the run
            assert np.max(wave.exc_v[-400:]) == pytest.approx(5.0 * (1 + drift / 100), rel=1e-3)
    np.testing.assert_allclose(ratios[1], ratios[0], atol=1e-9)


def test_quadrature_effect_is_in_quadrature_with_the_reference():
    q = 0.05
    s = _sensor(quadrature_null={"quadrature_v": q})
    wave = simulate_waveforms(s, WaveformSettings(**EXACT), parse_trajectory("steps:0.002"),
                              travel_mm=(-10.0, 10.0), step_mm=10.0)
    ia, qa, ib, qb, x = _lockin(wave, 5000.0, reference_phase_rad(s), 400)
    clean = simulate_waveforms(s.without_effects(), WaveformSettings(**EXACT), parse_trajectory("steps:0.002"),
                               travel_mm=(-10.0, 10.0), step_mm=10.0)
    ia0, qa0, ib0, qb0, _ = _lockin(clean, 5000.0, reference_phase_rad(s), 400)
    g = s.demodulator_gain_ratio
    np.testing.assert_allclose(g * ((qa - qb) - (qa0 - qb0)), q, rtol=1e-6)
    np.testing.assert_allclose(ia - ib, ia0 - ib0, atol=1e-7)   # the 32-bit converter's rounding


def test_third_harmonic_and_noise():
    s = _sensor()
    h, noise = 2.0, 0.003
    wave = simulate_waveforms(s, WaveformSettings(harmonic_pct=h, noise_v=noise, seed=3, **EXACT),
                              parse_trajectory("steps:0.01"), travel_mm=(0.0, 1.0), step_mm=1.0)
    spectrum = np.abs(np.fft.rfft(wave.exc_v[:2000]))   # 0.01 s: 50 whole carrier periods
    assert spectrum[150] / spectrum[50] == pytest.approx(h / 100, rel=1e-6)
    quiet = simulate_waveforms(s, WaveformSettings(harmonic_pct=h, **EXACT), parse_trajectory("steps:0.01"),
                               travel_mm=(0.0, 1.0), step_mm=1.0)
    assert np.std(wave.sec_a_v - quiet.sec_a_v) == pytest.approx(noise, rel=0.05)
    again = simulate_waveforms(s, WaveformSettings(harmonic_pct=h, noise_v=noise, seed=3, **EXACT),
                               parse_trajectory("steps:0.01"), travel_mm=(0.0, 1.0), step_mm=1.0)
    np.testing.assert_array_equal(again.sec_a_v, wave.sec_a_v)


def test_adc_saturates_and_rounds():
    s = _sensor()
    wave = simulate_waveforms(s, WaveformSettings(adc_bits=8, adc_range_v=1.0), parse_trajectory("steps:0.001"),
                              travel_mm=(-20.0, 20.0), step_mm=20.0)
    lsb = 2.0 / 256
    assert np.max(wave.sec_b_v) == pytest.approx(1.0 - lsb) and np.min(wave.sec_b_v) == pytest.approx(-1.0)
    np.testing.assert_allclose(wave.sec_a_v / lsb, np.round(wave.sec_a_v / lsb), atol=1e-9)


def test_trajectories():
    s = _sensor()
    ramp = simulate_waveforms(s, WaveformSettings(**EXACT), parse_trajectory("ramp:0.01"), travel_mm=(-5.0, 5.0))
    assert ramp.displacement_mm[0] == -5.0 and np.all(np.diff(ramp.displacement_mm) > 0)
    sine = simulate_waveforms(s, WaveformSettings(**EXACT), parse_trajectory("sine:100:0.02"),
                              travel_mm=(-5.0, 5.0))
    assert np.max(sine.displacement_mm) == pytest.approx(5.0, abs=1e-3)
    assert len(sine) == 4000


def test_a_calibration_at_several_temperatures_runs_the_trajectory_at_each_in_turn():
    s = _sensor(thermal_construction={"reference_temperature_c": 25.0, "copper_tempco_per_c": 0.00393,
                                      "source_resistance_ohm": 50.0, "permeability_tempco_per_c": 2e-4,
                                      "balance_drift_per_c": 2e-6})
    traj, args = parse_trajectory("steps:0.002"), dict(travel_mm=(-20.0, 20.0), step_mm=10.0)
    soaks = (0.0, 50.0)
    wave = simulate_waveforms(s, WaveformSettings(**EXACT), traj, temperatures=soaks, **args)
    each = [simulate_waveforms(s, WaveformSettings(**EXACT), traj, temperature_profile=f"const:{t:g}", **args)
            for t in soaks]
    n = len(each[0])
    assert len(wave) == 2 * n and np.all(np.diff(wave.time_s) > 0)
    for k, one in enumerate(each):
        part = slice(k * n, (k + 1) * n)
        assert np.all(wave.temperature_c[part] == soaks[k])
        np.testing.assert_array_equal(wave.displacement_mm[part], one.displacement_mm)
        # the pass takes whole carrier periods: each soak's secondaries are its own run's
        np.testing.assert_allclose(wave.sec_a_v[part], one.sec_a_v, atol=1e-7)
        np.testing.assert_allclose(wave.sec_b_v[part], one.sec_b_v, atol=1e-7)
    # the excitation runs on across the soaks: no jump in its phase where the temperature steps
    np.testing.assert_allclose(wave.exc_v, s.excitation_peak_v * np.cos(2 * math.pi * 5000.0 * wave.time_s), atol=1e-9)
    # and the sensor's temperature is in the secondaries: the hot soak's differ from the cold one's
    ia = [_lockin(w, 5000.0, reference_phase_rad(s), 400)[0] for w in each]
    assert np.max(np.abs(ia[0] - ia[1])) > 1e-3 * np.max(np.abs(ia[0]))


def test_cli_writes_a_waveform_file_the_reader_reads(cli, tmp_path):
    out = tmp_path / "wave.csv"
    rc, _out, err = cli(["simulate", "--waveforms", "-o", out, "--step-mm", "10", "--trajectory", "steps:0.002",
                         "--carrier-hz", "2500", "--adc-bits", "12", "--noise-v", "0.001"])
    assert rc == 0, err
    wave = read_waveforms(out)
    assert wave.sample_rate_hz == pytest.approx(80_000.0)   # 32 samples a carrier period
    assert wave.exc_v is not None and wave.temperature_c is not None
    assert any("ADC 12 bits" in c for c in wave.comments)


@pytest.mark.parametrize("argv, words", [
    *[(["--waveforms", "--trajectory", bad], "--trajectory") for bad in ("steps", "ramp:-1", "sine:10",
                                                                          "wobble:1", "ramp:x")],
    (["--waveforms", "--sample-rate-hz", "6000"], "--sample-rate-hz"),
    (["--waveforms", "--trajectory", "ramp:100"], "more than a recording holds"),
    (["--carrier-hz", "2500"], "need --waveforms"),
    (["--waveforms", "--temperatures", "0,50", "--temperature-profile", "ramp:0:50"], "either"),
    (["--waveforms", "--temperatures", "0,0"], "repeated"),
])
def test_cli_refuses_in_one_line(cli, tmp_path, argv, words):
    out = tmp_path / "wave.csv"
    rc, _out, err = cli(["simulate", "-o", out, *argv])
    assert rc == 2 and words in err and "Traceback" not in err
    assert not out.exists()
