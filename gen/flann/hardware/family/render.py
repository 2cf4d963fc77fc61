"""Render the family design (``flann gen --family``) and read it back.

The expansion and the adder are the fixed datapath's entities, rendered from its templates
with its contexts; the weight memory, the normaliser with fetched constants, the multiplier
reading the memory and the top level are this folder's templates.  The design directory
holds the VHDL, ``manifest.json`` (with the memory map and number formats under ``family``)
and ``init_model.json`` (the sensor the memory is initialised from, so the design can be
rebuilt from the directory alone).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from ...errors import FlannError
from ...golden.model import FlannModel, load_model
from ...numeric.fixed import bits_literal
from ...textgen import template
from ..header import header
from ..manifest import flat_port, write_design
from ..fixed import render as fixed
from .spec import DATA_BITS, HALF_BITS, FamilySpec, bram_image, family_from_dict, member_spec
from .twin import FlannFamilyMem

TOP = "flann_family_top"
DATAPATH = "family"
INIT_MODEL = "init_model.json"
# compile order: (entity, title, template); the multiplier is the fixed datapath's, its weights
# read from the memory (the "memory" weight fragment) instead of a ROM
FIXED_T, FAMILY_T = "hardware/fixed/templates", "hardware/family/templates"
ENTITIES = (
    ("flann_family_mem", "weight memory (per-sensor values, cfg write port)", f"{FAMILY_T}/flann_family_mem"),
    ("flann_family_norm", "input clamp and normalisation, constants fetched from the memory",
     f"{FAMILY_T}/flann_family_norm"),
    ("flann_expansion", "trigonometric expansion (phase accumulation, quarter-wave table)",
     f"{FIXED_T}/flann_expansion"),
    ("flann_family_multiplier", "terms x weights read from the memory", f"{FIXED_T}/flann_multiplier"),
    ("flann_adder", "accumulation, rounding, saturation", f"{FIXED_T}/flann_adder"),
    ("flann_seq", "sequencer of one sample (shared by every top level)", f"{FIXED_T}/flann_seq"),
    ("flann_family_top", "FLANN LVDT compensator for a sensor family, top level", f"{FAMILY_T}/flann_family_top"),
)


def _fetch_plan(fam: FamilySpec) -> dict:
    """What each parameter word is to flann_family_norm, where its products start, and the
    last word of its first fetch (clamp range, k1, k0) and of its second (ka, kb: the last
    parameter word)."""
    kinds, starts = [], []
    for f in fam.fields[1:]:
        if f.name in ("clamp_lo", "clamp_hi"):
            ks = [f"kd_{f.name}"]
        elif f.name in ("k1", "ka"):
            ks = ["kd_k_first"] + ["kd_k_next"] * (f.words - 1)
        else:  # k0, kb: the offsets, loaded into the accumulator; the product follows
            ks = ["kd_a_first"] + ["kd_a_next"] * (f.words - 1)
        kinds += ks
        starts += ["0"] * (len(ks) - 1) + ["1" if f.name in ("k0", "kb") else "0"]
    k0 = next(f for f in fam.fields if f.name == "k0")
    return dict(kinds=kinds, starts="".join(starts), param_words=len(kinds),
                last_first=k0.addr + k0.words - 1 - fam.param_base, last_second=len(kinds) - 1,
                pidx_bits=max(1, fam.param_words.bit_length()))


MEM = "flann_family_mem"


def contexts(fam: FamilySpec, init_name: str, mem_entity: str = MEM) -> dict[str, dict]:
    """Template context of every entity, by its name in :data:`ENTITIES`; the memory is
    rendered as ``mem_entity`` (one per temperature order in a family design with temperature)."""
    s = fam.spec
    base = fixed.contexts(s)
    words = FlannFamilyMem.encode(fam, s)
    # the block RAM holds each word as two halves (low half at 2k, high half at 2k + 1); the
    # VHDL array is descending, so its aggregate lists the highest address first
    mem = dict(entity=mem_entity, depth=fam.mem_depth, half_words=2 * fam.mem_depth, data_bits=DATA_BITS,
               half_bits=HALF_BITS, addr_bits=fam.addr_bits, init_name=init_name,
               halves_high_first=[bits_literal(h, HALF_BITS, False) for h in bram_image(words)][::-1])
    n = base["flann_norm"]
    norm = dict(code_bits=n["code_bits"], phase_bits=n["phase_bits"], lin_bits=n["lin_bits"],
                acc_v_bits=n["acc_v_bits"], lin_width=n["acc_l_bits"], guard_v=n["guard_v"],
                guard_l=n["guard_l"], cnt_bits=n["cnt_bits"], data_bits=DATA_BITS, width=fam.norm_width,
                # in_word sign-extended, wider than the register and a word: a field's first word is signed
                wide_bits=fam.norm_width + DATA_BITS,
                param_base=fam.param_base, **_fetch_plan(fam))
    mu = base["flann_multiplier"]
    step_bits = mu["step_bits"]
    if step_bits > fam.addr_bits:
        raise FlannError(f"internal: step counter ({step_bits} bits) wider than the memory address")
    if mu["lanes"] != 1 or mu["style"] != "shiftadd":
        raise FlannError("internal: the family multiplier is one serial shift-add lane")
    mult = dict(mu, entity="flann_family_multiplier", weight=f"{FIXED_T}/multiplier/weight/memory",
                data_bits=DATA_BITS)
    t = base["flann_top"]
    top = dict(t, mem_entity=mem_entity, latency=fam.latency_cycles, depth=fam.mem_depth, data_bits=DATA_BITS, addr_bits=fam.addr_bits,
               param_base=fam.param_base, step_bits=step_bits, pidx_bits=max(1, fam.param_words.bit_length()))
    return {MEM: mem, "flann_family_norm": norm, "flann_expansion": base["flann_expansion"],
            "flann_family_multiplier": mult, "flann_adder": base["flann_adder"], "flann_seq": base["flann_seq"],
            "flann_family_top": top}


def header_spec(fam: FamilySpec) -> dict:
    """The fixed datapath's spec plus the family's sizing, for the shared header."""
    d = fam.to_dict()
    # one short line per value (a line of VHDL stays under VSG's 120 characters)
    return dict(fam.spec.to_dict(), **{f"family_{k}": d[k] for k in ("margin", "members", "terms")},
                **{f"family_{k}": v for k, v in d["widths"].items()})


def render(fam: FamilySpec, init_name: str = "", mem_entity: str = MEM) -> dict[str, str]:
    """{file name: VHDL text} in compile order, the memory named ``mem_entity``."""
    ctx = contexts(fam, init_name or "(first member)", mem_entity)
    out = {}
    for name, title, tpl in ENTITIES:
        file = f"{mem_entity if name == MEM else name}.vhd"
        h = header(file, title, "flann gen --family", header_spec(fam), fam.spec.model_sha256)
        out[file] = template(f"{tpl}.vhd.j2").render(h=h, **ctx[name])
    return out


def manifest(fam: FamilySpec, files: list[str]) -> dict:
    s = fam.spec
    man = fixed.manifest(s, files)
    man.update(top=TOP, datapath=DATAPATH, model=INIT_MODEL, latency_cycles=fam.latency_cycles,
               cycles_per_sample=fam.cycles_per_sample, family=fam.to_dict(), init_model=INIT_MODEL)
    man["cfg_port"] = {
        "ports": {"cfg_we": flat_port("in"), "cfg_addr": flat_port("in", fam.addr_bits),
                  "cfg_data": flat_port("in", DATA_BITS)},
        "timing": "cfg_data is written at cfg_addr on every rising clk edge with cfg_we = 1 (one word per "
                  "cycle, back to back allowed)",
        "in_flight": "a write cancels the sample in flight (no out_valid for it); in_ready is 0 while "
                     "cfg_we = 1; the next accepted sample uses the memory as written",
        "reset": "rst clears the sequencer and valid flags, not the memory",
    }
    return man


def design_hash(out_dir) -> str:
    """sha256 over the design's VHDL files (compile order), the hash a certificate names."""
    out_dir = Path(out_dir)
    man = read_manifest(out_dir)
    h = hashlib.sha256()
    for name in man["files"]:
        h.update(name.encode() + b"\0" + (out_dir / name).read_bytes())
    return h.hexdigest()


