"""The float18 datapath (``flann gen --format float18``) behind the common :class:`Datapath` interface."""

from __future__ import annotations

import warnings

from ...golden.model import load_model, model_sha256
from ..datapath import Datapath, Field, _int, rebuild_matching
from ..fixed.render import _format_bits
from ..options import GenOptions
from . import render
from .spec import FlannF18Top, derive_f18_spec, float18_options

# LUT4 / flip-flops of flann_f18_cvt + flann_f18_mul + flann_f18_add and the top's sequencer,
# measured by `flann synth` (GHDL + Yosys, abc full) of an 8-bit, 5-term float18 design
# minus the fixed estimate of its front end
BLOCKS_LUTS, BLOCKS_FFS = 900, 300


def generate(model, out_dir, options: GenOptions | None = None) -> dict:
    return render.generate(model, out_dir, **float18_options(options or GenOptions()))


def _options(man: dict, clamp: bool) -> dict:
    s = man["spec"]
    return dict(device=s["device"], input_bits=s["input_bits"], input_lsb_v=s["input_lsb_v"], clamp=clamp,
                phase_bits=s["phase_bits"], table_addr_bits=s["table_addr_bits"], interp=s["interp"],
                term_frac_bits=_format_bits(s["term"], "term")[1])


def rebuild(model, man: dict, where="design"):
    """The F18Spec that reproduces the manifest's spec (clamping on or off, as generated)."""
    fmodel, sha = load_model(model), model_sha256(model)

    def derive(options):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return derive_f18_spec(fmodel, model_sha256=sha, **options)

    return rebuild_matching(man, where, derive, lambda clamp: _options(man, clamp))

def estimate(man: dict) -> dict:
    """The front end's estimate (as the fixed datapath's) plus the measured float blocks."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = man["spec"]
        lut, ff = BLOCKS_LUTS, BLOCKS_FFS
        brams = 0
        depth_bits = s["table_addr_bits"]
        # the quarter-wave value (and slope) tables: 4-Kbit blocks as the fixed estimate counts them
        for fmt in (s["value"], s["slope"]) if s["interp"] else (s["value"],):
            width = _format_bits(fmt, "value")[0]
            per_block = min(16, max(1, 4096 >> depth_bits))
            brams += -(-width // per_block) * max(1, (1 << depth_bits) // 4096)
        return {"luts": lut + 8 * s["phase_bits"] + 4 * s["input_bits"], "ffs": ff + 6 * s["phase_bits"],
                "brams": brams}


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
    bench="f18_top", stages="float18_terms", netlist="float18", explore="float18_widths", summary=summary, derive=derive_f18_spec,
    number_format=render.DATAPATH, stage_capture=True, fuzz_share=0.2,
    why_no_eval="flann eval --design compares a fixed-point output LSB with the ADC's physical limit; "
                "a float18 design has no output LSB: see its accuracy with flann sim DIR or flann trace DIR",
)

__all__ = ["DATAPATH"]
