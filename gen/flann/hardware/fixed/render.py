"""Render the VHDL-93 entities of a :class:`~flann.hardware.fixed.spec.Spec` and write ``manifest.json``.

Layer 3: one context dict per entity, computed here (widths, literals checked to fit,
names), one template per entity in ``hardware/fixed/templates``; templates only place text,
and an architecture choice the spec makes picks a fragment from a sub-folder there.
Output is deterministic: no timestamps, a header with generator version, model sha256
and the spec, so regenerating gives identical bytes.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ...errors import FlannError, SpecError
from ...textgen import template
from ...numeric.fixed import FixedFormat, bits_literal, bits_needed
from ...golden.model import FlannModel, load_model, model_sha256
from ..adc import AdcPlan, plan_adc
from ..header import header
from ..datapath import rebuild_matching
from ..manifest import MANIFEST, read_manifest, write_design
from ..options import NAMES as OPTION_NAMES, GenOptions
from .spec import FrontEnd, Spec, derive_spec

TOP = "flann_top"
DATAPATH = "fixed"
# the model a design was generated from, kept in its directory: verification needs nothing else
MODEL_FILE = "model.json"
# the entities' templates; a variant the spec chooses is a fragment in a sub-folder
TEMPLATES = "hardware/fixed/templates"


@dataclass(frozen=True)
class Entity:
    """One entity of the datapath: its short name (norm, ..., top), rendered as a prefix and
    the short name, from the template ``flann_<short>.vhd.j2``."""

    short: str
    title: str

    @property
    def name(self) -> str:
        """The default VHDL name, and the template's: ``flann_`` and the short name."""
        return f"flann_{self.short}"


# compile order
ENTITIES = (
    Entity("norm", "input clamp and normalisation (serial code x constant)"),
    Entity("expansion", "trigonometric expansion (phase accumulation, quarter-wave table)"),
    Entity("multiplier", "terms x trained weights"),
    Entity("adder", "accumulation, rounding, saturation"),
    Entity("seq", "sequencer of one sample (shared by every top level)"),
    Entity("top", "FLANN LVDT compensator, top level"),
)


def entity_names(prefix: str = "flann_") -> dict[str, str]:
    """Each entity's VHDL name by its short name (norm, expansion, ..., top): ``prefix`` and the
    short name, so one library can hold several datapaths (the thermal design's orders)."""
    return {e.short: prefix + e.short for e in ENTITIES}


def _ubits(n: int) -> int:
    """Width of an unsigned counter holding 0..n."""
    return max(1, int(n).bit_length())


def seq_context(steps: int, n_advs: int, adv_period: int) -> dict:
    """flann_seq, the sequencer every top level instantiates."""
    return dict(steps=steps, n_advs=n_advs, adv_period=adv_period, timer_bits=_ubits(max(1, adv_period - 1)),
                adv_cnt_bits=_ubits(n_advs))


def _lsb_first_norm(s: FrontEnd) -> dict:
    """flann_norm's LSB-first form: the code offset binary (u = c + 2^(B-1)), the offsets with
    -2^(B-1) x the constant folded in as the accumulators' start values, each cycle one add and
    a halving (the bits shifted out are final: floor of floors), so after B cycles the
    accumulators hold the sums over 2^B and the guard bits left are a fixed slice."""
    B, NV = s.input_bits, s.phase_bits + s.norm_guard
    theta_lo, lin_shift = s.norm_guard - B, s.lin_guard - B
    if theta_lo < 0 or lin_shift < 0:
        raise SpecError(f"internal: normaliser guard bits ({s.norm_guard}, {s.lin_guard}) below the code's {B} bits")
    half = 1 << (B - 1)
    kb_start = (s.kb_rounded - s.ka * half) % (1 << NV)  # theta is modular: every sum mod 2^NV
    k0_start = s.k0_rounded - s.k1 * half
    # every sum before its halving: |start| / 2^k + |k1| (2 - 2^-k), + 1 for the floors
    bound = abs(k0_start) + 2 * abs(s.k1) + 1
    lsb_l_bits = bits_needed(-bound, bound)
    return dict(
        clamp_lo_u=bits_literal(s.clamp_lo + half, B, False), clamp_hi_u=bits_literal(s.clamp_hi + half, B, False),
        kb_start=bits_literal(kb_start, NV, False), lsb_l_bits=lsb_l_bits,
        k1_lsb=bits_literal(s.k1, lsb_l_bits), k0_start=bits_literal(k0_start, lsb_l_bits),
        theta_lo=theta_lo, theta_hi=theta_lo + s.phase_bits - 1, lin_shift=lin_shift,
    )


