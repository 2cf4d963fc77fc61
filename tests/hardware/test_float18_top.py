"""The float18 datapath twin against a scalar re-computation with exact float18 ops."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from flann.errors import SpecError
from flann.numeric.float18 import FLOAT18 as F
from flann.hardware.float18.spec import FlannF18Top, derive_f18_spec
from flann.golden.model import load_model
from flann.recordings import read_recordings
from flann.golden.train import fit_lstsq
from flann.hardware.fixed.twin import FlannExpansion, FlannNorm

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def paper_model():
    """The paper's model: 51 terms on Table 1, raw volts (no normalisation)."""
    rec = read_recordings(ROOT / "data" / "paper_table1.csv")
    return fit_lstsq(rec.voltage_v, rec.displacement_mm, 51, norm="none")


def test_twin_equals_scalar_exact_chain(paper_model):
    spec = derive_f18_spec(paper_model)
    base = spec.front
    codes = np.array([base.clamp_lo, -1000, -1, 0, 1, 777, base.clamp_hi, base.code_max])
    out, sat = FlannF18Top(spec).process(codes)
    theta = FlannNorm(base).process(codes).out_theta
    trig = FlannExpansion(base).process(theta).out_terms.reshape(codes.size, -1)
    Tf = base.term_fmt.frac_bits
    m = paper_model
    a = Fraction(base.input_lsb_v) / Fraction(m.input_scale_v)
    for n, c in enumerate(codes):
        cc = min(max(int(c), base.clamp_lo), base.clamp_hi)
        # weights written from the model file, not from the spec's ROM
        w = [F.encode(Fraction(m.weights[0]) * a * 2 ** Tf)] + [F.encode(Fraction(x)) for x in m.weights[1:]]
        acc = F.encode(Fraction(m.bias) - Fraction(m.weights[0]) * Fraction(m.input_offset_v) / Fraction(m.input_scale_v))
        terms = [cc] + [int(x) for x in trig[n, : m.terms - 1]]
        for t, wc in zip(terms, w):
            acc = F.add(acc, F.mul(F.encode(Fraction(t, 2 ** Tf)), wc))
        assert out[n] == acc, (c, hex(out[n]), hex(acc))
        assert sat[n] == (c != cc)


def test_float18_error_is_small_relative_to_output(paper_model):
    spec = derive_f18_spec(paper_model)
    top = FlannF18Top(spec)
    c = np.arange(spec.front.clamp_lo, spec.front.clamp_hi + 1)
    y = top.out_mm(c)
    ref = paper_model.predict(c * spec.front.input_lsb_v)
    # 51 additions, each off by at most half an ulp (2^-12 relative) of a sum of size ~|y|:
    # a loose physical bound is 51 * 2^-12 * max|partial sums| + table error
    assert np.max(np.abs(y - ref)) < 51 * 2.0 ** -12 * np.max(np.abs(ref)) * 1.5
    assert np.max(np.abs(y - ref)) > 0          # float18 is not exact


def test_fixed_only_options_rejected():
    m = load_model(ROOT / "data" / "default_model.json")
    with pytest.raises(SpecError, match="output-bits"):
        derive_f18_spec(m, output_bits=16)
    with pytest.raises(SpecError, match="lanes"):
        derive_f18_spec(m, lanes=2)
