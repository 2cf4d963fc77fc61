"""Render the two-input datapath: each temperature order's one-input datapath plus the top.

Every order is the fixed datapath's own rendering (:func:`flann.hardware.fixed.render.render`,
its templates unchanged) with its entities given the order's prefix (``flann_t<j>_norm`` ...):
one VHDL library holds every order, and each order's constants (ROMs, widths) differ.
``flann_thermal_top`` (this folder's one template) instantiates them and adds what is new:
the temperature normalisation, the input's gain and offset in t_n, the interpolation between
two grid nodes and the Horner combination of the orders.  Widths are computed here from the
spec's integer ranges; the template only places text.
"""

from __future__ import annotations

import warnings
from pathlib import Path

from .widths import widths_warning
from ...errors import FlannError
from ...golden.model import model_sha256
from ...golden.thermal import ThermalModel, load_any_model
from ...numeric.fixed import bits_literal
from ...textgen import template
from ..adc import default_input_lsb
from ..datapath import rebuild_matching
from ..fixed import render as fixed_render
from ..header import header
from ..manifest import flat_port, write_design
from ..options import GenOptions
from .spec import ThermalSpec, derive_thermal_spec, top_widths

TOP = "flann_thermal_top"
DATAPATH = "thermal"
MODEL_FILE = fixed_render.MODEL_FILE
TEMPLATES = "hardware/thermal/templates"


def order_prefix(j: int) -> str:
    return f"flann_t{j}_"


def order_files(spec: ThermalSpec, j: int) -> dict[str, str]:
    """Order j's one-input datapath, its entities named with the order's prefix."""
    return fixed_render.render(spec.orders[j], order_prefix(j))


def contexts(spec: ThermalSpec) -> dict:
    s = spec
    w = top_widths(s)
    d, p = s.horner_degree, len(s.orders)
    gain_bits, offset_bits, t_scale_bits, t_pre_bits = w["gain_bits"], w["offset_bits"], w["t_scale_bits"], w["t_pre_bits"]
    node_bits, node_w, acc_bits = w["node_bits"], w["node_w"], w["acc_bits"]
    round_bits = acc_bits + 1  # the accumulator rounded to the output LSB (one bit wider), then saturated
    orders = [dict(j=j, top=order_prefix(j) + "top", out_bits=o.out_fmt.width) for j, o in enumerate(s.orders)]
    return dict(
        in_bits=s.input_bits, temp_bits=s.temp_bits, out_bits=s.out_fmt.width,
        input_lsb_v=s.input_lsb_v, temp_lsb_c=s.temp_lsb_c, output_lsb_mm=s.output_lsb_mm,
        latency=s.latency_cycles, degree=d, n_orders=p, orders=orders,
        grid_lsb_exp=-s.fine_bits,  # the order datapaths' grid: 2^grid_lsb_exp input codes
        **w,
        gain_words=[bits_literal(g, gain_bits) for g in s.gain_int],
        offset_words=[bits_literal(o, offset_bits) for o in s.offset_int],
        clamp_lo=bits_literal(s.clamp_lo, s.input_bits), clamp_hi=bits_literal(s.clamp_hi, s.input_bits),
        temp_lo=bits_literal(s.temp_lo, s.temp_bits), temp_hi=bits_literal(s.temp_hi, s.temp_bits),
        t_scale=bits_literal(s.t_scale_int, t_scale_bits),
        t_offset=bits_literal(s.t_offset_int, t_pre_bits), t_shift=s.t_shift,
        t_frac_bits=s.t_frac_bits, g_frac_bits=s.g_frac_bits, interp_bits=s.interp_bits,
        node_max=bits_literal((1 << (node_bits - 1)) - 1, node_w),
        node_min=bits_literal(-(1 << (node_bits - 1)), node_w),
        inner_bits=s.inner_bits,
        round_bits=round_bits,
        # the calibrated displacement limits (spec.output_limit_codes), within the output format
        out_max=bits_literal(s.out_hi, round_bits), out_min=bits_literal(s.out_lo, round_bits),
        out_max_mm=f"{s.out_hi * s.output_lsb_mm:.6g}", out_min_mm=f"{s.out_lo * s.output_lsb_mm:.6g}",
    )