def norm_context(s: FrontEnd) -> dict:
    """flann_norm: the clamp and the two serial code x constant products."""
    B, NV = s.input_bits, s.phase_bits + s.norm_guard
    return dict(
        code_bits=B, code_low_bits=B - 1,  # the code's bits below its sign bit
        phase_bits=s.phase_bits, lin_bits=s.lin_fmt.width, lin_type=s.lin_fmt.vhdl_type,
        acc_v_bits=NV, acc_l_bits=s.lin_width, guard_v=s.norm_guard, guard_l=s.lin_guard, cnt_bits=_ubits(B),
        cnt_init=bits_literal(B, _ubits(B), False),
        clamp_lo=bits_literal(s.clamp_lo, B), clamp_hi=bits_literal(s.clamp_hi, B),
        ka=bits_literal(s.ka, NV, False), **_lsb_first_norm(s),
    )


def expansion_context(s: FrontEnd) -> dict:
    """flann_expansion: phase accumulators, the quarter-wave table and its interpolation, the
    variants as fragments chosen here."""
    L, P, A = s.lanes, s.phase_bits, s.table_addr_bits
    de, do = s.delta_steps
    starts = [s.lane_start(l) for l in range(L)]
    slope_bits, kx, slope_reg = s.slope_rom_bits, s.interp_digit, s.slope_reg_bits
    icnt_bits = _ubits(slope_reg // kx + 1)
    return dict(
        lanes=L, phase_bits=P, term_bits=s.term_fmt.width, term_type=s.term_fmt.vhdl_type,
        terms_bus_bits=L * s.term_fmt.width,  # out_terms: every lane's term side by side
        # the phase inside a quadrant (table address and offset), and the bit above it that
        # mirrors the odd quadrants
        quarter_phase_bits=P - 2, mirror_bit=P - 2,
        delta_even=de, delta_odd=do,
        fragments=f"{TEMPLATES}/expansion/interp/{s.interp_style}",
        parity=f"{TEMPLATES}/expansion/parity/{'alternate' if s.lane_kind_alternates else 'fixed'}.vhd.j2",
        slope_round=f"{TEMPLATES}/expansion/slope_round/{'half_up' if s.slope_guard > 0 else 'exact'}.vhd.j2",
        offset=f"{TEMPLATES}/expansion/offset/{'edge' if s.shared_table else 'centre'}.vhd.j2",
        table_samples="bin edges" if s.shared_table else "bin centres",
        value_table="value_rom_s" if s.shared_table else "value_rom_c",
        interp_note=("; the difference of neighbouring samples (its second port) corrects to first order "
                     "inside a bin" if s.shared_table else
                     "; a slope table corrects to first order inside a bin" if s.interp else ""),
        mult_bits=_ubits(max([de, do, *starts])),
        start_mults=", ".join(f"{l} => {x}" for l, x in enumerate(starts)),
        start_par='"' + "".join("1" if s.trig_term(l)[0] == "cos" else "0" for l in range(L)) + '"',
        quarter=bits_literal(1 << (P - 2), P, False),
        table_depth=1 << A, addr_bits=A, offset_bits=s.offset_bits, dq_bits=s.dq_bits,
        # the offset's dq_bits kept from its offset_bits + 1 (the appended '1'): the lowest kept bit
        dq_lsb=s.offset_bits + 1 - s.dq_bits,
        # the serial offset x slope step's adder: the dq_bits + 1 bit partial product plus its carry
        interp_add_bits=s.dq_bits + 2,
        value_bits=s.value_fmt.width, value_type=s.value_fmt.vhdl_type, slope_bits=slope_bits, interp_digit=kx, slope_reg_bits=slope_reg,
        interp_cnt_bits=icnt_bits, interp_cnt_init=bits_literal(slope_reg // kx + 1, icnt_bits, False),
        prod_bits=s.interp_prod_bits,
        slope_guard=s.slope_guard, slope_half=(1 << (s.slope_guard - 1)) if s.slope_guard > 0 else 0,
        value_words=[s.value_fmt.literal(v) for v in s.value_rom],
        slope_words=[s.slope_fmt.literal(v) for v in s.slope_rom] if s.interp and not s.shared_table else [],
    )


# the shared front end: entity -> its context; every datapath that uses it renders it here
FRONT_END = {"flann_norm": norm_context, "flann_expansion": expansion_context}


def render_front(fe: FrontEnd, command: str, spec_dict: dict) -> dict[str, str]:
    """{file: text} of flann_norm and flann_expansion (compile order), their headers stamped with
    ``command`` and the design's ``spec_dict``."""
    out = {}
    for e in ENTITIES:
        if e.name in FRONT_END:
            h = header(f"{e.name}.vhd", e.title, command, spec_dict, fe.model_sha256)
            out[f"{e.name}.vhd"] = template(f"{TEMPLATES}/{e.name}.vhd.j2").render(
                h=h, entity=e.name, **FRONT_END[e.name](fe))
    return out


def contexts(spec: Spec, names: dict[str, str] | None = None) -> dict[str, dict]:
    """Template context of every entity, by its name in :data:`ENTITIES`; ``names``: the VHDL
    names (:func:`entity_names`) they are rendered under."""
    names = names or entity_names()
    s = spec
    B, L = s.input_bits, s.lanes
    T, W = s.term_fmt.width, s.weight_fmt.width
    Wp = s.product_fmt.width
    lin_bits = s.lin_fmt.width

    common = dict(lanes=L, phase_bits=s.phase_bits, term_bits=T, product_bits=Wp, lin_bits=lin_bits,
                  term_type=s.term_fmt.vhdl_type,
                  # the buses between the blocks: every lane's term / product side by side
                  terms_bus_bits=L * T, products_bus_bits=L * Wp)
    norm = norm_context(s)
    expansion = expansion_context(s)
    step_bits = _ubits(max(1, s.steps - 1))
    depth = 1 << step_bits
    words = [[s.weight_fmt.literal(w) for w in lane] + [s.weight_fmt.literal(0)] * (depth - len(lane))
             for lane in s.weight_rom]
    K, WX = s.mult_digits, s.weight_reg_bits
    cnt_bits = _ubits(WX // K)
    multiplier = dict(
        common, weight=f"{TEMPLATES}/multiplier/weight/rom", style=s.mult_style, fragments=f"{TEMPLATES}/multiplier/{s.mult_style}", weight_bits=W, weight_frac=s.weight_fmt.frac_bits,
        weight_type=s.weight_fmt.vhdl_type, product_type=s.product_fmt.vhdl_type,
        full_bits=(T + 1 + WX) if s.mult_style == "shiftadd" else (T + W), shift=s.product_shift, half=1 << (s.product_shift - 1),
        rom_depth=depth, step_bits=step_bits, weight_words=words,
        cnt_bits=cnt_bits, cnt_init=bits_literal(WX // K, cnt_bits, False), digit_bits=K,
        # shift-add: the adder of one weight digit, the term with a sign bit and a carry bit
        digit_adder_bits=T + 2,
        shift_bits=WX if s.mult_style == "shiftadd" else W,
        style_note=("inferred `*` (LUT array multiplier), one product per lane and cycle"
                    if s.mult_style == "lut" else
                    f"serial shift-add, {K} weight bit(s) per cycle ({WX // K} cycles per product)"),
    )
    AB = s.acc_fmt.width
    Pf = s.product_fmt.frac_bits
    round_bits = AB + 1  # the accumulator with room for the rounding carry; saturated from there
    adder = dict(
        common, acc_bits=AB, round_bits=round_bits, out_bits=s.out_fmt.width, acc_frac=Pf,
        acc_type=s.acc_fmt.vhdl_type, out_type=s.out_fmt.vhdl_type,
        acc_half=(1 << (Pf - 1)) if Pf > 0 else 0,
        round=f"{TEMPLATES}/adder/round/{'half_up' if Pf > 0 else 'exact'}.vhd.j2", output_lsb_mm=s.output_lsb_mm,
        out_max=bits_literal(s.out_fmt.max_int, round_bits), out_min=bits_literal(s.out_fmt.min_int, round_bits),
    )
    if s.out_fmt.width > round_bits:
        raise SpecError(f"output_bits = {s.out_fmt.width} exceeds the accumulator's range; use <= {round_bits}")
    n_advs = s.pipeline_advs
    top = dict(
        common, in_bits=B, out_bits=s.out_fmt.width, input_lsb_v=s.input_lsb_v,
        output_lsb_mm=s.output_lsb_mm, latency=s.latency_cycles, steps=s.steps, n_advs=n_advs,
        adv_period=s.adv_period, timer_bits=_ubits(max(1, s.adv_period - 1)), adv_cnt_bits=_ubits(n_advs),
    )
    seq = seq_context(s.steps, n_advs, s.adv_period)
    ctx = {"flann_norm": norm, "flann_expansion": expansion, "flann_multiplier": multiplier,
           "flann_adder": adder, "flann_seq": seq, "flann_top": dict(top, names=names)}
    return {e.name: dict(ctx[e.name], entity=names[e.short]) for e in ENTITIES}


def render(spec: Spec, prefix: str = "flann_") -> dict[str, str]:
    """{file name: VHDL text} in compile order, the entities named ``prefix`` + their short name."""
    names = entity_names(prefix)
    ctx = contexts(spec, names)
    out = {}
    for e in ENTITIES:
        entity = ctx[e.name]["entity"]
        h = header(f"{entity}.vhd", e.title, "flann gen", spec.to_dict(), spec.model_sha256)
        out[f"{entity}.vhd"] = template(f"{TEMPLATES}/{e.name}.vhd.j2").render(h=h, **ctx[e.name])
    return out


def manifest(spec: Spec, files: list[str], adc_plan: AdcPlan | None = None) -> dict:
    """``adc_plan``: the converter as the user gave it (wider than the design when low bits
    are dropped); without it the design's input is the converter."""
    return {
        "top": TOP,
        "datapath": DATAPATH,
        "files": list(files),
        "model": MODEL_FILE,
        "input_bits": spec.input_bits,
        "input_lsb_v": spec.input_lsb_v,
        "adc_bits": adc_plan.adc_bits if adc_plan else spec.input_bits,
        "adc_lsb_v": adc_plan.adc_lsb_v if adc_plan else spec.input_lsb_v,
        "output_bits": spec.out_fmt.width,
        "output_lsb_mm": spec.output_lsb_mm,
        "latency_cycles": spec.latency_cycles,
        "cycles_per_sample": spec.cycles_per_sample,
        "clamp_codes": [spec.clamp_lo, spec.clamp_hi],
        "generator_version": spec.generator_version,
        "spec": spec.to_dict(),
        "analysis": {k: v for k, v in spec.analysis.items() if k != "cost"},
        "model_sha256": spec.model_sha256,
    }


def load(model_path_or_model, options: GenOptions | None = None, **overrides) -> Spec:
    """Spec from a model file path (sha256 of its bytes is stamped) or a FlannModel."""
    if isinstance(model_path_or_model, FlannModel):
        return derive_spec(model_path_or_model, options, **overrides)
    path = Path(model_path_or_model)
    model = load_model(path)
    return derive_spec(model, options, model_sha256=model_sha256(path), **overrides)


def generate(model_path_or_model, out_dir, options: GenOptions | None = None, **overrides) -> dict:
    """Derive the spec, render every entity and write them plus manifest.json atomically.

    Returns the manifest dict.  Nothing is written if any step fails.
    """
    spec = load(model_path_or_model, options, **overrides)
    o = GenOptions.of(options, **{k: v for k, v in overrides.items() if k in OPTION_NAMES})
    return write(spec, out_dir, plan_adc(spec.model, o.input_bits, o.input_lsb_v, o.clamp),
                 model_text(model_path_or_model))


def model_text(model_path_or_model) -> str:
    """The model as its file holds it (so its sha256 is the one stamped into the VHDL)."""
    if isinstance(model_path_or_model, FlannModel):
        return model_path_or_model.to_json()
    return Path(model_path_or_model).read_bytes().decode("utf-8")


def write(spec: Spec, out_dir, adc_plan: AdcPlan | None = None, model: str | None = None) -> dict:
    """The VHDL, manifest.json and the model (``model``: its file's text) as one directory."""
    texts = render(spec)
    man = manifest(spec, list(texts), adc_plan)
    return write_design({**texts, MODEL_FILE: model if model is not None else spec.model.to_json()}, man, out_dir)


# -- a generated design, rebuilt from its manifest ----------------------------------------
def _format_bits(fmt: str, field: str) -> tuple[int, int]:
    """(width, fraction bits) of a format as the manifest writes it (``sfix<W,I,...>``)."""
    try:
        f = FixedFormat.parse(fmt)
    except SpecError as exc:
        raise FlannError(f"manifest spec field {field!r}: {exc}") from None
    return f.width, f.frac_bits


def manifest_options(man: dict, clamp: bool = True) -> dict:
    """derive_spec options that regenerate the design recorded in a manifest."""
    s = man.get("spec")
    if not isinstance(s, dict):
        raise FlannError("manifest.json has no 'spec' object: regenerate the design with flann gen")
    try:
        return dict(
            device=s["device"], input_bits=s["input_bits"], input_lsb_v=s["input_lsb_v"], clamp=clamp,
            output_bits=_format_bits(s["output"], "output")[0], output_lsb_mm=s["output_lsb_mm"],
            lanes=s["lanes"], mult_style=s["mult_style"], mult_digit_bits=s["mult_digit_bits"],
            interp=s["interp"], phase_bits=s["phase_bits"], table_addr_bits=s["table_addr_bits"],
            term_frac_bits=_format_bits(s["term"], "term")[1],
            weight_frac_bits=_format_bits(s["weight"], "weight")[1],
            product_frac_bits=_format_bits(s["product"], "product")[1],
        )
    except KeyError as exc:
        raise FlannError(f"manifest.json spec has no field {exc.args[0]!r}: regenerate the design") from None


def rebuild_spec(model_path, man: dict, where, check_device: bool = True) -> tuple[Spec, dict]:
    """The Spec of ``model_path`` with the options in ``man`` and those options, reproducing the
    manifest's spec field for field (clamping on or off, as generated); else one FlannError
    (``where`` names the design): another model or generator version made it."""
    return rebuild_matching(man, where, lambda o: load(model_path, check_device=check_device, **o),
                            lambda clamp: manifest_options(man, clamp))

__all__ = ["entity_names", "seq_context", "norm_context", "expansion_context", "render_front", "FRONT_END", "generate", "write", "model_text", "MODEL_FILE", "DATAPATH", "render", "contexts", "manifest", "load", "read_manifest", "manifest_options",
           "rebuild_spec", "TOP",
           "ENTITIES", "MANIFEST", "write_design"]

