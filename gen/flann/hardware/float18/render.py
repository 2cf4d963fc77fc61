"""Rendering of the float18 arithmetic blocks (``flann_f18_mul``, ``flann_f18_add``).

Layer: format (:mod:`flann.numeric.float18`) -> this module (context + templates) -> files.
Every width, constant and name is computed here; the templates only place text.
"""

from __future__ import annotations

from pathlib import Path

from ... import __version__
from ...errors import SpecError
from ...numeric.fixed import bits_literal, bits_needed
from ...numeric.float18 import FLOAT18, FlannF18Add, FlannF18Mul, FloatFormat
from ...textgen import template
from ..header import header
from ..manifest import write_design
from ...golden.model import FlannModel, load_model, model_sha256
from ..fixed.render import MODEL_FILE, TEMPLATES as FIXED_TEMPLATES, model_text, render_front, seq_context
from .spec import CVT, TOP, derive_f18_spec

DATAPATH = "float18"
SEQ = "flann_seq"
BLOCKS = {"mul": FlannF18Mul, "add": FlannF18Add}
BLOCK_TITLES = {"mul": "multiplier", "add": "adder"}
TEMPLATES = "hardware/float18/templates"
COMMAND = "flann gen --format float18"
# the arithmetic blocks and the converter depend on their number format only, not on a model
BLOCK_MODEL = "(none: depends only on the number format)"




def block_context(fmt: FloatFormat, kind: str) -> dict:
    if kind not in BLOCKS:
        raise SpecError(f"float block {kind!r}: allowed {sorted(BLOCKS)}")
    if fmt.frac_bits < 3:
        raise SpecError(f"float blocks need frac_bits >= 3 (got {fmt.frac_bits})")
    twin = BLOCKS[kind](fmt)
    return {
        "entity": twin.entity,
        "latency": twin.latency,
        "width": fmt.width,
        "exp_bits": fmt.exp_bits,
        "frac_bits": fmt.frac_bits,
        "bias": fmt.bias,
        "exp_max": fmt.exp_max,
        # signed exponent arithmetic must hold, without wrapping:
        #   mul: 2 - bias .. 2 * emax - bias + 2;  add: 1 - (frac_bits + 4) .. emax + 2
        "exp_calc_bits": _exp_calc_bits(fmt),
        "fmt_text": fmt.describe(),
    }


def render_block(kind: str, fmt: FloatFormat = FLOAT18) -> tuple[str, str]:
    """(file name, VHDL text) of one block."""
    ctx = block_context(fmt, kind)
    name = f"{ctx['entity']}.vhd"
    h = header(name, f"float18 {BLOCK_TITLES[kind]}", COMMAND, _format_spec(fmt), BLOCK_MODEL)
    return name, template(f"{TEMPLATES}/f18_{kind}.vhd.j2").render(h=h, **ctx)


def render_blocks(fmt: FloatFormat = FLOAT18) -> dict[str, str]:
    return dict(render_block(k, fmt) for k in BLOCKS)


def _format_spec(fmt: FloatFormat) -> dict:
    return {"float": fmt.to_dict()}


def _exp_calc_bits(fmt: FloatFormat) -> int:
    lo = min(2 - fmt.bias, 1 - (fmt.frac_bits + 4))
    hi = max(2 * fmt.exp_max - fmt.bias + 2, fmt.exp_max + 2)
    return bits_needed(lo, hi, signed=True)


def cvt_context(fmt: FloatFormat, in_bits: int, in_frac: int) -> dict:
    """flann_f18_cvt: signed fixed (in_bits, in_frac fraction bits) -> float."""
    mag_bits = max(in_bits, fmt.frac_bits + 3)
    exp_top = mag_bits - 1 - in_frac + fmt.bias
    # the largest magnitude 2^(in_bits-1) rounds at most to 2^(in_bits-1-in_frac)
    if in_bits - 1 - in_frac + fmt.bias > fmt.exp_max:
        raise SpecError(f"converter: {in_bits}-bit values with {in_frac} fraction bits overflow {fmt.name}")
    if fmt.bias - in_frac < 1:
        raise SpecError(f"converter: 2^-{in_frac} is below {fmt.name}'s min normal")
    lo, hi = exp_top - mag_bits, exp_top + 1
    return {
        "entity": CVT, "in_bits": in_bits, "in_frac": in_frac, "width": fmt.width,
        "exp_bits": fmt.exp_bits, "frac_bits": fmt.frac_bits, "mag_bits": mag_bits,
        "exp_top": exp_top, "exp_calc_bits": max(_exp_calc_bits(fmt), bits_needed(lo, hi, signed=True)),
        "fmt_text": fmt.describe(),
    }