def render(spec: ThermalSpec, sha: str = "") -> dict[str, str]:
    """{file name: VHDL text} in compile order: every order's entities, then the top."""
    out = {}
    for j in range(len(spec.orders)):
        out.update(order_files(spec, j))
    # each order's spec is in its own files' headers
    stamped = {**spec.to_dict(), "orders": [order_prefix(j) + "top" for j in range(len(spec.orders))]}
    h = header(f"{TOP}.vhd", "two-input (voltage, temperature) FLANN LVDT compensator, top level",
               "flann gen", stamped, sha)
    out[f"{TOP}.vhd"] = template(f"{TEMPLATES}/{TOP}.vhd.j2").render(h=h, **contexts(spec))
    return out


def manifest(spec: ThermalSpec, files: list[str], sha: str) -> dict:
    return {
        "top": TOP, "datapath": DATAPATH, "files": list(files), "model": MODEL_FILE,
        "input_bits": spec.input_bits, "input_lsb_v": spec.input_lsb_v,
        "adc_bits": spec.input_bits, "adc_lsb_v": spec.input_lsb_v,
        "temp_bits": spec.temp_bits, "temp_lsb_c": spec.temp_lsb_c,
        "output_bits": spec.out_fmt.width, "output_lsb_mm": spec.output_lsb_mm,
        "latency_cycles": spec.latency_cycles, "cycles_per_sample": spec.cycles_per_sample,
        "clamp_codes": [spec.clamp_lo, spec.clamp_hi], "temp_clamp_codes": [spec.temp_lo, spec.temp_hi],
        "generator_version": spec.orders[0].generator_version,
        "spec": spec.to_dict(),
        "analysis": dict(spec.analysis),
        "model_sha256": sha,
        # the port beyond the common interface, as the ISE pin map reads a datapath's extra ports
        "cfg_port": {"ports": {"in_temp": flat_port("in", spec.temp_bits)}},
    }


def load_model(model) -> ThermalModel:
    """A two-input model file; a one-input one is refused in one line."""
    m = load_any_model(model)
    if not isinstance(m, ThermalModel):
        raise FlannError(f"{model}: a one-input model (the thermal datapath takes a two-input model)")
    return m


def _load(model) -> tuple[ThermalModel, str, str]:
    """(model, sha256, file text) of a two-input model file."""
    path = Path(model)
    return load_model(path), model_sha256(path), path.read_bytes().decode("utf-8")


def derive(model: ThermalModel, options: GenOptions) -> ThermalSpec:
    lsb = options.input_lsb_v if options.input_lsb_v is not None else default_input_lsb(model, options.input_bits)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return derive_thermal_spec(model, input_bits=options.input_bits, input_lsb_v=lsb,
                                   temp_bits=options.temp_bits, temp_lsb_c=options.temp_lsb_c,
                                   output_lsb_mm=options.output_lsb_mm)


def generate(model, out_dir, options: GenOptions | None = None) -> dict:
    """Derive, render and write the design directory as a whole (VHDL, manifest.json, model)."""
    m, sha, text = _load(model)
    spec = derive(m, GenOptions.of(options))
    lost = widths_warning(spec)
    if lost:
        warnings.warn(lost)   # said before the design is written
    texts = render(spec, sha)
    return write_design({**texts, MODEL_FILE: text}, manifest(spec, list(texts), sha), out_dir)


def manifest_options(man: dict) -> GenOptions:
    s = man["spec"]
    try:
        return GenOptions.of(input_bits=s["input_bits"], input_lsb_v=s["input_lsb_v"], temp_bits=s["temp_bits"],
                             temp_lsb_c=s["temp_lsb_c"], output_lsb_mm=s["output_lsb_mm"])
    except KeyError as exc:
        raise FlannError(f"manifest.json spec has no field {exc.args[0]!r}: regenerate the design") from None


def rebuild(model, man: dict, where="design") -> tuple[ThermalSpec, dict]:
    """from_manifest: the spec derived again from the kept model, checked field for field."""
    m, _, _ = _load(model)
    spec, options = rebuild_matching(man, where, lambda o: derive(m, o), lambda clamp: manifest_options(man))
    return spec, options.changed()


__all__ = ["TOP", "DATAPATH", "load_model", "render", "contexts", "manifest", "generate", "rebuild", "derive", "order_files"]
