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


def _direct_by_hand(v_n, weights, bias):
    """Term by term with math.sin/cos in the paper's order, written independently here."""
    out = []
    for v in v_n:
        y, scale = bias, abs(bias)
        for i, w in enumerate(weights):
            m = (i + 1) // 2
            phi = v if i == 0 else (math.sin(m * math.pi * v) if i % 2 else math.cos(m * math.pi * v))
            y += w * phi
            scale += abs(w * phi)
        out.append((y, scale))
    return np.array(out)


@pytest.mark.parametrize("terms", [1, 2, 3, 4, 11, 50, 51, 61])
def test_recurrence_agrees_with_the_direct_sum_to_1e_12(terms):
    rng = np.random.default_rng(terms)
    w = rng.normal(0, 1, terms) * rng.choice([1e-3, 1.0, 1e3], terms)
    m = FlannModel(weights=tuple(w), bias=0.3, input_offset_v=0.2, input_scale_v=1.7)
    v = np.concatenate([rng.uniform(-3, 3, 300), [0.2, 0.2 + 1.7, 0.2 - 1.7, 1e-9]])
    ref = _direct_by_hand(m.normalise(v), w, 0.3)
    got = m.predict(v)
    assert np.all(np.abs(got - ref[:, 0]) <= 1e-12 * ref[:, 1])
    # the library's own direct path agrees too, and on a 2-D input shape
    np.testing.assert_allclose(m.predict(v.reshape(2, -1)).ravel(), got, rtol=0, atol=1e-12 * ref[:, 1].max())


def test_recurrence_relative_to_the_output_on_a_well_conditioned_model():
    # a smooth S-curve inverse: output is not small compared with the terms
    rng = np.random.default_rng(7)
    w = np.concatenate([[20.0], rng.normal(0, 1, 50) / np.repeat(np.arange(1, 26), 2) ** 2])
    m = FlannModel(weights=tuple(w), bias=1.0)
    v = np.linspace(-1, 1, 2001)
    ref = _direct_by_hand(v, w, 1.0)[:, 0]
    big = np.abs(ref) > 1.0
    assert np.max(np.abs(m.predict(v) - ref)[big] / np.abs(ref[big])) <= 1e-12
