"""Fixed-point spec, number format and bit-true twin (pure Python, fast tier).

Expected values come from independent computations: exact rationals (fractions), float64
numpy sin/cos of the model's own definition, or by hand.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from flann.errors import SpecError
from flann.numeric.fixed import FixedFormat, bits_literal, bits_needed, round_shift, saturate, wrap
from flann.golden.model import FlannModel, expand
from flann.hardware.fixed.spec import derive_spec, parse_device, table_brams
from flann.hardware.fixed.twin import FlannExpansion, FlannNorm, FlannTop


def table1_model(terms: int = 51) -> FlannModel:
    """Minimum-norm least squares on the seed's Table 1 (built here, not by the trainer)."""
    y = np.arange(-30.0, 31.0, 5.0)
    v = np.array([-5.185, -5.017, -4.717, -4.039, -2.896, -1.494, 0.001, 1.462, 1.810, 3.962,
                  4.799, 5.225, 5.276])
    off, sc = (v.max() + v.min()) / 2, (v.max() - v.min()) / 2
    a = np.hstack([np.ones((13, 1)), expand((v - off) / sc, terms)])
    w, *_ = np.linalg.lstsq(a, y, rcond=None)
    return FlannModel(weights=tuple(w[1:]), bias=float(w[0]), input_offset_v=off, input_scale_v=sc,
                      voltage_range_v=(v.min(), v.max()), displacement_range_mm=(-30.0, 30.0))


@pytest.fixture(scope="module")
def model():
    return table1_model()


@pytest.fixture(scope="module")
def spec(model):
    return derive_spec(model)


# ---- number format ---------------------------------------------------------------------
def test_round_shift_matches_exact_rational_rounding():
    xs = np.arange(-300, 301)
    for s in (1, 2, 3, 5):
        want = [math.floor(Fraction(int(x), 2 ** s) + Fraction(1, 2)) for x in xs]
        assert round_shift(xs, s).tolist() == want
        assert round_shift(xs, s, "trn").tolist() == [math.floor(Fraction(int(x), 2 ** s)) for x in xs]


def test_fixed_format_ranges_quantise_and_saturate():
    f = FixedFormat(8, 3, signed=True)  # s3.5
    assert (f.frac_bits, f.min_int, f.max_int) == (5, -128, 127)
    assert f.quantize([1.0, -1.0, 3.99, 100.0, -100.0]).tolist() == [32, -32, 127, 127, -128]
    assert f.quantize([1 / 64]).tolist() == [1]  # half LSB rounds up
    u = FixedFormat(4, 0, signed=False)
    assert (u.min_int, u.max_int) == (0, 15)
    assert FixedFormat(4, 4, overflow="wrap").overflow_policy([9, -9]).tolist() == [-7, 7]
    c, flag = saturate([200, -200, 5], 8)
    assert c.tolist() == [127, -128, 5] and flag.tolist() == [True, True, False]
    assert wrap([255, 128], 8).tolist() == [-1, -128]


def test_bits_needed_and_literals():
    assert bits_needed(-128, 127) == 8 and bits_needed(-129, 0) == 9 and bits_needed(0, 128) == 9
    assert bits_needed(0, 255, signed=False) == 8
    assert bits_literal(-1, 4) == '"1111"' and bits_literal(5, 4, False) == '"0101"'
    with pytest.raises(SpecError):
        bits_literal(8, 4)
    with pytest.raises(SpecError):
        FixedFormat(0, 0)
    # the VHDL type a format's integers travel in: 8 signed bits, 4 unsigned bits
    assert FixedFormat(8, 3).vhdl_type == "signed(7 downto 0)"
    assert FixedFormat(4, 0, signed=False).vhdl_type == "unsigned(3 downto 0)"


