"""The family's term rule (flann.golden.family.shared_terms): the fewest terms that keep every
member within FAMILY_SHARE of its own design, and a warning when no count does."""

from __future__ import annotations

import warnings

import pytest

from flann.golden.family import FAMILY_SHARE, shared_terms


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
