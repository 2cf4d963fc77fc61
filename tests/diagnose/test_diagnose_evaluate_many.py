"""A Jacobian's points evaluated together (PhysicsFamily.evaluate_many, least_squares' workers
map) are the same numbers, bit for bit, as one evaluation each, and so are the fits; the
physics caches that serve them give the simulator's own numbers."""

import numpy as np
import pytest

from flann.diagnose import model as M
from flann.diagnose.model import Data, PhysicsFamily, ShapeModes
from flann.physics import lvdt
from flann.physics.sensor import default_sensor

NAMES = ["baseline.gain_ratio", "baseline.origin_mm", "baseline.shape_1", "baseline.shape_2",
         "null_offset.offset_v", "zero_shift.shift_mm", "secondary_imbalance.imbalance_fraction",
         "secondary_imbalance.sum_curvature", "backlash.deadband_mm",
         "adc_clipping.rail_high_v", "adc_clipping.rail_low_v",
         "leadscrew_periodic.amplitude_mm", "leadscrew_periodic.period_mm",
         "leadscrew_periodic.phase_rad"]


def _family(kind="phase_sensitive", quadrature=False):
    sensor = default_sensor().replace(demodulator_kind=kind)
    x = np.linspace(-6.0, 6.0, 61)
    x = np.concatenate([x, x[::-1]]) + 0.3
    direction = np.repeat([1.0, -1.0], 61)
    rng = np.random.default_rng(3)
    y = 0.5 * np.tanh((x - 0.3) / 4) + 0.01 + rng.normal(0, 1e-3, x.size)
    data = Data(x=x, y=y, direction=direction, temperature_c=None, time_s=None)
    grid = np.linspace(-12, 12, 201)
    modes = np.stack([np.sin(grid / 7), np.tanh(grid / 5) ** 3])
    shape = ShapeModes(grid, modes, ("a", "b"), np.cos(grid / 6))
    fam = PhysicsFamily(sensor, data, origin_known=False, shape=shape, gain0=0.5, origin0=0.3)
    fam = fam.with_shape_range(6.5, kind != "phase_sensitive").with_terms(2)
    names = list(NAMES)
    if quadrature:
        names.insert(5, "quadrature_null.quadrature_v")
    return fam, names


def _thetas(names, rng, rows):
    base = {"baseline.gain_ratio": 0.5, "baseline.origin_mm": 0.3, "null_offset.offset_v": 0.01,
            "zero_shift.shift_mm": 0.05, "secondary_imbalance.imbalance_fraction": 0.02,
            "secondary_imbalance.sum_curvature": 0.3, "backlash.deadband_mm": 0.02,
            "adc_clipping.rail_high_v": 0.45, "adc_clipping.rail_low_v": -0.6,
            "leadscrew_periodic.amplitude_mm": 0.01, "leadscrew_periodic.period_mm": 1.3,
            "leadscrew_periodic.phase_rad": 0.4, "quadrature_null.quadrature_v": 0.01}
    theta = np.array([base.get(n, 0.1) for n in names])
    out = []
    for r in range(rows):   # finite-difference points about theta, and a few far from it
        t = theta.copy()
        j = r % len(names)
        t[j] += 1.49e-8 * max(1.0, abs(t[j])) if r < len(names) else rng.normal(0, 0.05)
        if r >= len(names):
            t += rng.normal(0, 0.02, t.size)
        out.append(t)
    out.append(theta.copy())
    out[-1][names.index("secondary_imbalance.sum_curvature")] = 0.0   # no bend: one simulation
    return out


@pytest.mark.parametrize("kind, quadrature", [("phase_sensitive", False), ("amplitude", True)])
def test_evaluate_many_is_evaluate_bit_for_bit(kind, quadrature):
    fam, names = _family(kind, quadrature)
    idx = np.arange(fam.data.x.size)[::2]
    basis = fam.basis(2)
    target = fam.data_y(idx)
    thetas = _thetas(names, np.random.default_rng(1), len(names) + 6)
    many = fam.evaluate_many(thetas, names, idx, target=target, basis=basis)
    coef = np.linspace(-0.01, 0.01, basis.ncols)
    fixed = fam.evaluate_many(thetas, names, idx, coef=coef, basis=basis)
    for th, row, row_fixed in zip(thetas, many, fixed):
        one = fam.evaluate(th, names, idx, target=target, basis=basis)
        assert np.array_equal(one.view(np.uint8), row.view(np.uint8))
        one = fam.evaluate(th, names, idx, coef=coef, basis=basis)
        assert np.array_equal(one.view(np.uint8), row_fixed.view(np.uint8))


def test_a_fit_with_the_points_together_is_the_fit_point_by_point(monkeypatch):
    fam, _names = _family()
    idx = np.arange(fam.data.x.size)
    effects = ("null_offset", "secondary_imbalance", "zero_shift")
    together = fam._fit_now(effects, idx, None, "both", fam.basis(2))
    monkeypatch.setattr(PhysicsFamily, "_evaluator",
                        lambda self, *a: (lambda fun, points: [fun(p) for p in points]))
    fresh, _ = _family()
    alone = fresh._fit_now(effects, idx, None, "both", fresh.basis(2))
    assert together.names == alone.names
    for a, b in ((together.theta, alone.theta), (together.stderr, alone.stderr),
                 (together.resid, alone.resid)):
        assert np.array_equal(np.asarray(a).view(np.uint8), np.asarray(b).view(np.uint8))


def test_a_copy_of_a_sensor_keys_its_magnetics_anew_only_when_they_change():
    s = default_sensor()
    key = s.magnetics_key()
    assert s.replace(demodulator_gain_ratio=3.0).magnetics_key() == key
    longer = s.replace(core_length_mm=s.core_length_mm * 1.1)
    assert longer.magnetics_key() != key
    assert longer.magnetics_key() == default_sensor().replace(
        core_length_mm=s.core_length_mm * 1.1).magnetics_key()
    eddy = s.replace(core_conductivity_s_per_m=1e6)
    assert eddy.replace(excitation_frequency_hz=2 * s.excitation_frequency_hz).magnetics_key() \
        != eddy.magnetics_key()


def test_the_kept_line_solutions_are_bounded_in_bytes(monkeypatch):
    monkeypatch.setattr(lvdt, "_INDUCTANCE_BYTES", 200_000)
    s = default_sensor()
    x = np.linspace(-5, 5, 300)
    first = lvdt.inductances_h(s, x)
    for k in range(20):
        lvdt.inductances_h(s, x + 1e-3 * (k + 1))
    assert lvdt._inductance_bytes[0] <= 200_000
    assert sum(lvdt._INDUCTANCE_SIZES.values()) == lvdt._inductance_bytes[0]
    assert set(lvdt._INDUCTANCE_SIZES) == set(lvdt._INDUCTANCES)
    again = lvdt.inductances_h(s, x)     # dropped and solved again: the same numbers
    for a, b in zip(first, again):
        assert np.array_equal(a, b)
