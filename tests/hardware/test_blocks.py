"""The fixed datapath's blocks, each derived by one checked function, composed by derive_spec,
by the float18 datapath (its front end only, once) and by the family envelope (with its bounds)."""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import replace

import numpy as np
import pytest

from flann.errors import SpecError
from flann.golden.model import load_model
from flann.hardware.family.spec import derive_family, family_from_dict
from flann.hardware.fixed import spec as fixed_spec
from flann.hardware.fixed.render import render, render_front
from flann.hardware.fixed.spec import (FrontEnd, derive_blocks, derive_front, derive_multiplier, derive_normaliser,
                                      derive_spec, front_end, sfix)
from flann.hardware.fixed.twin import FlannExpansion, FlannNorm
from flann.hardware.float18 import spec as f18_spec
from flann.hardware.options import GenOptions


@pytest.fixture(scope="module")
def model(default_model_json):
    return load_model(default_model_json)


def test_sfix_holds_its_bound_and_no_more():
    # -127..127 in 8 bits, 128 needs a ninth; the fraction bits leave the integer range alone
    assert (sfix(127, 3).width, sfix(127, 3).frac_bits) == (8, 3)
    assert sfix(128, 0).width == 9 and sfix(1, 0).width == 2


def test_a_bound_below_the_blocks_own_values_is_refused(model):
    b = derive_blocks(model, GenOptions())
    own = max(abs(w) for lane in b.multiplier.weight_rom for w in lane)
    Pf = b.multiplier.product_fmt.frac_bits
    with pytest.raises(SpecError, match=f"weights reach {own}"):
        derive_multiplier(b.budget, b.expansion, b.multiplier.weight_fmt.frac_bits, Pf, 1, weight_bound=own - 1)
    with pytest.raises(SpecError, match="linear part reach"):
        derive_normaliser(b.input, b.normaliser.phase_bits, b.output.output_lsb_mm, Pf, lin_bound=1)
    # a larger bound widens the format by the bits it needs, nothing else
    wide = derive_multiplier(b.budget, b.expansion, b.multiplier.weight_fmt.frac_bits, Pf, 1, weight_bound=own * 4)
    assert wide.weight_fmt.width == b.multiplier.weight_fmt.width + 2
    assert wide.weight_rom == b.multiplier.weight_rom


def test_float18_derives_its_front_end_once(model, monkeypatch):
    calls = []

    def counting(*args, **kw):
        calls.append(kw)
        return derive_front(*args, **kw)

    monkeypatch.setattr(f18_spec, "derive_front", counting)
    # 12-bit input, trig weights small beside the line's: the budget's terms are narrower than
    # the code, so they widen
    small = replace(model, weights=(model.weights[0], *(w * 1e-3 for w in model.weights[1:])))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        f = f18_spec.derive_f18_spec(small, input_bits=12)
        own = derive_spec(small, mult_style="lut", input_bits=12, check_device=False)
    assert len(calls) == 1 and calls[0] == {"terms_hold_code": True}
    # the float18 spec holds the front end only: no fixed multiplier or adder
    assert type(f.front) is FrontEnd and not hasattr(f.front, "weight_fmt") and not hasattr(f, "base")
    # widened to the code's width, against the fixed budget's narrower terms
    assert f.front.term_fmt.width == 12 > own.term_fmt.width
    assert f.term_frac_bits - own.term_fmt.frac_bits == 12 - own.term_fmt.width


@pytest.mark.parametrize("options", [dict(input_bits=8), dict(input_bits=8, interp=False, lanes=3, mult_style="lut"),
                                     dict(input_bits=10, lanes=2)])
def test_front_end_record_and_fixed_spec_give_the_same_front_blocks(model, options):
    """flann_norm and flann_expansion read a FrontEnd: the fixed Spec (a FrontEnd and more) and
    the bare FrontEnd of the same blocks render the same VHDL (below the header) and their twins
    give the same values."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        spec = derive_spec(model, check_device=False, **options)
        o = GenOptions.of(None, **options)
        fe = front_end(derive_front(model, o), model_sha256="", device=o.device, lanes=spec.lanes,
                       adv_period=spec.adv_period, serial_interp=spec.serial_interp)
    fixed, front = render(spec), render_front(fe, "flann gen", {})
    assert list(front) == ["flann_norm.vhd", "flann_expansion.vhd"]
    for name, text in front.items():
        body = [ln for ln in text.splitlines() if not ln.startswith("--")]
        assert body == [ln for ln in fixed[name].splitlines() if not ln.startswith("--")], name
    codes = np.arange(spec.code_min, spec.code_max + 1)
    n_s, n_f = FlannNorm(spec).process(codes), FlannNorm(fe).process(codes)
    for port in ("out_sat", "out_theta", "out_lin"):
        assert np.array_equal(n_s[port], n_f[port])
    assert np.array_equal(FlannExpansion(spec).process(n_s.out_theta).out_terms,
                          FlannExpansion(fe).process(n_f.out_theta).out_terms)


def test_family_envelope_holds_every_member_and_its_manifest_rebuilds_it(model):
    other = replace(model, weights=tuple(w * 1.3 for w in model.weights), bias=model.bias + 0.2)
    fam = derive_family([model, other], names=["a", "b"], input_bits=9, margin=0.5)
    s = fam.spec
    # weights: (1 + margin) x the larger member's largest word, in the family's format
    b = derive_blocks(other, GenOptions.of(None, **fam.options))
    biggest = max(abs(w) for lane in b.multiplier.weight_rom for w in lane)
    assert s.weight_fmt.max_int >= math.ceil(1.5 * biggest) > s.weight_fmt.max_int // 2
    # shift-add pace follows the family's weight width, not the first member's
    assert s.adv_period == -(-s.weight_fmt.width // s.mult_digit_bits) + 1
    d = json.loads(json.dumps(fam.to_dict()))
    assert family_from_dict(d, model).spec == s
    # a manifest whose widths cannot hold its own initial sensor is refused, naming what
    d["widths"]["weight_bits"] = 3
    with pytest.raises(SpecError, match="weights reach"):
        family_from_dict(d, model)


def test_block_checks_raise_spec_errors_not_asserts():
    src = open(fixed_spec.__file__).read()
    assert "\n    assert " not in src and "\n        assert " not in src
