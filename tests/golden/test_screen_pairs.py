"""The outlier screen on a sweep there and back (each position read twice): two readings that
agree are the curve, even where a held-out fit misses both (quiet dwell means of a waveform
recording at a sharp knee); one reading far from its partner is still a gross outlier."""

import numpy as np

from flann.golden.forward import robust_forward

UP = np.linspace(-25, 25, 21)
X = np.concatenate([UP, UP[::-1][1:]])       # there and back: 20 positions read twice
NOISE_V = 2e-5


def _curve(x):
    """A ratio flat beyond a sharp knee near the ends of the stroke."""
    return 0.8 * np.tanh(x / 14.0) * (1 - 0.25 * (np.abs(x) / 25) ** 8)


def _readings(seed=1):
    return _curve(X) + np.random.default_rng(seed).normal(0, NOISE_V, X.size)


def test_a_knee_read_twice_alike_is_kept():
    fit = robust_forward(X, _readings())
    assert fit.outliers == [] and fit.keep.all(), fit.outliers


def test_a_glitch_far_from_its_partner_is_left_out():
    v = _readings()
    glitch = 12                                     # 5 mm, read again at row 28
    v[glitch] += 200 * NOISE_V
    fit = robust_forward(X, v)
    assert [i for i, _ in fit.outliers] == [glitch], fit.outliers
