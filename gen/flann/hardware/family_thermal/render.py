"""Render the temperature-compensated family design and read it back.

The blocks are the family design's entities (:func:`flann.hardware.family.render.render`, its
templates unchanged): the normaliser, expansion, multiplier, adder and sequencer written
once, the weight memory once per order (named ``flann_ft<j>_mem``, initialised from order
j of the initial sensor).  ``flann_family_thermal_top`` (this folder's template) wires them as
the family top does, with one sequencer and one expansion shared by the orders (the orders'
memories hold one input scale and clamp) and a memory, normaliser, multiplier and adder per
order, and adds the temperature code and the Horner combination.  The directory holds the
VHDL, ``manifest.json``, ``init_model.json`` (the initial sensor's two-input model) and each
member's image (every order's memory in turn).
"""

from __future__ import annotations

from dataclasses import replace

from ...numeric.fixed import bits_literal
from ...textgen import template
from ..family import render as family_render
from ..family.spec import DATA_BITS
from ..header import header
from ..manifest import flat_port, write_design
from .spec import FamilyThermalSpec, check_member
from .twin import encode_image

TOP = "flann_family_thermal_top"
DATAPATH = "family_thermal"
INIT_MODEL = "init_model.json"
TEMPLATES = "hardware/family_thermal/templates"
UNUSED = ("flann_family_top",)   # the top here wires the blocks itself


def order_name(entity: str, j: int) -> str:
    return f"flann_ft{j}_" + entity[len("flann_family_"):]


def order_files(spec: FamilyThermalSpec, init_name: str) -> dict[str, str]:
    """The shared family entities once, then every order's memory (named for its order)."""
    shared, memories = {}, {}
    for j, order_spec in enumerate(check_member(spec, spec.model)):
        mem = order_name(family_render.MEM, j)
        texts = family_render.render(replace(spec.fam, spec=order_spec), f"{init_name}, order {j}", mem)
        memories[f"{mem}.vhd"] = texts[f"{mem}.vhd"]
        if j == 0:
            shared = {n: t for n, t in texts.items() if n[:-len(".vhd")] not in (mem, *UNUSED)}
    return {**shared, **memories}


def contexts(spec: FamilyThermalSpec) -> dict:
    s, t = spec, spec.temp
    acc = s.acc_bits
    prod = acc + t.t_bits
    temp_diff_bits = t.bits + 1  # the clamped temperature code minus the mid code, one bit wider
    round_bits = acc + 1         # the accumulator rounded to the output LSB (one bit wider), then saturated
    top = family_render.contexts(s.fam, "")["flann_family_top"]
    return dict(
        **{k: top[k] for k in ("phase_bits", "lin_bits", "term_bits", "product_bits", "step_bits", "pidx_bits",
                               "param_base")},
        mem_entities=[order_name(family_render.MEM, j) for j in range(s.orders)],
        in_bits=s.input_bits, temp_bits=t.bits, out_bits=s.out_fmt.width, input_lsb_v=s.input_lsb_v,
        temp_lsb_c=t.lsb_c, output_lsb_mm=s.output_lsb_mm, latency=s.latency_cycles, orders=s.orders,
        order_bits=s.order_bits, acc_bits=acc, prod_bits=prod, t_bits=t.t_bits, t_shift=t.shift,
        inner_bits=s.inner_bits, sel_bits=s.sel_bits, addr_bits=s.fam.addr_bits, cfg_addr_bits=s.cfg_addr_bits,
        data_bits=DATA_BITS, temp_mid=t.mid, temp_lo_int=t.lo, temp_hi_int=t.hi,
        temp_lo=bits_literal(t.lo, t.bits), temp_hi=bits_literal(t.hi, t.bits),
        temp_diff_bits=temp_diff_bits, temp_mid_lit=bits_literal(t.mid, temp_diff_bits), round_bits=round_bits,
        half_t=bits_literal(1 << (t.shift - 1), prod), half_k=bits_literal(1 << (s.inner_bits - 1), round_bits),
        out_max=bits_literal(s.out_fmt.max_int, round_bits), out_min=bits_literal(s.out_fmt.min_int, round_bits),
        cnt_bits=max(1, t.t_bits.bit_length()), idx_bits=max(1, (s.orders - 1).bit_length()),
        last_idx=max(0, s.orders - 2), after_run="s_mul" if s.orders > 1 else "s_out",
    )


def header_spec(spec: FamilyThermalSpec) -> dict:
    d = spec.to_dict()
    t = d.pop("temperature")
    return {**d, **{f"temperature_{k}": v for k, v in t.items()}}


def render(spec: FamilyThermalSpec, sha: str = "", init_name: str = "") -> dict[str, str]:
    out = order_files(spec, init_name or "(first member)")
    h = header(f"{TOP}.vhd", "FLANN LVDT compensator for a sensor family with temperature, top level",
               "flann gen --family", header_spec(spec), sha)
    out[f"{TOP}.vhd"] = template(f"{TEMPLATES}/{TOP}.vhd.j2").render(h=h, **contexts(spec))
    return out


def manifest(spec: FamilyThermalSpec, files: list[str], sha: str) -> dict:
    s = spec
    return {
        "top": TOP, "datapath": DATAPATH, "files": list(files), "model": INIT_MODEL, "init_model": INIT_MODEL,
        "model_sha256": sha,
        "input_bits": s.input_bits, "input_lsb_v": s.input_lsb_v, "adc_bits": s.input_bits, "adc_lsb_v": s.input_lsb_v,
        "temp_bits": s.temp_bits, "temp_lsb_c": s.temp.lsb_c,
        "output_bits": s.out_fmt.width, "output_lsb_mm": s.output_lsb_mm,
        "latency_cycles": s.latency_cycles, "cycles_per_sample": s.cycles_per_sample,
        "generator_version": s.fam.spec.generator_version,
        "spec": s.to_dict(), "family": s.fam.to_dict(), "analysis": dict(s.analysis),
        "cfg_port": {
            "ports": {"in_temp": flat_port("in", s.temp_bits), "cfg_we": flat_port("in"),
                      "cfg_addr": flat_port("in", s.cfg_addr_bits), "cfg_data": flat_port("in", DATA_BITS)},
            "timing": "cfg_data is written at cfg_addr on every rising clk edge with cfg_we = 1; cfg_addr's top "
                      f"{s.sel_bits} bit(s) name the temperature order's memory, the low {s.fam.addr_bits} the word",
            "image": f"a sensor's image is {s.image_words} words: order j's memory at j x {s.fam.mem_depth}",
            "in_flight": "a write cancels the sample in flight (no out_valid for it); in_ready is 0 while cfg_we = 1",
            "reset": "rst clears the sequencers and valid flags, not the memories",
        },
    }


def write(spec: FamilyThermalSpec, out_dir, init_text: str, sha: str, init_name: str = "",
          members: dict | None = None) -> dict:
    """The VHDL, manifest.json, the initial model and each member's image ({name: ThermalModel})."""
    texts = render(spec, sha, init_name)
    man = manifest(spec, list(texts), sha)
    images = {f"image_{name}.hex": family_render.image_text(encode_image(spec, m))
              for name, m in (members or {}).items()}
    man["images"] = [{"name": n[len("image_"):-len(".hex")], "hex": n} for n in images]
    return write_design({**texts, INIT_MODEL: init_text, **images}, man, out_dir)


__all__ = ["render", "manifest", "write", "contexts", "order_files", "TOP", "DATAPATH", "INIT_MODEL"]
