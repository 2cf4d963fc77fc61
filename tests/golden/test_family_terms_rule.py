"""The family's term rule (flann.golden.family.shared_terms): the fewest terms that keep every
member within FAMILY_SHARE of its own design, and a warning when no count does."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.special import erf

from flann.golden.family import FAMILY_SHARE, _steady, family_terms, shared_terms
from flann.hardware.family.build import NORMALISATION


def test_the_fewest_accurate_steady_count_is_taken_without_a_warning():
    table = [{3: 2.0, 5: 1.1, 7: 1.0}, {3: 3.0, 5: 1.15, 7: 1.0}]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert shared_terms([3, 5, 7], table, [1.0, 1.0], lambda t: True) == 5


def test_no_count_within_the_share_is_said():
    """A family with temperature took 7 terms at 3.4 x its members' own held-out RMS, silently."""
    table = [{3: 5.0, 5: 3.4, 7: 3.0}, {3: 4.0, 5: 3.0, 7: 2.5}]
    with pytest.warns(UserWarning, match=rf"within {FAMILY_SHARE:g} x .* 5 terms, the most accurate with "
                                         r"steady weights, leave the worst member at 3\.40 x its own"):
        assert shared_terms([3, 5, 7], table, [1.0, 1.0], lambda t: t <= 5) == 5


def _erf_sensor(gain: float, null_mm: float, seed: int):
    """A centred erf sensor with a small cubic (not the project's forms): two sweeps of
    +-25 mm, 0.8 mV noise, a 14-bit +-5 V converter; its fitted bias is near 0 mm."""
    x = np.linspace(-25, 25, 201)
    x = np.concatenate([x, x[::-1]])
    u = x - null_mm
    v = 1.9 * gain * erf(u / 11) + 0.012 * (u / 10) ** 3
    lsb = 10 / 2 ** 14
    v = np.round((v + np.random.default_rng(seed).normal(0, 8e-4, v.size)) / lsb) * lsb
    return v, x


def test_members_with_a_bias_near_zero_are_steady():
    """The bias of a centred sensor is noise about 0 (0.003 against 0.063 mm): judged like the
    weights it made every count from 13 terms up unsteady, and three such sensors took 11
    terms at 2.05 x their own held-out RMS, with a warning."""
    assert _steady([(0.003, [2.09, 4.60]), (0.063, [2.09, 4.59]), (0.007, [2.09, 4.60])], 0.5)
    assert not _steady([(0.0, [2.09, 4.60]), (0.0, [2.09, 9.0]), (0.0, [2.09, 4.60])], 0.5)
    members = [(f"s{k}", *_erf_sensor(g, d, k)) for k, (g, d) in enumerate([(1.0, 0.05), (0.97, -0.03),
                                                                            (1.03, 0.0)])]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        terms, _ridge, choices = family_terms(members, norm=NORMALISATION)
    assert terms > 11
    assert all(c.family_rms_mm <= FAMILY_SHARE * c.own_rms_mm for c in choices), choices
    assert all(c.family_max_mm <= FAMILY_SHARE * c.own_max_mm for c in choices), choices