def top_context(fspec) -> dict:
    """flann_f18_top: sequencer, weight ROM, start value, instances."""
    b = fspec.front
    fmt = fspec.fmt
    n_terms = fspec.terms
    n_advs = fspec.n_advs
    widx_bits = max(1, n_terms.bit_length())
    return {
        "entity": TOP, "cvt_entity": CVT, "mul_entity": FlannF18Mul(fmt).entity,
        "add_entity": FlannF18Add(fmt).entity, "width": fmt.width, "fmt_name": fmt.name,
        # exponent and fraction: a code's bits below its sign (all ones: the largest magnitude)
        "magnitude_bits": fmt.width - 1,
        "fmt_text": fmt.describe(), "in_bits": b.input_bits, "input_lsb_v": b.input_lsb_v,
        "term_bits": b.term_fmt.width, "phase_bits": b.phase_bits, "lin_bits": b.lin_fmt.width,
        "n_advs": n_advs, "adv_period": fspec.adv_period, "n_terms": n_terms, "widx_bits": widx_bits,
        "clamp_lo": bits_literal(b.clamp_lo, b.input_bits), "clamp_hi": bits_literal(b.clamp_hi, b.input_bits),
        "start": bits_literal(fspec.start_code, fmt.width, signed=False),
        "rom_depth": n_terms,
        "weight_words": [bits_literal(c, fmt.width, signed=False) for c in fspec.weight_codes],
        "latency": fspec.latency_cycles,
    }


def render_design(fspec) -> dict[str, str]:
    """{file: text} in compile order: shared front end, float18 blocks, top."""
    fmt = fspec.fmt
    b = fspec.front
    # the shared front end, as the fixed datapath renders it, and the shared sequencer with this
    # datapath's advances (one term per adder latency)
    out = render_front(b, COMMAND, fspec.to_dict())
    h = header(f"{SEQ}.vhd", "sequencer of one sample (shared by every top level)", COMMAND, fspec.to_dict(),
               b.model_sha256)
    out[f"{SEQ}.vhd"] = template(f"{FIXED_TEMPLATES}/{SEQ}.vhd.j2").render(
        h=h, entity=SEQ, **seq_context(b.steps, fspec.n_advs, fspec.adv_period))
    ctx = cvt_context(fmt, b.term_fmt.width, b.term_fmt.frac_bits)
    cvt_spec = dict(_format_spec(fmt), in_bits=ctx["in_bits"], in_frac_bits=ctx["in_frac"])
    h = header(f"{CVT}.vhd", "signed fixed point terms to float18", COMMAND, cvt_spec, BLOCK_MODEL)
    out[f"{CVT}.vhd"] = template(f"{TEMPLATES}/f18_cvt.vhd.j2").render(h=h, **ctx)
    out.update(render_blocks(fmt))
    h = header(f"{TOP}.vhd", "FLANN LVDT compensator in float18, top level", COMMAND, fspec.to_dict(),
               b.model_sha256)
    out[f"{TOP}.vhd"] = template(f"{TEMPLATES}/f18_top.vhd.j2").render(h=h, **top_context(fspec))
    return out


def manifest(fspec, files: list[str]) -> dict:
    b = fspec.front
    return {
        "top": TOP,
        "datapath": DATAPATH,
        "files": list(files),
        "model": MODEL_FILE,
        "number_format": "float18",
        "input_bits": b.input_bits,
        "input_lsb_v": b.input_lsb_v,
        "output": fspec.fmt.to_dict(),
        "output_bits": fspec.fmt.width,
        "latency_cycles": fspec.latency_cycles,
        "cycles_per_sample": fspec.cycles_per_sample,
        "clamp_codes": [b.clamp_lo, b.clamp_hi],
        "generator_version": __version__,
        "spec": fspec.to_dict(),
        "model_sha256": b.model_sha256,
    }


def derive(model_path_or_model, **options):
    """The F18Spec of a model (a FlannModel, or a model.json path: its hash recorded)."""
    if isinstance(model_path_or_model, FlannModel):
        return derive_f18_spec(model_path_or_model, **options)
    path = Path(model_path_or_model)
    return derive_f18_spec(load_model(path), model_sha256=model_sha256(path), **options)


def generate(model_path_or_model, out_dir, **options) -> dict:
    """`flann gen --format float18`: derive, render, write VHDL + manifest.json atomically."""
    return write(derive(model_path_or_model, **options), out_dir, model_text(model_path_or_model))


def write(fspec, out_dir, model: str | None = None) -> dict:
    texts = render_design(fspec)
    man = manifest(fspec, list(texts))
    return write_design({**texts, MODEL_FILE: model if model is not None else fspec.model.to_json()}, man, out_dir)


__all__ = ["BLOCKS", "block_context", "render_block", "render_blocks", "render_design", "derive", "generate",
           "write", "manifest", "TOP", "CVT", "DATAPATH"]
