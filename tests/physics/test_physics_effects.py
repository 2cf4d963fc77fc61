"""Each non-ideal effect changes the output with the sign and magnitude its formula says.

Expectations are built from the ideal model evaluated at hand-transformed positions or
hand-scaled (the effect's physics written out here), not from the effect code."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from flann.physics.effects import EFFECTS
from flann.physics.lvdt import ideal_output_v, inductances_h, null_slope_v_per_mm
from flann.physics.sensor import default_sensor
from flann.physics.simulate import contributions_v, simulate_output_v

X = np.linspace(-28.0, 28.0, 113)


@pytest.fixture(scope="module")
def s():
    return default_sensor()


def test_catalogue_names_exact():
    required = ["null_offset", "quadrature_null", "zero_shift", "secondary_imbalance",
                "backlash", "thermal_drift", "adc_clipping", "leadscrew_periodic"]
    assert list(EFFECTS)[:8] == required
    for e in EFFECTS.values():
        assert e.description and e.formula and e.stage in ("position", "transformer", "output")
        for p in e.params:
            assert p.lower <= p.default <= p.upper and p.lower <= p.neutral <= p.upper


@pytest.mark.parametrize("name", list(EFFECTS))
def test_neutral_parameters_do_nothing(s, name):
    d = np.where(np.arange(X.size) % 2 == 0, 1.0, -1.0)
    y = simulate_output_v(s.replace(effects={name: EFFECTS[name].neutral()}), X, direction=d,
                          temperature_c=np.linspace(0, 60, X.size), time_s=np.arange(X.size))
    np.testing.assert_allclose(y, ideal_output_v(s, X), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("name", list(EFFECTS))
def test_default_parameters_change_the_output(s, name):
    sens = s.replace(demodulator_kind="amplitude") if name == "quadrature_null" else s
    x = np.linspace(-30, 30, 61)
    y = simulate_output_v(sens.with_effect(name), x, direction=np.ones(x.size),
                          temperature_c=np.full(x.size, 45.0))
    assert np.abs(y - ideal_output_v(sens, x)).max() > 1e-3


def test_null_offset_adds_constant(s):
    y = simulate_output_v(s.with_effect("null_offset", offset_v=-0.037), X)
    np.testing.assert_allclose(y - ideal_output_v(s, X), -0.037, atol=1e-12)


def test_zero_shift_moves_null_to_plus_shift(s):
    sens = s.with_effect("zero_shift", shift_mm=1.3)
    root = brentq(lambda x: float(simulate_output_v(sens, np.array([x]))[0]), -5, 5, xtol=1e-10)
    assert root == pytest.approx(1.3, abs=1e-8)
    np.testing.assert_allclose(simulate_output_v(sens, X), ideal_output_v(s, X - 1.3), atol=1e-12)


def test_backlash_lags_against_travel(s):
    b = 0.4
    sens = s.with_effect("backlash", deadband_mm=b)
    up = simulate_output_v(sens, X, direction=np.ones(X.size))
    down = simulate_output_v(sens, X, direction=-np.ones(X.size))
    np.testing.assert_allclose(up, ideal_output_v(s, X - b / 2), atol=1e-12)
    np.testing.assert_allclose(down, ideal_output_v(s, X + b / 2), atol=1e-12)
    # going up the core lags below the commanded position: output lower; gap = slope * b
    gap = simulate_output_v(sens, [0.0], direction=[-1])[0] - simulate_output_v(sens, [0.0], direction=[1])[0]
    assert gap == pytest.approx(null_slope_v_per_mm(s) * b, rel=1e-3)
    # unknown direction: no hysteresis can be applied
    np.testing.assert_allclose(simulate_output_v(sens, X), ideal_output_v(s, X), atol=1e-12)


def test_leadscrew_periodic_position_error(s):
    a, period, phase = 0.05, 3.0, 0.7
    sens = s.with_effect("leadscrew_periodic", amplitude_mm=a, period_mm=period, phase_rad=phase)
    core = X + a * np.sin(2 * math.pi * X / period + phase)
    np.testing.assert_allclose(simulate_output_v(sens, X), ideal_output_v(s, core), atol=1e-12)
    # at a crest (sin = +1) near null the output is high by about slope * a
    x_crest = (math.pi / 2 - phase) * period / (2 * math.pi)
    dy = simulate_output_v(sens, [x_crest])[0] - ideal_output_v(s, [x_crest])[0]
    assert dy == pytest.approx(null_slope_v_per_mm(s) * a, rel=0.01)


def test_thermal_drift_scales_sensitivity(s):
    k, t_ref = -0.002, 20.0
    sens = s.with_effect("thermal_drift", coefficient_per_c=k, reference_temperature_c=t_ref)
    temp = np.linspace(10.0, 50.0, X.size)
    y = simulate_output_v(sens, X, temperature_c=temp)
    np.testing.assert_allclose(y, ideal_output_v(s, X) * (1 + k * (temp - t_ref)), rtol=1e-12, atol=1e-12)
    # warmer than reference with k < 0: magnitude falls; null stays at zero
    assert abs(y[-1]) < abs(ideal_output_v(s, X[-1:])[0])
    assert simulate_output_v(sens, [0.0], temperature_c=[50.0])[0] == pytest.approx(0, abs=1e-12)


def test_secondary_imbalance_leaves_common_mode(s):
    e = 0.02
    sens = s.with_effect("secondary_imbalance", imbalance_fraction=e)
    # At null both secondaries carry the same e.m.f. |v_s| = w M(0) |Ip|; the imbalance
    # leaves e * |v_s| in phase at the demodulator input: output G e |v_s| (positive e:
    # secondary 1 stronger, reads as the core moved to +).
    m1, _m2, lp = (v[0] for v in inductances_h(s, [0.0]))
    w = 2 * math.pi * s.excitation_frequency_hz
    i_p = s.excitation_peak_v / abs(complex(s.primary_resistance_ohm, w * lp))
    want = s.demodulator_gain_ratio * e * w * m1 * i_p
    got = simulate_output_v(sens, [0.0])[0]
    assert got == pytest.approx(want, rel=1e-9)
    assert got > 0


def test_adc_clipping_rails(s):
    rail = 3.0
    sens = s.with_effect("adc_clipping", rail_v=rail)
    y = simulate_output_v(sens, X)
    y0 = ideal_output_v(s, X)
    assert y.max() == pytest.approx(rail) and y.min() == pytest.approx(-rail)
    inside = np.abs(y0) < rail
    np.testing.assert_allclose(y[inside], y0[inside], rtol=1e-12, atol=1e-12)
    # clipping is applied last: an offset cannot push the output past the rail
    both = sens.with_effect("null_offset", offset_v=0.5)
    assert simulate_output_v(both, X).max() == pytest.approx(rail)


def test_quadrature_null_seen_by_amplitude_detector_only(s):
    q = 0.05
    amp = s.replace(demodulator_kind="amplitude")
    y = simulate_output_v(amp.with_effect("quadrature_null", quadrature_v=q), X)
    y0 = ideal_output_v(amp, X)
    # residual at null equals q; elsewhere in quadrature: sqrt(y0^2 + q^2) within the small
    # quadrature part of y0 itself (Ip's phase varies slightly along the stroke)
    assert simulate_output_v(amp.with_effect("quadrature_null", quadrature_v=q), [0.0])[0] == pytest.approx(q, rel=1e-9)
    np.testing.assert_allclose(y, np.hypot(y0, q), rtol=2e-3)
    psd = simulate_output_v(s.with_effect("quadrature_null", quadrature_v=q), X)
    np.testing.assert_allclose(psd, ideal_output_v(s, X), atol=1e-12)


def test_secondary_loading_reduces_output_monotonically(s):
    x = np.array([5.0, 15.0, 25.0])
    y0 = ideal_output_v(s, x)
    prev = y0
    for r_load in (1e7, 1e5, 1e4):
        y = simulate_output_v(s.with_effect("secondary_loading", load_ohm=r_load), x)
        assert np.all(y < prev) and np.all(y > 0)
        prev = y
    y_light = simulate_output_v(s.with_effect("secondary_loading", load_ohm=1e12), x)
    np.testing.assert_allclose(y_light, y0, rtol=1e-5)
    assert simulate_output_v(s.with_effect("secondary_loading", load_ohm=1e4), [0.0])[0] == pytest.approx(0, abs=1e-12)


def test_contributions_isolate_each_effect(s):
    sens = s.with_effect("null_offset", offset_v=0.01).with_effect("zero_shift", shift_mm=0.5)
    c = contributions_v(sens, X)
    np.testing.assert_allclose(c["null_offset"], 0.01, atol=1e-12)
    np.testing.assert_allclose(c["zero_shift"], ideal_output_v(s, X - 0.5) - ideal_output_v(s, X), atol=1e-12)
    # these two act on different stages and add exactly
    np.testing.assert_allclose(c["all"], c["null_offset"] + c["zero_shift"], atol=1e-12)


def test_copper_thermal_coefficient_matches_primary_current(s):
    # Independent: heat the primary's copper by 1 degC (R * (1 + 0.00393)) and compare the
    # ideal output's change with the predicted coefficient.
    from flann.physics.effects import thermal_coefficient_from_copper

    k = thermal_coefficient_from_copper(s)
    hot = s.replace(primary_resistance_ohm=s.primary_resistance_ohm * (1 + 0.00393))
    x = np.array([2.0])
    ratio = ideal_output_v(hot, x)[0] / ideal_output_v(s, x)[0] - 1
    assert k < 0
    assert ratio == pytest.approx(k, rel=0.01)


def test_copper_thermal_coefficient_with_lossy_core(s):
    from flann.physics.effects import thermal_coefficient_from_copper

    lossy = s.replace(core_conductivity_s_per_m=1e7, primary_resistance_ohm=600.0)
    k = thermal_coefficient_from_copper(lossy)
    hot = lossy.replace(primary_resistance_ohm=600.0 * (1 + 0.00393))
    x = np.array([2.0])
    ratio = abs(ideal_output_v(hot, x)[0] / ideal_output_v(lossy, x)[0]) - 1
    assert ratio == pytest.approx(k, rel=0.02)
