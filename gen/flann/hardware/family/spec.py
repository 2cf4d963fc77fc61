"""One design for a family of sensors: common number formats, per-sensor values in a memory.

Layer 1 of the family datapath.  The arithmetic is the fixed datapath's
(:mod:`flann.hardware.fixed.spec`): the same normaliser, sin/cos table, shift-add multiplier
and adder.  What differs between sensors -- the trig weights, bias and linear weight (k1, k0),
input offset and scale (ka, kb), clamp range -- is no longer a constant but a word of the
weight memory, so one bitstream serves every sensor of the family.

Sizing (``derive_family``):

* the input code LSB covers every member's voltage range plus ``margin``; the output LSB is
  the finest a member needs, its width holds every member's output range plus ``margin``;
* fraction bits (phase, table, terms, weights, products) are those the error budget of the
  fixed datapath gives a member whose weights are ``(1 + margin)`` times larger than any
  member's, so a sensor like them still meets the 1-LSB bound;
* integer widths (weights, linear constants, products, accumulator) hold sensors of the same
  kind that were not in the gen set (``flann calibrate`` runs them later): each bound is the
  members' envelope widened by ``SPREAD`` times their spread (largest minus smallest, signed
  for the linear constants k1 and k0), then ``(1 + margin)`` times that envelope's largest
  magnitude (:func:`headroom`); the first member's blocks derived again
  (:func:`flann.hardware.fixed.spec.derive_multiplier`, ``derive_normaliser``,
  ``derive_adder``, ``derive_sequencer``) with these bounds.

``member_spec`` derives one sensor's values under these formats (a fixed :class:`Spec`
with the family's widths and the sensor's constants) and says why a sensor does not fit.
"""

from __future__ import annotations

import json

import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from ...errors import SpecError
from ...golden.family import DEFAULT_RIDGE
from ...golden.model import FlannModel
from ...numeric.fixed import bits_needed, nearest_codes
from ..fixed.latency import norm_latency
from ..fixed.spec import (BRAM_BITS, Blocks, Spec, acc_bound_for, assemble, check_fits, compose, derive_adder,
                          derive_blocks, derive_multiplier, derive_normaliser, derive_sequencer, derive_spec,
                          estimate_resources, lin_acc_reach, lin_acc_width, nice_125, round_sig)
from ..options import GenOptions, default

DATA_BITS = 32  # one memory word: one weight, or one word of a normaliser field
# The memory is one Spartan-II block RAM (RAMB4_S16_S16, 256 x 16): word k is held as two
# halves, bits 15:0 at block address 2k and bits 31:16 at 2k + 1, read through its two ports
# at once.  One block instead of two side by side leaves a block for the sin/cos tables.
HALF_BITS = 16
BRAM_HALVES = 256
MEM_DEPTH_MAX = BRAM_HALVES * HALF_BITS // DATA_BITS


def bram_image(words) -> list[int]:
    """The block RAM's contents for memory words: (bits 15:0, bits 31:16) of each word in turn."""
    mask = (1 << HALF_BITS) - 1
    return [h for w in words for h in (int(w) & mask, (int(w) >> HALF_BITS) & mask)]
DEFAULT_MARGIN = 0.5
# readings at one extreme value, this many or more, are a clipped output, not a sensor's end
CLIPPED_READINGS = 3
# a later sensor may lie beyond the members' envelope by this many times the members' own
# spread: the offset constant k0 (bias + linear term at code 0) follows the sensor's null
# asymmetry, which a few members sample poorly (tests/hardware/test_family_headroom.py: three
# members within +-3 % asymmetry, later sensors within +-6 %)
SPREAD = 2.0
# the forced generator options every member is derived with (stored in the manifest)
FORCED = ("input_bits", "input_lsb_v", "output_bits", "output_lsb_mm", "phase_bits", "table_addr_bits",
          "term_frac_bits", "weight_frac_bits", "product_frac_bits", "interp", "mult_style",
          "mult_digit_bits", "device")


class FitError(SpecError):
    """A sensor whose values do not fit the family design's formats."""