def image_text(words) -> str:
    """A weight image as ``flann calibrate`` writes it: one hex word per line."""
    return "".join(format(int(w), f"0{DATA_BITS // 4}x") + "\n" for w in words)


def write(fam: FamilySpec, out_dir, init_model: FlannModel, init_name: str = "",
          members: dict | None = None) -> dict:
    """The VHDL, manifest.json, the initial model and each member's weight image (``members``:
    {name: FlannModel}), so `flann sim DIR` can load two sensors through the cfg port."""
    texts = render(fam, init_name)
    man = manifest(fam, list(texts))
    members = members or {}
    images = {f"image_{name}.hex": image_text(FlannFamilyMem.encode(fam, member_spec(fam, m)))
              for name, m in members.items()}
    # each image's model beside it: flann sim measures the hardware against it
    models = {f"model_{name}.json": m.to_json() for name, m in members.items()}
    man["images"] = [{"name": name, "hex": f"image_{name}.hex", "model": f"model_{name}.json"} for name in members]
    return write_design({**texts, INIT_MODEL: init_model.to_json(), **images, **models}, man, out_dir)


def read_manifest(out_dir) -> dict:
    man = fixed.read_manifest(out_dir)
    if "family" not in man:
        raise FlannError(f"{Path(out_dir) / fixed.MANIFEST}: not a family design (generate it with "
                         "`flann gen --family`)")
    return man


def load_design(out_dir) -> FamilySpec:
    """The FamilySpec of a design directory written by :func:`write`."""
    out_dir = Path(out_dir)
    man = read_manifest(out_dir)
    return family_from_dict(man["family"], load_model(out_dir / man.get("init_model", INIT_MODEL)))


__all__ = ["render", "manifest", "write", "load_design", "read_manifest", "design_hash", "contexts",
           "TOP", "ENTITIES", "INIT_MODEL"]
