"""Physics sanity of the ideal LVDT model (flann.physics.lvdt).

Expected values come from an independent finite-difference network solved with
scipy.sparse, from closed-form limits (long solenoid, lossless primary) or from symmetry
and scaling laws -- never from the code under test.
"""

import math

import numpy as np
import pytest
from scipy.sparse import diags
from scipy.sparse.linalg import spsolve

from flann.physics import lvdt
from flann.physics.sensor import default_sensor, load_sensor

MU0 = 4e-7 * math.pi


def _fd_inductances(s, p_mm, n=20001, half_mm=400.0):
    """Independent check: the same magnetic line discretised into n nodes (lumped branch
    reluctances with the core's and windings' exact overlap, node leakage), solved as a
    sparse system; geometry taken from the sensor fields directly."""
    mm = 1e-3
    z = np.linspace(-half_mm, half_mm, n) * mm
    h = z[1] - z[0]
    a_core = math.pi / 4 * (s.core_outer_diameter_mm**2 - s.core_inner_diameter_mm**2) * mm**2
    r_mean = (s.coil_inner_diameter_mm + s.coil_outer_diameter_mm) / 4 * mm
    a_air = math.pi * r_mean**2
    r_core = 1 / (MU0 * (s.core_permeability_ratio * a_core + a_air - a_core))
    r_air = 1 / (MU0 * a_air)
    g = 2 * math.pi * MU0 / math.log(s.housing_inner_diameter_mm / s.core_outer_diameter_mm)
    a1 = s.primary_length_mm / 2 * mm
    a2 = a1 + s.secondary_gap_mm * mm
    a3 = a2 + s.secondary_length_mm * mm

    def overlap(lo, hi):  # length of [lo, hi] inside each branch [z_i, z_i+1]
        return np.clip(np.minimum(z[1:], hi) - np.maximum(z[:-1], lo), 0, None)

    half = s.core_length_mm / 2 * mm
    inside = overlap(p_mm * mm - half, p_mm * mm + half)
    c = 1 / (inside * r_core + (h - inside) * r_air)
    n_p = overlap(-a1, a1) * s.primary_turns / (2 * a1)
    n_s1 = overlap(a2, a3) * s.secondary_turns / (a3 - a2)
    n_s2 = overlap(-a3, -a2) * s.secondary_turns / (a3 - a2)
    d = np.full(n, g * h)
    d[:-1] += c
    d[1:] += c
    a = diags([d, -c, -c], [0, 1, -1], format="csc")
    rhs = np.zeros(n)
    rhs[:-1] -= c * n_p
    rhs[1:] += c * n_p
    u = spsolve(a, rhs)
    phi = c * (u[:-1] - u[1:] + n_p)
    return phi @ n_s1, phi @ n_s2, phi @ n_p


@pytest.mark.parametrize("p_mm", [0.0, 7.5, -22.0, 41.0])
def test_exact_line_matches_independent_finite_differences(p_mm):
    s = default_sensor()
    want = _fd_inductances(s, p_mm)
    got = [float(v[0]) for v in lvdt.inductances_h(s, [p_mm])]
    for g, w in zip(got, want):
        assert g == pytest.approx(w, rel=1e-4)


def test_long_uniform_core_carries_mu_r_flux():
    # A core and primary much longer than the decay length: in the middle the line carries
    # the long-solenoid flux Phi = mu0 (mu_r A_core + A_air - A_core) N I / L.
    s = default_sensor().replace(primary_length_mm=800.0, core_length_mm=1200.0,
                                 secondary_gap_mm=1.0, secondary_length_mm=10.0)
    mm = 1e-3
    a_core = math.pi / 4 * (5.0**2 - 4.4**2) * mm**2
    a_air = math.pi * ((6.0 + 14.0) / 4 * mm) ** 2
    want = MU0 * (s.core_permeability_ratio * a_core + a_air - a_core) * 1500 / (800 * mm)
    got = lvdt.flux_profile(s, 0.0, [0.0])[0]
    assert got == pytest.approx(want, rel=1e-6)


def test_output_odd_and_zero_at_null():
    s = default_sensor()
    x = np.linspace(0.0, 45.0, 91)
    y_pos = lvdt.ideal_output_v(s, x)
    y_neg = lvdt.ideal_output_v(s, -x)
    assert abs(y_pos[0]) < 1e-12
    np.testing.assert_allclose(y_neg, -y_pos, atol=1e-12)
    assert np.all(y_pos[1:] > 0)     # positive gain, secondary 1 on the +z side


def test_sensitivity_scales_with_excitation_amplitude():
    s = default_sensor()
    x = np.linspace(-30, 30, 61)
    y1 = lvdt.ideal_output_v(s, x)
    y2 = lvdt.ideal_output_v(s.replace(excitation_amplitude_vpp=2.5 * s.excitation_amplitude_vpp), x)
    np.testing.assert_allclose(y2, 2.5 * y1, rtol=1e-12, atol=1e-12)


