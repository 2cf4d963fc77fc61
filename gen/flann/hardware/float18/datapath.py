"""The float18 datapath (``flann gen --format float18``) behind the common :class:`Datapath` interface."""

from __future__ import annotations

import math
import warnings

from ...golden.model import load_model, model_sha256
from ..datapath import Datapath, Field, _int, check_design_model, rebuild_matching
from ..fixed.render import _format_bits, model_text
from ..fixed.spec import table_brams
from ..options import GenOptions
from . import render
from .accuracy import float_model_error, warning_text
from .spec import FlannF18Top, derive_f18_spec, float18_options

# Resource estimate, fitted to `flann synth` (GHDL + Yosys synth_xilinx -family xcv, abc full) of
# 15 float18 designs: models of one sensor with 5, 11, 25, 51 and auto (61) terms at 8, 10 and
# 12-bit inputs (bench/bench_float18.py --estimate-vs-synth prints them).  Per entity, LUT4:
#   flann_f18_mul + flann_f18_add + flann_seq: 983..1018, whatever the model
#   flann_expansion: the array slope multiplier, dq x (slope + 1) bits, and the phase adders
#   flann_f18_cvt: a leading-zero count and a shift over max(term width, 14) bits
#   flann_norm: its adders and the code's clamp;  flann_f18_top: the weight ROM in LUTs
# The sum is within -56..+39 LUT4 of synthesis (rms 33; -64..+31 on four designs left out of
# the fit, the repository's model among them); LUT_MARGIN covers the largest shortfall, so
# that a part the estimate accepts is one synthesis accepts too.
FLOAT_BLOCK_LUTS = 1020
LUT_MARGIN = 45
# the weight ROM: Yosys kept 51 words (of 18 bits) in LUTs and put 61 in two block RAMs
ROM_LUT_WORDS = 51
# flip-flops: least squares over the same designs (residual -11..+8) plus its largest shortfall
FF_MARGIN = 12


def _lut_estimate(s: dict) -> float:
    T, C = _format_bits(s["term"], "term")[0], _format_bits(s["slope"], "slope")[0]
    mag = max(T, 14)
    expansion = 17 * s["phase_bits"] - 188 + (3.16 * s["dq_bits"] * (C + 1) if s["interp"] else 0)
    cvt = 79 + 1.33 * mag * (mag - 1).bit_length()
    norm = 14 + 0.46 * s["phase_bits"] + 4 * s["input_bits"]
    top = 75 + (1.2 * s["terms"] if s["terms"] <= ROM_LUT_WORDS else 0)
    return FLOAT_BLOCK_LUTS + expansion + cvt + norm + top + LUT_MARGIN


def _bram_estimate(s: dict) -> int:
    # the value table as the fixed estimate counts it (the slope table stayed in LUTs in every
    # design measured), and the weight ROM when it is too long for LUTs
    value = table_brams(s["table_addr_bits"], [_format_bits(s["value"], "value")[0]])
    return value + (0 if s["terms"] <= ROM_LUT_WORDS else 2)


def generate(model, out_dir, options: GenOptions | None = None) -> dict:
    """`flann gen --format float18`: the design, and a warning when float18 rounding puts it
    far from its float model (no generator option changes that: see accuracy.py)."""
    fspec = render.derive(model, **float18_options(options or GenOptions()))
    man = render.write(fspec, out_dir, model_text(model))
    text = warning_text(float_model_error(fspec), str(out_dir))
    if text:
        warnings.warn(text)
    return man


def _options(man: dict, clamp: bool) -> dict:
    s = man["spec"]
    return dict(device=s["device"], input_bits=s["input_bits"], input_lsb_v=s["input_lsb_v"], clamp=clamp,
                phase_bits=s["phase_bits"], table_addr_bits=s["table_addr_bits"], interp=s["interp"],
                term_frac_bits=_format_bits(s["term"], "term")[1])


def _eval_spec(model, man: dict, directory):
    """The design's F18Spec for ``model``, which must be the model it was generated from."""
    load_model(model)  # a file that is not a model says so before the hash is compared
    check_design_model(model, man, directory)
    return rebuild(model, man, directory)[0]


def rebuild(model, man: dict, where="design"):
    """The F18Spec that reproduces the manifest's spec (clamping on or off, as generated)."""
    fmodel, sha = load_model(model), model_sha256(model)

    def derive(options):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return derive_f18_spec(fmodel, model_sha256=sha, **options)

    return rebuild_matching(man, where, derive, lambda clamp: _options(man, clamp))

def estimate(man: dict) -> dict:
    """LUT4 / FF / block RAM of the whole design before synthesis, fitted on the high side
    (`flann synth DIR` measures it)."""
    s = man["spec"]
    ffs = 275 + 4.7 * s["phase_bits"] + 8.8 * s["input_bits"] + 0.46 * s["terms"] + FF_MARGIN
    return {"luts": math.ceil(_lut_estimate(s)), "ffs": math.ceil(ffs), "brams": _bram_estimate(s)}


def summary(man: dict) -> list[str]:
    return [f"  {man['input_bits']}-bit input x {man['input_lsb_v']} V -> float18 displacement in mm "
            f"({man['output']['exp_bits']} exponent, {man['output']['frac_bits']} fraction bits); "
            f"{man['cycles_per_sample']} cycles/sample"]


FIELDS = (
    Field("model_sha256", (str,)), Field("output", (dict,)),
    _int("output.exp_bits"), _int("output.frac_bits"), Field("clamp_codes", (list,)),
    Field("spec.device", (str,)), _int("spec.input_bits", 2), _int("spec.phase_bits"),
    _int("spec.table_addr_bits"), Field("spec.interp", (bool,)), Field("spec.term", (str,)),
    Field("spec.value", (str,)),
)

DATAPATH = Datapath(
    name=render.DATAPATH, top=render.TOP, about="the seed's 18-bit floating point after the fixed front end",
    generate=generate, rebuild=rebuild, twin=FlannF18Top, estimate=estimate, fields=FIELDS,
    # compared with the fixed design, fixed-only options are meant for that one
    derive_options=lambda options, compared=False: float18_options(options, fixed_too=compared),
    summary=summary, derive=derive_f18_spec, number_format=render.DATAPATH,
    eval_spec=lambda model, man, directory: _eval_spec(model, man, directory),
)

__all__ = ["DATAPATH"]
