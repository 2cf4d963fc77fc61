"""Expansion order and model evaluation, against values worked out by hand."""

import math

import numpy as np
import pytest

from flann.golden.model import FlannModel, expand, term_kind


def test_expansion_at_half_by_hand():
    # v = 0.5: [v, sin(pi/2), cos(pi/2), sin(pi), cos(pi)] = [0.5, 1, 0, 0, -1]
    np.testing.assert_allclose(expand([0.5], 5)[0], [0.5, 1.0, 0.0, 0.0, -1.0], atol=1e-15)


def test_expansion_at_quarter_even_terms_by_hand():
    r = math.sqrt(0.5)
    # v = 0.25, 4 terms: [v, sin(pi/4), cos(pi/4), sin(pi/2)]
    np.testing.assert_allclose(expand([0.25], 4)[0], [0.25, r, r, 1.0], atol=1e-15)


def test_paper_order_of_the_51_terms():
    # Paper, section V: E1 = {v, sin(pi v), ..., cos(4 pi v), sin(5 pi v)}, E2 starts with
    # cos(5 pi v), E5 lists cos(20 pi v) .. sin(25 pi v) and is the block with 11 outputs:
    # 51 = v + 25 sines + 25 cosines, the 51st being cos(25 pi v).
    assert term_kind(0) == ("lin", 1)
    assert term_kind(9) == ("sin", 5)       # last of E1
    assert term_kind(10) == ("cos", 5)      # first of E2
    assert term_kind(40) == ("cos", 20)     # first of E5
    assert term_kind(49) == ("sin", 25)
    assert term_kind(50) == ("cos", 25)
    assert expand([0.1], 51).shape == (1, 51)


def test_model_output_is_bias_plus_weighted_sum_of_normalised_terms():
    # v = 3 V, offset 1, scale 4 -> v_n = 0.5; phi = [0.5, 1, 0]; y = 2 + 0.5*4 + 1*10 + 0*7
    m = FlannModel(weights=(4.0, 10.0, 7.0), bias=2.0, input_offset_v=1.0, input_scale_v=4.0)
    assert m.predict([3.0])[0] == pytest.approx(14.0, abs=1e-12)