def test_sensitivity_scales_with_secondary_turns():
    s = default_sensor()
    x = np.linspace(-30, 30, 61)
    y1 = lvdt.ideal_output_v(s, x)
    y2 = lvdt.ideal_output_v(s.replace(secondary_turns=2 * s.secondary_turns), x)
    np.testing.assert_allclose(y2, 2 * y1, rtol=1e-12, atol=1e-12)


def _peak_position(s):
    x = np.linspace(0, 120, 4801)
    return x[np.argmax(lvdt.ideal_output_v(s, x))]


def test_end_of_stroke_rolloff_moves_outward_with_longer_core():
    s = default_sensor()
    peaks = [_peak_position(s.replace(core_length_mm=L)) for L in (40.0, 60.0, 80.0)]
    assert peaks[0] < peaks[1] < peaks[2]
    # and the output has rolled off (not a polynomial): beyond the peak it falls
    y = lvdt.ideal_output_v(s, np.array([peaks[1], peaks[1] + 20.0]))
    assert y[1] < 0.9 * y[0]


def test_output_vanishes_when_core_has_left():
    s = default_sensor()
    far = s.coil_span_mm / 2 + s.core_length_mm / 2 + 100.0
    y_far = lvdt.ideal_output_v(s, np.array([far, -far]))
    y_max = np.abs(lvdt.ideal_output_v(s, np.linspace(-60, 60, 241))).max()
    assert np.all(np.abs(y_far) < 1e-3 * y_max)


def test_lossless_primary_gives_inphase_emf():
    # With R_p = 0 the primary current lags the voltage by 90 deg and j w M I = (M/Lp) V:
    # the secondary e.m.f.s are in phase with the excitation voltage.
    s = default_sensor().replace(primary_resistance_ohm=0.0)
    v1, v2 = lvdt.secondary_emf_v(s, np.array([5.0]))
    m1, m2, lp = lvdt.inductances_h(s, np.array([5.0]))
    assert v1[0].imag == pytest.approx(0.0, abs=1e-12)
    assert v1[0].real == pytest.approx(s.excitation_peak_v * m1[0] / lp[0], rel=1e-12)
    assert lvdt.reference_phase_rad(s) == pytest.approx(0.0, abs=1e-12)


def test_amplitude_detector_is_unsigned():
    s = default_sensor().replace(demodulator_kind="amplitude")
    psd = default_sensor()
    x = np.linspace(-25, 25, 51)
    y = lvdt.ideal_output_v(s, x)
    assert np.all(y >= 0)
    # |in-phase| <= amplitude; equal within the phase change of Ip along the stroke
    assert np.all(y + 1e-12 >= np.abs(lvdt.ideal_output_v(psd, x)))
    np.testing.assert_allclose(y, np.abs(lvdt.ideal_output_v(psd, x)), rtol=0.02)


def test_negative_gain_reverses_output():
    s = load_sensor("data/sensors/miniature_reversed.toml")
    assert lvdt.null_slope_v_per_mm(s) < 0
    assert lvdt.null_slope_v_per_mm(s.replace(demodulator_gain_ratio=3.0)) == pytest.approx(
        -lvdt.null_slope_v_per_mm(s), rel=1e-12)


def test_ideal_output_fast_path_is_cached_per_geometry():
    # correctness of the cache: changing a magnetic field must change the answer
    s = default_sensor()
    x = np.linspace(-30, 30, 2000)
    y1 = lvdt.ideal_output_v(s, x)
    y2 = lvdt.ideal_output_v(s.replace(secondary_gap_mm=s.secondary_gap_mm + 1.0), x)
    assert np.abs(y2 - y1).max() > 0.01
    np.testing.assert_array_equal(lvdt.ideal_output_v(s, x), y1)


def test_coupling_table_reciprocity_and_passivity():
    s = default_sensor()
    t = lvdt.coupling_table(s, half_range_mm=60.0, n=121)
    assert t.position_mm[0] == -60.0 and t.position_mm[-1] == 60.0
    # mirror symmetry of the construction: M1(x) = M2(-x)
    np.testing.assert_allclose(t.m1_h, t.m2_h[::-1], rtol=1e-10)
    # self-inductances positive; the loop of two secondaries has |M1 - M2|^2 <= Lp L_loop
    assert np.all(t.lp_h > 0) and np.all(t.lloop_h > 0)
    assert np.all((t.m1_h - t.m2_h) ** 2 <= t.lp_h * t.lloop_h * (1 + 1e-9))