def _words(bits: int) -> int:
    return -(-int(bits) // DATA_BITS)


@dataclass(frozen=True)
class Field:
    """One per-sensor value in the weight memory: ``words`` words from ``addr``, most significant
    word first (sign-extended into the whole field), so the normaliser loads a field by shifting
    each word in from the right."""

    name: str
    addr: int
    words: int
    bits: int
    signed: bool
    meaning: str

    def to_dict(self) -> dict:
        return {"name": self.name, "addr": self.addr, "words": self.words, "bits": self.bits,
                "format": f"{'s' if self.signed else 'u'}int<{self.bits}>", "meaning": self.meaning}


@dataclass(frozen=True)
class FamilySpec:
    """The family design: the envelope :class:`Spec` (family widths, initial sensor's values)."""

    spec: Spec
    margin: float
    options: dict = field(compare=False)  # FORCED options, as every member is derived
    members: tuple = ()  # names the design was sized from
    ridge: float = DEFAULT_RIDGE  # the members' weights are trained with this ridge (calibrate: first)

    # -- shape ----------------------------------------------------------------------------
    @property
    def terms(self) -> int:
        return self.spec.model.terms

    @property
    def norm_bits(self) -> int:
        return self.spec.phase_bits + self.spec.norm_guard

    @property
    def fields(self) -> tuple[Field, ...]:
        """The memory map: weights first (one word each, hardware term order), then the normaliser."""
        s = self.spec
        B, NV, LW = s.input_bits, self.norm_bits, s.lin_width
        out = [Field("weights", 0, s.steps, s.weight_fmt.width, True,
                     f"trig weight j = 0..{s.steps - 1} (model term j + 1), output LSB x 2^{s.weight_fmt.frac_bits}")]
        addr = s.steps
        # in the order the normaliser consumes them: clamp, the linear product, then the phase
        for name, bits, signed, meaning in (
            ("clamp_lo", B, True, "lowest input code used (lower codes clamp, out_sat)"),
            ("clamp_hi", B, True, "highest input code used"),
            ("k1", LW, True, f"linear weight per code w0 lsb/(scale q) x 2^{s.product_fmt.frac_bits + s.lin_guard}"),
            ("k0", LW, True, f"bias + w0 b in accumulator units x 2^{s.lin_guard} + 2^{s.lin_guard - 1} (rounding)"),
            ("ka", NV, False, f"phase per input code: (lsb / input_scale) x 2^{s.phase_bits - 1 + s.norm_guard}, mod 2^{NV}"),
            ("kb", NV, False, f"phase offset -input_offset/input_scale x 2^{s.phase_bits - 1 + s.norm_guard} "
                              f"+ 2^{s.norm_guard - 1} (rounding), mod 2^{NV}"),
        ):
            out.append(Field(name, addr, _words(bits), bits, signed, meaning))
            addr += _words(bits)
        return tuple(out)

    @property
    def param_base(self) -> int:
        return self.spec.steps

    @property
    def param_words(self) -> int:
        return sum(f.words for f in self.fields[1:])

    @property
    def used_words(self) -> int:
        return self.param_base + self.param_words

    @property
    def addr_bits(self) -> int:
        return max(1, (self.used_words - 1).bit_length())

    @property
    def mem_depth(self) -> int:
        return 1 << self.addr_bits

    @property
    def norm_width(self) -> int:
        """Width of the normaliser's shared constant register and accumulator (both products)."""
        return max(self.norm_bits, self.spec.lin_width)

    @property
    def norm_latency(self) -> int:
        """flann_family_norm, accepting edge to out_valid: one cycle per parameter word, one to
        read the first word of each of its two fetches, ``input_bits`` per product."""
        return self.param_words + 2 + 2 * self.spec.input_bits

    @property
    def latency_cycles(self) -> int:
        """The fixed datapath's latency with flann_norm's replaced by flann_family_norm's."""
        s = self.spec
        return s.latency_cycles - norm_latency(s.input_bits) + self.norm_latency

    @property
    def cycles_per_sample(self) -> int:
        return self.latency_cycles + 1

    def to_dict(self) -> dict:
        s = self.spec
        return {
            "margin": self.margin,
            "ridge": self.ridge,
            "members": list(self.members),
            "options": dict(self.options),
            "terms": self.terms,
            "widths": {"weight_bits": s.weight_fmt.width, "lin_width": s.lin_width, "lin_bits": s.lin_fmt.width,
                       "product_bits": s.product_fmt.width, "acc_bits": s.acc_fmt.width,
                       "term_bound": s.term_bound},
            "memory": {"data_bits": DATA_BITS, "addr_bits": self.addr_bits, "depth": self.mem_depth,
                       "used_words": self.used_words, "word_order": "most significant word first",
                       "fields": [f.to_dict() for f in self.fields]},
            "formats": {"input_code": f"sint<{s.input_bits}> x {s.input_lsb_v} V",
                        "output_code": f"sint<{s.out_fmt.width}> x {s.output_lsb_mm} mm",
                        "weight": s.weight_fmt.describe(), "term": s.term_fmt.describe(),
                        "product": s.product_fmt.describe(), "linear": s.lin_fmt.describe(),
                        "acc": s.acc_fmt.describe()},
        }


# ------------------------------------------------------------------------------------------
def _check_margin(margin) -> float:
    if isinstance(margin, bool) or not isinstance(margin, (int, float)) or not 0 <= margin <= 10:
        raise SpecError(f"margin = {margin!r}: must be a number in 0..10 (0.5 = 50 % headroom)")
    return float(margin)


def _quiet(fn, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*args, **kw)


def _padded(model: FlannModel, terms: int) -> FlannModel:
    """The same function with ``terms`` terms (zero weights appended)."""
    if model.terms > terms:
        raise FitError(f"model has {model.terms} terms, the design {terms}")
    return replace(model, weights=tuple(model.weights) + (0.0,) * (terms - model.terms))


def headroom(values, margin: float) -> int:
    """The magnitude a design holds for a value whose members' values are ``values``: their
    envelope widened by ``SPREAD`` x (largest - smallest) each way, its largest magnitude
    x (1 + margin) (one member: (1 + margin) x its magnitude)."""
    lo, hi = min(values), max(values)
    wide = SPREAD * (hi - lo)
    return int(math.ceil(max(abs(lo - wide), abs(hi + wide)) * (1 + margin)))


def _scaled(model: FlannModel, k: float) -> FlannModel:
    return replace(model, weights=tuple(w * k for w in model.weights))


def derive_family(models: list[FlannModel], *, names=(), margin: float = DEFAULT_MARGIN,
                  ridge: float = DEFAULT_RIDGE,
                  input_bits: int = default("input_bits"), input_lsb_v: float | None = None,
                  output_bits: int | None = None, output_lsb_mm: float | None = None,
                  device: str = default("device"), mult_style: str = default("mult_style"),
                  mult_digit_bits: int = default("mult_digit_bits"), interp: bool = default("interp"),
                  phase_bits: int | None = None, table_addr_bits: int | None = None,
                  term_frac_bits: int | None = None, weight_frac_bits: int | None = None,
                  product_frac_bits: int | None = None, lanes: int = default("lanes"),
                  clamp: bool = default("clamp"), check_device: bool = True) -> FamilySpec:
    """Size one design for ``models`` (see the module docstring); the first model initialises the memory."""
    if not models:
        raise SpecError("a family needs at least one sensor")
    mu = _check_margin(margin)
    if lanes != 1:
        raise SpecError(f"lanes = {lanes}: the family design reads one weight per step from its memory (lanes = 1)")
    if mult_style != "shiftadd":
        raise SpecError(f"mult_style {mult_style!r}: the family design needs 'shiftadd' (the weight memory "
                        "is a block RAM with a registered read)")
    if not clamp:
        raise SpecError("the family design always clamps (the clamp range is a per-sensor value)")
    N = max(m.terms for m in models)
    models = [_padded(m, N) for m in models]
    # a member that cannot take the common formats is named: the options are the family's
    labels = list(names) if len(names) == len(models) else [f"member {k + 1}" for k in range(len(models))]
    # common input code: every member's voltage range + margin
    vmax = max(max(abs(v) for v in m.voltage_range_v) for m in models)
    if input_lsb_v is None:
        input_lsb_v = round_sig(max(vmax, 1e-12) * (1 + mu) / (1 << (input_bits - 1)))
    # common output code: the finest LSB a member needs, range of all + margin
    ys = []
    for m in models:
        lo, hi = sorted(m.voltage_range_v)
        ys.append(m.predict(np.linspace(lo, hi, 257)))
    ymax = max(float(np.max(np.abs(y))) for y in ys)
    if output_lsb_mm is None:
        steps = [(float(np.ptp(y)) or 1.0) / max(1, (max(m.voltage_range_v) - min(m.voltage_range_v)) / input_lsb_v)
                 for y, m in zip(ys, models)]
        output_lsb_mm = nice_125(min(steps) / 4, up=False)
    if output_bits is None:
        r = math.ceil(ymax * (1 + mu) / output_lsb_mm)
        output_bits = bits_needed(-r, r)
    common = dict(input_bits=input_bits, input_lsb_v=input_lsb_v, output_lsb_mm=output_lsb_mm,
                  device=device, mult_style=mult_style, mult_digit_bits=mult_digit_bits, interp=interp,
                  check_device=False)
    # fraction bits: the budget of a member with (1 + margin) x larger weights
    forced = dict(phase_bits=phase_bits, table_addr_bits=table_addr_bits, term_frac_bits=term_frac_bits,
                  weight_frac_bits=weight_frac_bits, product_frac_bits=product_frac_bits)
    if any(v is None for v in forced.values()):
        o = GenOptions.of(None, **{k: v for k, v in common.items() if k != "check_device"})
        big = [_member(n, _quiet, derive_blocks, _scaled(m, 1 + mu), o) for n, m in zip(labels, models)]
        picks = dict(phase_bits=max(b.normaliser.phase_bits for b in big),
                     table_addr_bits=max(b.expansion.table_addr_bits for b in big),
                     term_frac_bits=max(b.expansion.term_fmt.frac_bits for b in big),
                     weight_frac_bits=max(b.multiplier.weight_fmt.frac_bits for b in big),
                     product_frac_bits=max(b.multiplier.product_fmt.frac_bits for b in big))
        forced = {k: (picks[k] if v is None else v) for k, v in forced.items()}
    options = {**{k: v for k, v in common.items() if k != "check_device"}, **forced, "output_bits": output_bits}
    blocks = [_member(n, derive_blocks, m, GenOptions.of(None, **options)) for n, m in zip(labels, models)]
    specs = [assemble(b, device=device, check_device=False) for b in blocks]

    b0 = blocks[0]
    wmax = headroom([max(abs(w) for lane in s.weight_rom for w in lane) for s in specs], mu)
    k1max, k0max = headroom([s.k1 for s in specs], mu), headroom([s.k0 for s in specs], mu)
    lin_bound = headroom([s.lin_fmt.max_int for s in specs], mu)
    shift = specs[0].product_shift
    fam = FamilySpec(spec=_envelope(b0, specs[0], weight_bound=wmax,
                                    lin_width=lin_acc_width(k1max, k0max, input_bits),
                                    lin_bound=lin_bound,
                                    acc_bound=acc_bound_for(lin_bound, [wmax] * specs[0].steps,
                                                            b0.expansion.term_max, shift)),
                     margin=mu, options=options, members=tuple(names), ridge=float(ridge))
    _check_memory(fam)
    for s in specs:  # every member fits by construction; keep the check honest
        member_spec(fam, s.model)
    if check_device:
        check_fits(fam.spec, fam.spec.device.split("-")[0])
    return fam


def _member(name: str, fn, *args):
    try:
        return fn(*args)
    except FitError:
        raise
    except SpecError as exc:
        raise SpecError(f"{name}: {exc}") from None


def _envelope(b: Blocks, s: Spec, *, weight_bound: int, lin_width: int, lin_bound: int, acc_bound: int,
              product_bound: int | None = None) -> Spec:
    """The family's spec: the first member's blocks (``b``; its spec ``s``) derived again with the
    family's bounds (weights, linear part and running sums (1 + margin) x the family's largest),
    and the sequencer paced by the wider weights."""
    Pf = s.product_fmt.frac_bits
    mult = derive_multiplier(b.budget, b.expansion, s.weight_fmt.frac_bits, Pf, s.lanes, weight_bound=weight_bound,
                             product_bound=product_bound)
    norm = derive_normaliser(b.input, s.phase_bits, s.output_lsb_mm, Pf, lin_width=lin_width, lin_bound=lin_bound)
    env = Blocks(b.input, b.output, b.budget, norm, b.expansion, mult,
                 derive_adder(norm, b.expansion, mult, acc_bound=acc_bound),
                 derive_sequencer(s.mult_style, s.mult_digit_bits, mult.weight_fmt.width))
    fam = compose(env, model_sha256=s.model_sha256, device=s.device, number_format=s.number_format)
    analysis = dict(s.analysis)
    est = estimate_resources(fam)
    # the weights live in the weight memory (one block RAM), not in a ROM
    W = mult.weight_fmt.width
    rom = math.ceil(s.steps * W / BRAM_BITS) if s.steps * W > 2048 else 0
    analysis["estimate"] = {**est, "brams": est["brams"] - rom + 1}
    return replace(fam, analysis=analysis)


def _check_memory(fam: FamilySpec) -> None:
    s = fam.spec
    if s.weight_fmt.width > DATA_BITS:
        raise SpecError(f"weights need {s.weight_fmt.width} bits, the memory word has {DATA_BITS}: "
                        "use fewer --weight-frac-bits or a smaller margin")
    if fam.used_words > MEM_DEPTH_MAX:
        raise SpecError(f"{fam.used_words} memory words needed, one RAMB4 holds {MEM_DEPTH_MAX} of {DATA_BITS} "
                        "bits: fewer terms")


def check_against(fam: "FamilySpec", man: dict) -> None:
    """The manifest fields a family design's readers take as they are (``family`` with its memory
    map and formats, the members, ``cfg_port``, ``clamp_codes``) must be what the design derived
    again from its options and initial model says: SpecError naming the first that is not."""
    got = json.loads(json.dumps(fam.to_dict()))
    had = man.get("family", {})
    for key in sorted(set(got) | set(had)):
        if got.get(key) != had.get(key):
            sub = ""
            if isinstance(got.get(key), dict) and isinstance(had.get(key), dict):
                sub = next((f".{k}" for k in sorted(set(got[key]) | set(had[key])) if got[key].get(k) != had[key].get(k)), "")
            raise SpecError(f"manifest field 'family.{key}{sub}' is not what the design derives again: "
                            "edited by hand? regenerate the design with flann gen --family")
    images = man.get("images")
    if isinstance(images, list) and images and [im.get("name") for im in images if isinstance(im, dict)][:len(fam.members)] \
            != list(fam.members)[:len(images)]:
        raise SpecError("manifest field 'family.members' does not name the design's weight images "
                        "in order: regenerate the design with flann gen --family")
    ports = man.get("cfg_port", {}).get("ports") if isinstance(man.get("cfg_port"), dict) else None
    want = {"cfg_addr": fam.addr_bits, "cfg_data": DATA_BITS}
    for name, width in want.items():
        port = ports.get(name) if isinstance(ports, dict) else None
        if not isinstance(port, dict) or port.get("width") != width:
            raise SpecError(f"manifest field 'cfg_port.ports.{name}' must be {width} bits wide, as the design's "
                            f"memory is, got {port!r}: regenerate the design with flann gen --family")
    clamp = man.get("clamp_codes")
    if clamp is not None and clamp != [fam.spec.clamp_lo, fam.spec.clamp_hi]:
        raise SpecError(f"manifest field 'clamp_codes' {clamp!r} is not the design's "
                        f"[{fam.spec.clamp_lo}, {fam.spec.clamp_hi}]: regenerate the design with flann gen --family")


def family_from_dict(d: dict, init_model: FlannModel) -> FamilySpec:
    """Rebuild the FamilySpec of a manifest's ``family`` entry (and the initial model)."""
    try:
        options = dict(d["options"])
        w = d["widths"]
        margin = float(d["margin"])
        terms = int(d["terms"])
        ridge = float(d.get("ridge", DEFAULT_RIDGE))
    except (KeyError, TypeError, ValueError) as exc:
        raise SpecError(f"manifest 'family' entry is incomplete ({exc})") from None
    try:
        o = GenOptions.of(None, **options)
        b = _quiet(derive_blocks, _padded(init_model, terms), o)
        s = _quiet(assemble, b, device=o.device, check_device=False)
        top = {k: (1 << (int(w[k]) - 1)) - 1 for k in ("weight_bits", "product_bits", "lin_bits", "acc_bits")}
        spec = _envelope(b, s, weight_bound=top["weight_bits"], product_bound=top["product_bits"],
                         lin_width=int(w["lin_width"]), lin_bound=top["lin_bits"], acc_bound=top["acc_bits"])
    except (KeyError, TypeError, ValueError) as exc:
        raise SpecError(f"manifest 'family' entry is incomplete ({exc})") from None
    fam = FamilySpec(spec=spec, margin=margin, options=options, members=tuple(d.get("members", ())), ridge=ridge)
    _check_memory(fam)
    return fam


def clamp_codes(voltage_range_v, lsb: float, code_min: int, code_max: int) -> tuple[int, int]:
    """A member's clamp: the codes its recorded range's ends round to (the ADC rounds too), so
    the end points of a calibration sweep are measured, not clamped."""
    lo, hi = nearest_codes(sorted(voltage_range_v), lsb, code_min, code_max)
    return int(lo), int(hi)


def outside_input(fam: FamilySpec, voltage_v) -> str:
    """'' when the voltages ``voltage_v`` (readings, or a model's range) lie inside the design's
    input codes, else why not; readings piled up at their extreme are named as clipped."""
    f, v = fam.spec, np.asarray(voltage_v, dtype=float).ravel()
    lo, hi = float(v.min()), float(v.max())
    in_lo, in_hi = f.code_min * f.input_lsb_v, f.code_max * f.input_lsb_v
    if in_lo <= lo and hi <= in_hi:
        return ""
    why = f"voltage range {lo:.6g}..{hi:.6g} V exceeds the design's input {in_lo:.6g}..{in_hi:.6g} V"
    piled = max((int(np.count_nonzero(v == e)), e) for e in (lo, hi))
    if piled[0] >= CLIPPED_READINGS:
        why += (f" ({piled[0]} readings at {piled[1]:.6g} V: the output is clipped at the converter's rail, "
                "a sensor of more gain than the family's)")
    return why


def member_spec(fam: FamilySpec, model: FlannModel, model_sha256: str = "") -> Spec:
    """One sensor's values under the family formats; FitError names what does not fit."""
    f = fam.spec
    if not isinstance(model, FlannModel):
        raise SpecError("model must be a FlannModel")
    model = _padded(model, fam.terms)
    why = outside_input(fam, model.voltage_range_v)
    if why:
        raise FitError(why)
    lo, hi = sorted(model.voltage_range_v)
    try:
        s = _quiet(derive_spec, model, **fam.options, model_sha256=model_sha256, check_device=False)
    except SpecError as exc:
        raise FitError(str(exc)) from None
    words = [w for lane in s.weight_rom for w in lane]
    checks = (
        ("weights", max(abs(w) for w in words), f.weight_fmt.max_int),
        ("linear constants", lin_acc_reach(s.k1, s.k0, f.input_bits), (1 << (f.lin_width - 2)) - 1),
        ("linear part", s.lin_fmt.max_int, f.lin_fmt.max_int),
        ("products", s.product_fmt.max_int, f.product_fmt.max_int),
        ("accumulator", s.acc_fmt.max_int, f.acc_fmt.max_int),
    )
    for what, need, have in checks:
        if need > have:
            raise FitError(f"{what} reach {need}, the design holds {have}: outside the family "
                           f"(margin {fam.margin:g}); regenerate the design with this sensor in --family")
    clo, chi = clamp_codes((lo, hi), f.input_lsb_v, f.code_min, f.code_max)
    return replace(f, model=model, model_sha256=model_sha256, ka=s.ka, kb=s.kb, k1=s.k1, k0=s.k0,
                   clamp_lo=clo, clamp_hi=chi, weight_rom=s.weight_rom,
                   analysis={**s.analysis, "estimate": f.analysis.get("estimate")})


__all__ = ["check_against", "clamp_codes", "FamilySpec", "Field", "FitError", "derive_family", "family_from_dict", "member_spec",
           "bram_image", "headroom", "DATA_BITS", "HALF_BITS", "DEFAULT_MARGIN", "FORCED", "SPREAD"]
