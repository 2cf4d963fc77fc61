"""Model-free parts of flann diagnose: noise, passes, outliers, regions, V shape, bad input."""

import numpy as np
import pytest

from flann.diagnose import data as D
from flann.errors import RecordingsError


def _two_passes(n=500, lo=-30.0, hi=30.0):
    up = np.linspace(lo, hi, n)
    x = np.concatenate([up, up[::-1]])
    d = np.concatenate([np.ones(n), -np.ones(n)])
    return x, d


def test_noise_estimate_ignores_s_curve():
    # a steep S-curve (5 V over +-30 mm) with 10 mV white noise: the estimate must be the
    # noise, not the curve (a plain std of the voltages would be ~3.6 V)
    rng = np.random.default_rng(11)
    x, _ = _two_passes()
    y = 5 * np.tanh(x / 12) + rng.normal(0, 0.01, x.size)
    passes = D.find_passes(x, None)
    assert 0.0092 < D.estimate_noise(x, y, passes) < 0.0108


def test_noise_estimate_robust_to_glitches():
    rng = np.random.default_rng(12)
    x, d = _two_passes()
    r = rng.normal(0, 0.002, x.size)
    r[::97] += 0.5  # 11 large glitches
    s = D.estimate_noise(x, r, D.find_passes(x, d))
    assert 0.0018 < s < 0.0023


def test_passes_inferred_from_order():
    x, d = _two_passes(50)
    p = D.find_passes(x, None)
    assert p.inferred and p.ordered and len(p.runs) == 2
    # the repeated reading at the turn (row 50) was taken before the core reversed
    assert np.array_equal(np.delete(p.direction, 50), np.delete(d, 50))
    # shuffled rows carry no sweep: treated as unordered
    rng = np.random.default_rng(0)
    p2 = D.find_passes(rng.permutation(x), None)
    assert p2.direction is None and not p2.ordered


def test_outliers_found_and_only_them():
    rng = np.random.default_rng(13)
    x, d = _two_passes()
    r = rng.normal(0, 0.005, x.size) + 0.02 * np.sin(x / 7)  # smooth structure is not a glitch
    r[123] += 0.08
    r[777] -= 0.06
    p = D.find_passes(x, d)
    mask = D.find_outliers(x, r, p, 0.005)
    assert sorted(np.flatnonzero(mask)) == [123, 777]


def test_no_regions_or_outliers_in_pure_noise():
    x, d = _two_passes()
    p = D.find_passes(x, d)
    for seed in range(20):
        r = np.random.default_rng(seed).normal(0, 0.003, x.size)
        s = D.estimate_noise(x, r, p)
        assert D.locate_regions(x, r, p, s) == []
        assert not D.find_outliers(x, r, p, s).any()


def test_region_located_with_direction():
    # +8 mV between 10 and 20 mm on the outward pass only, noise 5 mV
    rng = np.random.default_rng(14)
    x, d = _two_passes()
    r = rng.normal(0, 0.005, x.size) + np.where((d > 0) & (x > 10) & (x < 20), 0.008, 0.0)
    regs = D.locate_regions(x, r, D.find_passes(x, d), 0.005)
    assert len(regs) == 1
    g = regs[0]
    assert g["direction"] == "+"
    assert 7 < g["from_mm"] < 13 and 17 < g["to_mm"] < 23
    assert 0.005 < g["peak_residual_v"] < 0.011


def test_region_both_directions_merged():
    rng = np.random.default_rng(15)
    x, d = _two_passes()
    r = rng.normal(0, 0.005, x.size) + d * 0.01 * np.exp(-(x / 5) ** 2)  # backlash-like
    regs = D.locate_regions(x, r, D.find_passes(x, d), 0.005)
    assert [g["direction"] for g in regs] == ["both"]
    assert regs[0]["from_mm"] < -2 and regs[0]["to_mm"] > 2


def test_v_shape_recognised():
    x = np.linspace(-20, 30, 300)
    signed = 4 * np.tanh((x - 5) / 10)
    assert D.detect_v_shape(x, signed, 0.001) is None
    tip = D.detect_v_shape(x, np.abs(signed), 0.001)
    assert tip is not None and abs(tip - 5) < 1
    assert D.detect_v_shape(x, -np.abs(signed), 0.001) is not None
    # a clipped signed curve is not a V
    assert D.detect_v_shape(x, np.clip(signed, -3, 3), 0.001) is None


@pytest.mark.parametrize("x, y, d, words", [
    (np.full(10, 3.0), np.linspace(0, 1, 10), None, "does not vary"),
    (np.full(10, 3.0), np.full(10, 0.5), None, "identical"),
    (np.linspace(0, 1, 10), np.full(10, 0.5), None, "voltage_v"),
    (np.linspace(0, 1, 10), np.linspace(0, 1, 10), np.array([1, 1, 0, 1, 1, 1, 1, 1, 1, 1.0]),
     "direction"),
    (np.linspace(0, 1, 3), np.linspace(0, 1, 3), None, "at least"),
])
def test_check_inputs_refuses(x, y, d, words):
    with pytest.raises(RecordingsError, match=words):
        D.check_inputs(x, y, d, "f.csv")