def test_eddy_current_permeability_limits():
    # skin depth delta = sqrt(2 / (w mu0 mu_r sigma)); deep in the skin-effect regime the
    # flux penetrates ~delta/sqrt(2) (|1/(1+j)| delta) from each exposed face, so the
    # section-averaged permeability tends to mu_r * sqrt(2) * delta / thickness for a wall
    # open on both faces (tube, full wall thickness) and mu_r * sqrt(2) * delta / radius for a
    # rod (surface / area = 2 / radius), at a phase lag of 45 deg.
    s = default_sensor().replace(core_conductivity_s_per_m=2e6)
    for f in (2e5, 1e6):
        t = s.replace(excitation_frequency_hz=f)
        delta = math.sqrt(2 / (2 * math.pi * f * MU0 * t.core_permeability_ratio * 2e6))
        wall = (5.0 - 4.4) / 2 * 1e-3
        mu = lvdt.core_permeability_eff(t)
        assert abs(mu) == pytest.approx(t.core_permeability_ratio * math.sqrt(2) * delta / wall, rel=0.02)
        assert math.degrees(-np.angle(mu)) == pytest.approx(45.0, abs=1.0)
    rod = s.replace(core_inner_diameter_mm=0.0, excitation_frequency_hz=1e6)
    delta = math.sqrt(2 / (2 * math.pi * 1e6 * MU0 * rod.core_permeability_ratio * 2e6))
    assert abs(lvdt.core_permeability_eff(rod)) == pytest.approx(
        rod.core_permeability_ratio * math.sqrt(2) * delta / 2.5e-3, rel=0.05)
    slow = rod.replace(excitation_frequency_hz=0.01)
    assert lvdt.core_permeability_eff(slow) == pytest.approx(rod.core_permeability_ratio, rel=1e-4)


def test_eddy_currents_lower_sensitivity_with_frequency():
    # With R_p = 0, Ip = V/(jw Lp) and v = (M/Lp) V: without eddy currents the output does
    # not depend on frequency at all; a conducting core loses coupling as f rises.
    base = default_sensor().replace(primary_resistance_ohm=0.0)
    x = np.array([10.0])
    ref = lvdt.ideal_output_v(base, x)[0]
    assert lvdt.ideal_output_v(base.replace(excitation_frequency_hz=50e3), x)[0] == pytest.approx(ref, rel=1e-12)
    cond = base.replace(core_conductivity_s_per_m=2e6)
    assert lvdt.ideal_output_v(cond.replace(excitation_frequency_hz=1.0), x)[0] == pytest.approx(ref, rel=1e-5)
    ys = [lvdt.ideal_output_v(cond.replace(excitation_frequency_hz=f), x)[0] for f in (1e3, 5e3, 20e3, 100e3)]
    assert ref > ys[0] > ys[1] > ys[2] > ys[3] > 0
    # still odd and zero at null, and the detector is trimmed to the rotated phase
    y = lvdt.ideal_output_v(cond, np.array([-7.0, 0.0, 7.0]))
    assert y[1] == pytest.approx(0, abs=1e-12) and y[0] == pytest.approx(-y[2], rel=1e-9)


def test_table_interpolation_matches_exact_solution():
    # >= TABLE_MIN_POINTS positions go through the per-geometry table; the same positions
    # asked a few at a time are solved exactly: they must agree to ~1e-6 of full scale.
    s = default_sensor()
    x = np.random.default_rng(1).uniform(-70, 70, 3 * lvdt.TABLE_MIN_POINTS)
    many = lvdt.ideal_output_v(s, x)
    few = np.concatenate([lvdt.ideal_output_v(s, chunk) for chunk in np.array_split(x, 40)])
    assert np.abs(many - few).max() < 1e-6 * np.abs(few).max()
    # beyond the table the exact solution is used
    far = np.concatenate([x, [500.0]])
    assert lvdt.ideal_output_v(s, far)[-1] == pytest.approx(lvdt.ideal_output_v(s, [500.0])[0], abs=1e-15)


def test_tabulated_takes_the_table_at_any_number_of_positions():
    # a fit's few positions asked inside tabulated(): the table's numbers, which a call with
    # many positions interpolates too (the same function at every call), near the exact ones
    s = default_sensor().replace(primary_length_mm=11.0)
    x = np.random.default_rng(2).uniform(-70, 70, 3 * lvdt.TABLE_MIN_POINTS)
    many = lvdt.ideal_output_v(s, x)
    few = np.concatenate([lvdt.ideal_output_v(s, chunk) for chunk in np.array_split(x, 40)])
    with lvdt.tabulated():
        tab = np.concatenate([lvdt.ideal_output_v(s, chunk) for chunk in np.array_split(x, 40)])
        one = lvdt.ideal_output_v(s, x[:1])
        far = lvdt.ideal_output_v(s, np.array([x[0], 500.0]))
    assert np.array_equal(tab, many) and one[0] == many[0]
    assert not np.array_equal(tab, few) and np.abs(tab - few).max() < 1e-6 * np.abs(few).max()
    # beyond the table, exact; and the context ends with its block
    assert far[1] == pytest.approx(lvdt.ideal_output_v(s, [500.0])[0], abs=1e-15)
    assert np.array_equal(np.concatenate([lvdt.ideal_output_v(s, c) for c in np.array_split(x, 40)]), few)