# ---- spec ------------------------------------------------------------------------------
def test_default_spec_covers_trained_range_and_bounds_error(spec, model):
    lo, hi = model.voltage_range_v
    assert spec.input_bits == 12
    # the 12-bit code range covers the trained range with margin, and the clamp codes sit on it
    assert spec.code_min * spec.input_lsb_v < lo * 1.05 and spec.code_max * spec.input_lsb_v > hi * 1.05
    assert (spec.clamp_lo - 1) * spec.input_lsb_v < lo <= spec.clamp_lo * spec.input_lsb_v
    assert spec.clamp_hi * spec.input_lsb_v <= hi < (spec.clamp_hi + 1) * spec.input_lsb_v
    assert spec.analysis["bound_total_lsb"] <= 1.0
    # shift-add, 2 weight bits per cycle: ceil(W/2) cycles per product + the handing-on advance
    assert spec.mult_style == "shiftadd" and spec.adv_period == -(-spec.weight_fmt.width // 2) + 1
    assert spec.steps == 50 and spec.latency_cycles == 12 + 4 + (50 + 5 - 1) * spec.adv_period


def test_bad_options_raise_spec_error_naming_the_field(model):
    cases = [
        (dict(device="xc3s500e-fg320-4"), "device"),
        (dict(device="xc2s15-pq208-5"), "pq208"),
        (dict(input_bits=3), "input_bits"),
        (dict(lanes=0), "lanes"),
        (dict(mult_style="dsp"), "mult_style"),
        (dict(output_bits=8, output_lsb_mm=0.002), "output_bits"),
        (dict(output_lsb_mm=-1.0), "output_lsb_mm"),
        (dict(input_lsb_v=0.0), "input_lsb_v"),
        (dict(table_addr_bits=40), "table_addr_bits"),
        (dict(phase_bits=8, table_addr_bits=8), "table_addr_bits"),
    ]
    for opts, word in cases:
        with pytest.raises(SpecError, match=word):
            derive_spec(model, **opts)


def test_too_many_terms_for_the_device_is_rejected():
    big = table1_model(401)
    with pytest.raises(SpecError, match="block RAMs|LUT4"):
        derive_spec(big, device="xc2s30-pq208-5", lanes=8)


def test_device_parsing():
    assert parse_device("XC2S50-PQ208-6") == ("xc2s50", "pq208", "6")
    with pytest.raises(SpecError):
        parse_device("xc2s50")


# ---- twin against independent float computations ----------------------------------------
def test_norm_theta_is_vn_mod_2_and_lin_is_bias_plus_w0_vn(spec, model):
    codes = np.arange(spec.code_min, spec.code_max + 1)
    n = FlannNorm(spec).process(codes)
    c = np.clip(codes, spec.clamp_lo, spec.clamp_hi)
    assert n["sat"].tolist() == ((codes < spec.clamp_lo) | (codes > spec.clamp_hi)).tolist()
    vn = (c * spec.input_lsb_v - model.input_offset_v) / model.input_scale_v
    theta = n["theta"] / 2.0 ** (spec.phase_bits - 1)
    d = (theta - np.mod(vn, 2.0) + 1.0) % 2.0 - 1.0  # circular difference
    assert np.max(np.abs(d)) <= 2.0 ** -(spec.phase_bits - 1)
    lin_mm = n["lin"] / 2.0 ** spec.product_fmt.frac_bits * spec.output_lsb_mm
    want = model.bias + model.weights[0] * vn
    assert np.max(np.abs(lin_mm - want)) <= spec.output_lsb_mm * 2.0 ** -spec.product_fmt.frac_bits


def test_expansion_terms_match_numpy_sin_cos(spec):
    rng = np.random.default_rng(7)
    P = spec.phase_bits
    theta = np.concatenate([[0, 1, (1 << P) - 1, 1 << (P - 1), 1 << (P - 2)], rng.integers(0, 1 << P, 300)])
    terms = FlannExpansion(spec).process(theta)["terms"].reshape(theta.size, -1)[:, : spec.n_trig]
    vn = theta / 2.0 ** (P - 1)
    ref = expand(vn, spec.n_trig + 1)[:, 1:]
    err = np.max(np.abs(terms / 2.0 ** spec.term_fmt.frac_bits - ref))
    # half-LSB phase bias x m, table rounding and the interpolation residual
    m = spec.n_trig // 2 + 1
    bound = math.pi * m * 2.0 ** -P + 3 * 2.0 ** -spec.term_fmt.frac_bits \
        + (math.pi / 2 * 2.0 ** -(spec.table_addr_bits + 1)) ** 2
    assert err <= bound, (err, bound)


@pytest.mark.parametrize("opts", [{}, {"lanes": 2}, {"lanes": 3, "check_device": False},
                                  {"input_bits": 14}, {"clamp": False}])
def test_twin_within_one_lsb_of_float_model_for_every_code(model, opts):
    spec = derive_spec(model, **opts)
    codes = np.arange(spec.code_min, spec.code_max + 1)
    out, sat = FlannTop(spec).process(codes)
    c = np.clip(codes, spec.clamp_lo, spec.clamp_hi)
    ref = model.predict(c * spec.input_lsb_v) / spec.output_lsb_mm
    assert np.max(np.abs(out - ref)) <= 1.0
    assert not np.any(sat[(codes >= spec.clamp_lo) & (codes <= spec.clamp_hi)])


def test_lanes_do_not_change_the_result(model):
    codes = np.arange(-2048, 2048, 7)
    a = FlannTop(derive_spec(model, lanes=1)).process(codes)[0]
    for lanes in (2, 3, 4):
        spec = derive_spec(model, lanes=lanes, check_device=False)
        assert np.array_equal(FlannTop(spec).process(codes)[0], a)


def test_shorter_table_without_interpolation_costs_accuracy(model):
    fine = derive_spec(model)
    with pytest.warns(UserWarning):
        coarse = derive_spec(model, interp=False, table_addr_bits=6)
    e_fine = FlannTop(fine).error_vs_float()["max_err_lsb"]
    e_coarse = FlannTop(coarse).error_vs_float()["max_err_lsb"]
    assert e_fine <= 1.0 < e_coarse
    assert coarse.analysis["bound_total_lsb"] > 1.0


def test_a_straight_line_model_builds_and_gives_the_line():
    # `flann train --terms 1` writes a line: no sin/cos term, so the datapath gets a zero one
    line = FlannModel(weights=(-12.5,), bias=0.75, input_offset_v=0.1, input_scale_v=2.0,
                      voltage_range_v=(-1.9, 2.1), displacement_range_mm=(-12.0, 13.0))
    spec = derive_spec(line)
    codes = np.arange(spec.code_min, spec.code_max + 1)
    out = FlannTop(spec).process(codes).out_data
    v = np.clip(codes, spec.clamp_lo, spec.clamp_hi) * spec.input_lsb_v   # clamped to the trained range
    by_hand = 0.75 - 12.5 * (v - 0.1) / 2.0
    assert np.max(np.abs(out * spec.output_lsb_mm - by_hand)) <= spec.output_lsb_mm


def test_trig_weights_under_an_output_lsb_take_the_narrowest_widths():
    # a nearly straight sensor: widths below their minimum are the minimum, not an error
    m = FlannModel(weights=(10.0, 1e-7, -2e-7), bias=0.0, input_offset_v=0.0, input_scale_v=1.0,
                   voltage_range_v=(-1.0, 1.0), displacement_range_mm=(-10.0, 10.0))
    spec = derive_spec(m)
    assert spec.phase_bits == 6 and spec.weight_fmt.width >= spec.mult_digit_bits
    codes = np.arange(spec.code_min, spec.code_max + 1)
    out = FlannTop(spec).process(codes).out_data
    v = np.clip(codes, spec.clamp_lo, spec.clamp_hi) * spec.input_lsb_v
    assert np.max(np.abs(out * spec.output_lsb_mm - 10.0 * v)) <= spec.output_lsb_mm


def test_eval_runs_the_twin_once_per_distinct_code(model, monkeypatch):
    # a logger's file repeats codes: the twin's per-term arrays grow with what it is given
    from types import SimpleNamespace

    from flann.hardware import accuracy

    spec = derive_spec(model)
    seen = []
    real = FlannTop.process
    monkeypatch.setattr(accuracy.FlannTop, "process", lambda self, c: (seen.append(len(c)), real(self, c))[1])
    v = np.repeat(np.linspace(-5.0, 5.0, 40), 50)           # 2000 rows, 40 voltages
    x = model.predict(v)
    rec = SimpleNamespace(displacement_mm=x, voltage_v=v, direction=None)
    rep = accuracy.hardware_accuracy(spec, rec, tol=2.0, band=0.1, fs_mm=30.0)
    assert max(seen) <= 40
    codes = np.clip(np.floor(v / spec.input_lsb_v + 0.5).astype(np.int64), spec.code_min, spec.code_max)
    per_row = real(FlannTop(spec), codes).out_data * spec.output_lsb_mm   # every row, by itself
    assert rep["max_error_mm"] == pytest.approx(np.max(np.abs(per_row - x)), abs=1e-12)


@pytest.mark.parametrize("opts, says, not_says", [
    ({"input_bits": 4}, "--input-bits", "--input-lsb-v"),                 # the user gave only the width
    ({"output_lsb_mm": 1e-9}, "--output-lsb-mm", "output_bits ="),         # a derived width, named by its cause
    ({"lanes": 8, "check_device": True}, "fewer lanes", "mult_style=shiftadd"),   # already shift-add
])
def test_refusals_name_the_option_the_user_gave(model, opts, says, not_says):
    with pytest.raises(SpecError) as exc:
        derive_spec(model, **opts)
    assert says in str(exc.value) and not_says not in str(exc.value)


# ---- shared sin/slope table ------------------------------------------------------------
def test_interpolated_designs_take_the_one_table_when_it_saves_block_rams(model):
    s = derive_spec(model)
    assert s.table_style == "shared" and s.interp_style == "serial_shared" and s.slope_rom == ()
    two_tables = table_brams(s.table_addr_bits, [s.value_fmt.width, s.slope_fmt.width])
    assert s.analysis["estimate"]["brams"] == table_brams(s.table_addr_bits, [s.value_fmt.width]) < two_tables
    assert derive_spec(model, mult_style="lut").interp_style == "array_shared"
    with pytest.warns(UserWarning):
        assert derive_spec(model, interp=False, table_addr_bits=6).table_style == "separate"


@pytest.mark.parametrize("opts", [{}, {"table_addr_bits": 5, "term_frac_bits": 14}])
def test_shared_table_term_is_within_its_bound_at_every_quarter_wave_phase(model, opts):
    """sin(pi v) (term 1, harmonic 1) over every phase of the first quadrant against numpy:
    the samples' and the product's rounding (2^-Tf), linear interpolation between samples
    h apart (h^2/8) and the offset truncated to Dq bits (< 2^-Dq times a difference <= h + 2^-Tf)."""
    s = derive_spec(model, check_device=False, **opts)
    assert s.table_style == "shared"
    P, Tf, A, Dq = s.phase_bits, s.term_fmt.frac_bits, s.table_addr_bits, s.dq_bits
    theta = np.arange(1 << (P - 2))
    expansion = FlannExpansion(s)
    # j = 0 (step 0, lane 0): sin(m pi v_n), m = 1.  The twin works each (step, lane) slot
    # elementwise, so it is asked for this slot alone: all 50 slots over 2^21 phases took 20 s.
    assert expansion.harmonic[0, 0] == 1 and not expansion.is_cos[0, 0]
    expansion.harmonic, expansion.is_cos = expansion.harmonic[:1, :1], expansion.is_cos[:1, :1]
    terms = expansion.process(theta)["terms"][:, 0, 0]
    ref = np.sin((theta + 0.5) * math.pi / 2.0 ** (P - 1))  # the phase LSB's centre
    h = math.pi / 2 * 2.0 ** -A
    bound = 2.0 ** -Tf + h * h / 8 + 2.0 ** -Dq * (h + 2.0 ** -Tf)
    err = np.abs(terms / 2.0 ** Tf - ref)
    assert err.max() <= bound, (err.max(), bound)
    assert err.max() > bound / 20  # the check sees the table's error, not a vacuous bound


@pytest.mark.parametrize("fmt", [FixedFormat(20, 3), FixedFormat(12, -2, False, "trn", "wrap"), FixedFormat(5, 5)])
def test_a_described_format_parses_back(fmt):
    assert FixedFormat.parse(fmt.describe()) == fmt


@pytest.mark.parametrize("text", ["sfix<1,2>", "fix<8,2,rnd,sat>", "sfix<8,2,round,sat>", "sfix<0,0,rnd,sat>"])
def test_a_malformed_format_is_a_spec_error(text):
    with pytest.raises(SpecError):
        FixedFormat.parse(text)
