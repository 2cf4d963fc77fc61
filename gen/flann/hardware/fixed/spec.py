"""Fixed-point hardware spec of a FLANN, derived from a model by an error/range analysis.

Layer 1 of the generator: ``derive_spec(model, **options) -> Spec`` validates the options,
chooses every width (or checks a width the user forced) and computes every constant the
hardware holds (normalisation constants, sin/slope table, weight ROMs).  The bit-true twin
(:mod:`flann.hardware.fixed.twin`) and the templates (:mod:`flann.hardware.fixed.render`) only read a :class:`Spec`.
It composes one short, checked derive function per block (``derive_input``, ``derive_output``,
``derive_phase_bits``, ``derive_expansion``, ``derive_normaliser``: ``derive_front``; then
``derive_multiplier``, ``derive_adder``, ``derive_sequencer``: ``derive_blocks``).  The float18
datapath takes the front end alone (``derive_front`` -> :class:`FrontEnd`); the family envelope
calls the same functions with its own constraints.  flann_norm and flann_expansion (templates
and twins) read a :class:`FrontEnd`; the fixed :class:`Spec` is one (a subclass).

Datapath (see docs/hardware.md)::

    code --clamp--> c --serial x const--> theta = v_n mod 2 (P bits, units of pi)
                      \\-serial x const--> lin  = (bias + w0 v_n) / q_y      (adder's start value)
    theta --phase accumulators (m theta mod 2), quarter-wave table + slope--> terms (sin/cos m pi v_n)
    terms x weights (ROM) --> products --> accumulate --> round, saturate --> out_data, out_sat

Error budget (pre-rounding, in output LSB; the final rounding adds at most 0.5 LSB so the
total stays below 1 LSB for every input code): each source gets a share and the width is the
smallest one whose *worst-case* bound fits its share; ``Spec.analysis`` lists bound and cost.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from ... import __version__
from .. import adc
from .. import target as spartan2
from .latency import ADDER_EDGES, EXPANSION_ADVANCES, MULTIPLIER_ADVANCES, SEQ_START_EDGES, norm_latency
from ...errors import SpecError
from ...numeric.fixed import FixedFormat, InputCodes, bits_needed, signed_range
from ...golden.model import FlannModel, term_kind
from ..options import MULT_STYLES, GenOptions

# Device data (luts, brams, packages) and the clock come from flann.hardware.target.
BRAM_BITS = spartan2.BRAM_BITS
CLOCK_HZ = spartan2.CLOCK_HZ

# Share of the 0.5-LSB pre-rounding budget given to each error source.
BUDGET = {"phase": 0.15, "table": 0.20, "weights": 0.07, "products": 0.03, "linear": 0.02}


def parse_device(device: str) -> tuple[str, str, str]:
    """'xc2s200-pq208-5' -> ('xc2s200', 'pq208', '5'); SpecError if not an orderable part."""
    part = spartan2.parse_part(str(device))
    return part.device.name, part.package, part.speed


def _offset_bits(phase_bits: int, table_addr_bits: int) -> int:
    # phase = 2 quadrant bits, table address, offset inside the bin
    return phase_bits - 2 - table_addr_bits


def nice_125(x: float, up: bool) -> float:
    """Nearest value of the 1-2-5 series at or above (up) / at or below x."""
    if not (math.isfinite(x) and x > 0):
        raise SpecError(f"cannot size a step from {x!r}: the model's output does not vary (weights all zero?); "
                        "give --output-lsb-mm")
    e = math.floor(math.log10(x))
    cands = [k * 10.0 ** p for p in (e - 1, e, e + 1) for k in (1, 2, 5)]
    cands = sorted(float(f"{c:.12g}") for c in cands)
    return min(c for c in cands if c >= x * (1 - 1e-12)) if up else max(c for c in cands if c <= x * (1 + 1e-12))


def round_sig(x: float, sig: int = 3, up: bool = True) -> float:
    e = math.floor(math.log10(abs(x))) - sig + 1
    f = math.ceil if up else math.floor
    return float(f"{f(x / 10.0 ** e) * 10.0 ** e:.12g}")


@dataclass(frozen=True)
class FrontEnd(InputCodes):
    """The shared front end (flann_norm, flann_expansion) as one record: the input stage, the
    normaliser's constants, the expansion's tables and the pace of its advances.  The templates
    and twins of flann_norm and flann_expansion read it; the float18 datapath is this plus its
    float blocks, and the fixed :class:`Spec` is this plus the multiplier, adder and sequencer."""

    model: FlannModel = field(repr=False, compare=False)
    model_sha256: str
    device: str
    lanes: int
    interp: bool
    # input
    input_bits: int
    input_lsb_v: float
    clamp_lo: int
    clamp_hi: int
    # normaliser: theta = round((ka*c + kb) / 2^norm_guard) mod 2^phase_bits
    phase_bits: int  # P: phase of v_n in units of pi, mod 2  (v_n has P-1 fraction bits)
    norm_guard: int
    ka: int
    kb: int
    # linear term + bias in accumulator units: lin = round((k1*c + k0) / 2^lin_guard)
    lin_guard: int
    k1: int
    k0: int
    lin_width: int  # serial accumulator width (exact, no wrap)
    lin_fmt: FixedFormat
    # sin/cos table (quarter wave, midpoint samples)
    table_addr_bits: int
    value_fmt: FixedFormat  # unsigned ROM value, frac bits = term frac bits
    slope_fmt: FixedFormat  # unsigned ROM slope
    dq_bits: int  # signed phase offset bits fed to the slope multiplier
    slope_guard: int
    term_fmt: FixedFormat
    # 'separate': sin at bin centres + a slope table; 'shared': sin at bin edges, the slope is the
    # difference of neighbouring samples read through the same table's second port (no slope ROM)
    table_style: str
    # schedule: steps advances issue the trig terms, one every adv_period cycles
    steps: int
    adv_period: int
    serial_interp: bool  # the offset x slope product formed serially between advances
    # ROM contents
    value_rom: tuple = field(repr=False)
    slope_rom: tuple = field(repr=False)

    @property
    def n_trig(self) -> int:
        return self.model.terms - 1

    @property
    def phase_frac_bits(self) -> int:
        return self.phase_bits - 1

    # -- term order: hardware trig term j is model term j + 1 (golden.model.term_kind) ---
    @staticmethod
    def trig_term(j: int) -> tuple[str, int]:
        """('sin'|'cos', harmonic m) of hardware trig term j (lane j % lanes, step j // lanes)."""
        return term_kind(j + 1)

    @property
    def delta_steps(self) -> tuple[int, int]:
        """Harmonic increase of one lane per step when its term index j is (even, odd)."""
        L = self.lanes
        return tuple(self.trig_term(j + L)[1] - self.trig_term(j)[1] for j in (0, 1))

    def lane_start(self, lane: int) -> int:
        """Harmonic of lane ``lane``'s first term (j = lane)."""
        return self.trig_term(lane)[1]

    @property
    def lane_kind_alternates(self) -> bool:
        """Whether a lane's next term is of the other kind (sin <-> cos) than its current one."""
        return self.trig_term(self.lanes)[0] != self.trig_term(0)[0]

    # -- expansion architecture ---------------------------------------------------------
    @property
    def offset_bits(self) -> int:
        """D: phase bits below the table address (offset inside a table bin)."""
        return _offset_bits(self.phase_bits, self.table_addr_bits)

    @property
    def slope_rom_bits(self) -> int:
        """Width of the slope the correction multiplies: the slope ROM's word, or (shared table)
        the low bits of the difference of two neighbouring samples."""
        return self.slope_fmt.width if self.interp else 1

    @property
    def shared_table(self) -> bool:
        return self.interp and self.table_style == "shared"

    @property
    def interp_style(self) -> str:
        """The expansion's table interpolation: 'plain' (none), 'array' (an offset x slope
        array multiplier) or 'serial' (the same product formed serially between advances)."""
        if not self.interp:
            return "plain"
        return ("serial" if self.serial_interp else "array") + ("_shared" if self.shared_table else "")

    @property
    def interp_digit(self) -> int:
        """Slope bits per cycle of the serial offset x slope product."""
        return -(-self.slope_rom_bits // (self.adv_period - 2)) if self.serial_interp else 1

    @property
    def slope_reg_bits(self) -> int:
        """Slope register, padded to whole digits of the serial product."""
        kx = self.interp_digit
        return -(-self.slope_rom_bits // kx) * kx if self.serial_interp else self.slope_rom_bits

    @property
    def interp_prod_bits(self) -> int:
        if self.serial_interp:
            return self.dq_bits + 1 + self.slope_reg_bits
        # shared: an unsigned offset ('0' & dq) times the unsigned difference ('0' & delta)
        return self.dq_bits + self.slope_rom_bits + (2 if self.shared_table else 1)

    # -- constants with the rounding half-LSB folded in (the VHDL adds them, then shifts) --
    @property
    def kb_rounded(self) -> int:
        return (self.kb + (1 << (self.norm_guard - 1))) % (1 << (self.phase_bits + self.norm_guard))

    @property
    def k0_rounded(self) -> int:
        return self.k0 + (1 << (self.lin_guard - 1))

    def float_reference(self, codes) -> np.ndarray:
        """Golden float64 model (mm) at the clamped input codes."""
        c = np.clip(np.asarray(codes, dtype=np.int64), self.clamp_lo, self.clamp_hi)
        return self.model.predict(c * self.input_lsb_v)

    def to_dict(self) -> dict:
        """The front end's fields as stamped in headers and manifest.json (the fixed Spec's
        names and order)."""
        return {
            "device": self.device,
            "terms": self.model.terms,
            "input_bits": self.input_bits,
            "input_lsb_v": self.input_lsb_v,
            "clamp_codes": [self.clamp_lo, self.clamp_hi],
            "phase_bits": self.phase_bits,
            "table_addr_bits": self.table_addr_bits,
            "interp": self.interp,
            "dq_bits": self.dq_bits,
            "slope_guard": self.slope_guard,
            "norm_guard": self.norm_guard,
            "value": self.value_fmt.describe(),
            "slope": self.slope_fmt.describe(),
            "term": self.term_fmt.describe(),
            "steps": self.steps,
        }


def serial_interp_for(interp: bool, mult_style: str, adv_period: int) -> bool:
    """Shift-add designs have adv_period - 1 idle cycles per step: the offset x slope product is
    formed serially then (one cycle copies the slope, the rest iterate)."""
    return interp and mult_style == "shiftadd" and adv_period >= 3


@dataclass(frozen=True)
class Spec(FrontEnd):
    """Everything the twin and the templates need; nothing is recomputed downstream: the
    :class:`FrontEnd`'s fields, then the multiplier's, the adder's and the sequencer's."""

    # provenance
    generator_version: str
    number_format: str  # "fixed" or "float18": the datapath this spec sizes
    # architecture
    mult_style: str
    mult_digit_bits: int  # shift-add: weight bits per cycle
    # multiplier
    weight_fmt: FixedFormat
    product_fmt: FixedFormat
    product_shift: int
    # adder
    acc_fmt: FixedFormat
    out_fmt: FixedFormat
    output_lsb_mm: float
    weight_rom: tuple = field(repr=False)  # [lane][step]
    analysis: dict = field(repr=False, compare=False, default_factory=dict)
    term_bound: int = 0  # largest |term| the expansion can produce (sizes products and acc)

    # -- derived ------------------------------------------------------------------------
    @property
    def output_bits(self) -> int:
        return self.out_fmt.width

    # -- multiplier architecture ----------------------------------------------------------
    @property
    def mult_digits(self) -> int:
        """Weight bits per cycle: shift-add's digit, 1 for the inferred multiplier."""
        return self.mult_digit_bits if self.mult_style == "shiftadd" else 1

    @property
    def weight_reg_bits(self) -> int:
        """Weight register, sign-extended to whole digits (shift-add)."""
        W, K = self.weight_fmt.width, self.mult_digits
        return -(-W // K) * K

    @property
    def pipeline_advs(self) -> int:
        """Pipeline advances: S issue steps, then the expansion's and the multiplier's own
        (the adder adds at the last)."""
        return self.steps + EXPANSION_ADVANCES + MULTIPLIER_ADVANCES

    @property
    def latency_cycles(self) -> int:
        """Clock edges from the edge accepting a sample to the edge raising out_valid: the
        blocks' latencies summed (flann_norm, flann_seq's start, the advances, flann_adder)."""
        return (norm_latency(self.input_bits) + SEQ_START_EDGES + (self.pipeline_advs - 1) * self.adv_period
                + ADDER_EDGES)

    @property
    def cycles_per_sample(self) -> int:
        return self.latency_cycles + 1

    @property
    def samples_per_s_at_50mhz(self) -> float:
        return CLOCK_HZ / self.cycles_per_sample

    def to_dict(self) -> dict:
        """The spec as stamped in headers and manifest.json (ROM contents excluded): the front
        end's fields with the multiplier's, adder's and sequencer's placed among them."""
        return _placed(super().to_dict(), {
            None: {"number_format": self.number_format},
            "device": {"lanes": self.lanes, "mult_style": self.mult_style, "mult_digit_bits": self.mult_digit_bits},
            "interp": {"table_style": self.table_style},
            "norm_guard": {"lin_guard": self.lin_guard},
            "term": {"weight": self.weight_fmt.describe(), "product": self.product_fmt.describe(),
                     "linear": self.lin_fmt.describe(), "acc": self.acc_fmt.describe(),
                     "output": self.out_fmt.describe(), "output_lsb_mm": self.output_lsb_mm},
            "steps": {"adv_period": self.adv_period},
        })


def _placed(d: dict, after: dict) -> dict:
    """``d`` with each group of ``after`` placed after its key (``None``: first); the order is
    what the headers and manifest.json show, so it is kept."""
    if not set(after) - {None} <= set(d):
        raise KeyError(f"no field {sorted(set(after) - {None} - set(d))} to place after")
    out = dict(after.get(None, {}))
    for k, v in d.items():
        out[k] = v
        out.update(after.get(k, {}))
    return out


# ------------------------------------------------------------------------------------------
def _check_int(name: str, value, lo: int, hi: int, derived: str = "") -> int:
    """``derived``: why a width the user did not give came out of range (said instead)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= int(value) <= hi:
        if derived:
            raise SpecError(f"derived {name} = {value!r} is outside {lo}..{hi}: {derived}")
        raise SpecError(f"{name} = {value!r} (--{name.replace('_', '-')}): must be an integer in {lo}..{hi}")
    return int(value)


def _table(A: int, value_fmt: FixedFormat, Dq: int, Gs: int, interp: bool):
    Tf = value_fmt.frac_bits
    k = np.arange(1 << A)
    mid = (k + 0.5) / (1 << A) * (math.pi / 2)
    value = value_fmt.quantize(np.sin(mid))
    if interp:
        slope = np.floor((math.pi / 2) * np.cos(mid) * 2.0 ** (Tf - A - Dq + Gs) + 0.5).astype(np.int64)
    else:
        slope = np.zeros_like(value)
    return value, slope


def _edge_table(A: int, value_fmt: FixedFormat):
    """sin at the bin edges k/N pi/2 (k = 0..N-1) and the largest neighbour difference
    (sample N is sin(pi/2) = 2^Tf)."""
    value = value_fmt.quantize(np.sin(np.arange(1 << A) / (1 << A) * (math.pi / 2)))
    return value, int(np.diff(np.append(value, 1 << value_fmt.frac_bits)).max())


def table_brams(A: int, widths) -> int:
    """Block RAMs of 2^A-word ROMs of the given widths (a 4-Kbit block is 4096/depth bits wide,
    at most 16), one lane."""
    per_block = min(16, max(1, BRAM_BITS >> A))
    return sum(math.ceil(w / per_block) * max(1, (1 << A) // BRAM_BITS) for w in widths)


# -- the blocks, each derived by one short, checked function ----------------------------------
# derive_spec composes them in the order the error budget needs them: the input stage (the
# normaliser's clamp), the output stage (the adder's rounding), the budget shares, the
# normaliser's phase width, the expansion, the normaliser's constants (its linear part is in the
# accumulator's units) -- the front end, derive_front -- then the multiplier, the adder, the
# sequencer.  The float18 datapath takes the front end alone; the family envelope calls the
# same functions with its own constraints.
def sfix(bound: int, frac_bits: int) -> FixedFormat:
    """The signed format that holds -bound..bound (integer units) with ``frac_bits`` fraction bits."""
    width = bits_needed(-bound, bound)
    return FixedFormat(width, width - frac_bits)


def _at_least(name: str, bound: int | None, own: int) -> int:
    """A bound a caller imposes (the family's envelope), which must hold the block's own values."""
    if bound is None:
        return own
    if bound < own:
        raise SpecError(f"{name} reach {own}, the format given holds {bound}")
    return int(bound)


@dataclass(frozen=True)
class InputStage:
    """The codes in use: the normaliser's clamp range and the model over it."""

    model: FlannModel = field(repr=False)  # at least one sin/cos term
    input_bits: int
    input_lsb_v: float
    clamp_lo: int
    clamp_hi: int
    y: np.ndarray = field(repr=False)  # the model's output (mm) at every code in use


def derive_input(model: FlannModel, input_bits, input_lsb_v, clamp) -> InputStage:
    if model.terms < 2:
        # A straight line (trained with --terms 1): the datapath has at least one sin/cos lane,
        # so the line gets sin(pi v_n) with weight 0 -- the same output, bit for bit.
        model = replace(model, weights=(*model.weights, 0.0))
    plan = adc.plan_adc(model, input_bits, input_lsb_v, clamp)  # ranges, units, wide ADCs
    for note in plan.notes:
        warnings.warn(note)
    B = _check_int("input_bits", plan.input_bits, adc.ADC_BITS[0], adc.max_input_bits(model))
    vlo, vhi = sorted(model.voltage_range_v)
    cmin, cmax = signed_range(B)
    input_lsb_v = adc.default_input_lsb(model, B) if plan.input_lsb_v is None else plan.input_lsb_v
    if not (isinstance(input_lsb_v, (int, float)) and math.isfinite(input_lsb_v) and input_lsb_v > 0):
        raise SpecError(f"input_lsb_v = {input_lsb_v!r}: must be a positive number of volts")
    lsb = float(input_lsb_v)
    if clamp:
        clo, chi = max(cmin, math.ceil(vlo / lsb - 1e-9)), min(cmax, math.floor(vhi / lsb + 1e-9))
        if clo > chi:
            raise SpecError(f"input_lsb_v = {lsb} V: the trained range {vlo}..{vhi} V holds no input code")
    else:
        clo, chi = cmin, cmax
    if (vlo < cmin * lsb or vhi > cmax * lsb) and clamp:
        warnings.warn(
            f"{B}-bit codes x {lsb} V cover {cmin * lsb:.4g}..{cmax * lsb:.4g} V, less than the "
            f"trained range {vlo:.4g}..{vhi:.4g} V"
        )
    codes = np.arange(clo, chi + 1)
    return InputStage(model, B, lsb, int(clo), int(chi), model.predict(codes * lsb))


@dataclass(frozen=True)
class OutputStage:
    """The adder's output: code width and mm per LSB."""

    output_lsb_mm: float
    out_fmt: FixedFormat


def derive_output(inp: InputStage, output_bits, output_lsb_mm) -> OutputStage:
    y = inp.y
    ymax = float(np.max(np.abs(y)))
    given = "lsb" if output_lsb_mm is not None else "bits" if output_bits is not None else ""
    if output_lsb_mm is None:
        if output_bits is None:
            step = (float(y.max() - y.min()) or 1.0) / max(1, y.size - 1)
            output_lsb_mm = nice_125(adc.default_output_step_mm(inp.model, step), up=False)
        else:
            ob = _check_int("output_bits", output_bits, 4, 32)
            output_lsb_mm = nice_125(ymax * 1.05 / ((1 << (ob - 1)) - 1), up=True)
    if not (isinstance(output_lsb_mm, (int, float)) and math.isfinite(output_lsb_mm) and output_lsb_mm > 0):
        raise SpecError(f"output_lsb_mm = {output_lsb_mm!r}: must be a positive number of mm")
    q = float(output_lsb_mm)
    adc.check_output_step(inp.model, q, given)   # fewer than 16 codes over the stroke: refused
    need_out = bits_needed(-math.ceil(ymax * 1.05 / q), math.ceil(ymax * 1.05 / q))
    if output_bits is None:
        output_bits = max(4, need_out)
        if output_bits > 32:
            raise SpecError(f"output_lsb_mm = {q:g} (--output-lsb-mm): the model's {ymax:.4g} mm then need "
                            f"{output_bits} output bits (at most 32): give a coarser --output-lsb-mm")
    Bout = _check_int("output_bits", output_bits, 4, 32)
    if Bout < bits_needed(-math.ceil(ymax / q + 1), math.ceil(ymax / q + 1)):
        raise SpecError(
            f"output_bits = {Bout} at {q} mm/LSB holds +-{((1 << (Bout - 1)) - 1) * q:.4g} mm, but the "
            f"model reaches {ymax:.4g} mm over the input range: use >= {need_out} bits or a coarser LSB"
        )
    return OutputStage(q, FixedFormat(Bout, Bout, signed=True))


@dataclass(frozen=True)
class Budget:
    """What the error budget's shares are divided by: the trig weights in output LSB."""

    wt: np.ndarray = field(repr=False)  # trig weights / output LSB, model term order
    Sw: float                           # sum |wt|
    Swm: float                          # sum |wt| x harmonic
    hint: str                           # said when a width the user did not give comes out of range
    given: frozenset                    # widths the user gave

    @property
    def N(self) -> int:
        return int(self.wt.size)

    @property
    def e_t(self) -> float:
        """Allowed error per term (term units)."""
        return BUDGET["table"] / self.Sw

    def why(self, name: str) -> str:
        return "" if name in self.given else self.hint


def error_budget(model: FlannModel, q: float, given) -> Budget:
    w = np.asarray(model.weights, dtype=float)
    wt = w[1:] / q  # trig weights in output LSB
    m = np.array([term_kind(i)[1] for i in range(1, model.terms)], dtype=float)
    return Budget(wt, float(np.sum(np.abs(wt))) or 1e-9, float(np.sum(np.abs(wt) * m)) or 1e-9,
                  adc.pathological_hint(model, q), frozenset(given))


def derive_phase_bits(budget: Budget, phase_bits) -> int:
    """The normaliser's phase width P (v_n mod 2 with P - 1 fraction bits)."""
    # phase: error per lookup <= m*(1/2 + 1/4) LSB_v (rounding of v, of ka) + 1/2 LSB (mid-sample bias)
    if phase_bits is None:
        F = math.ceil(math.log2(math.pi * (1.5 * budget.Swm + budget.Sw) / (2 * BUDGET["phase"])))
        # trig weights under an output LSB need less than the narrowest phase: take that
        phase_bits = max(6, F + 1)
    return _check_int("phase_bits", phase_bits, 6, 40, derived=budget.why("phase_bits"))


@dataclass(frozen=True)
class Expansion:
    """The sin/cos table and its interpolation, and the terms it puts out."""

    interp: bool
    table_addr_bits: int
    dq_bits: int
    slope_guard: int
    value_fmt: FixedFormat
    slope_fmt: FixedFormat
    table_style: str
    term_fmt: FixedFormat
    term_max: int  # largest |term| (sizes products and accumulator)
    value_rom: tuple = field(repr=False)
    slope_rom: tuple = field(repr=False)


def derive_expansion(budget: Budget, P: int, term_frac_bits, table_addr_bits, interp,
                     min_term_bits: int = 0) -> Expansion:
    """``min_term_bits``: the terms share a converter with wider values (float18's code): terms
    the budget sizes narrower get more fraction bits, unless the user gave them."""
    e_t = budget.e_t
    if term_frac_bits is None:
        # value and correction rounding: 2 x 2^-(Tf+1) <= e_t / 2
        term_frac_bits = max(4, math.ceil(-math.log2(e_t / 2)))
    Tf = _check_int("term_frac_bits", term_frac_bits, 4, 30, derived=budget.why("term_frac_bits"))
    if table_addr_bits is None:
        if interp:  # residual of first-order interpolation (pi/2 2^-(A+1))^2 / 2 <= e_t / 4
            A = math.ceil(math.log2(math.pi / 2 / math.sqrt(e_t / 2)) - 1)
        else:  # step error pi/2 2^-(A+1) <= e_t / 2
            A = math.ceil(math.log2(math.pi / 2 / (e_t / 2)) - 1)
        table_addr_bits = max(2, min(A, P - 3, 10))  # 10: 1024 words, 5 block RAMs
    A = _check_int("table_addr_bits", table_addr_bits, 2, 16)
    if A > P - 3:
        raise SpecError(f"table_addr_bits = {A}: must be <= phase_bits - 3 = {P - 3}")
    exp = _expansion_tables(e_t, P, Tf, A, bool(interp))
    short = min_term_bits - exp.term_fmt.width
    if short > 0 and "term_frac_bits" not in budget.given:
        exp = _expansion_tables(e_t, P, _check_int("term_frac_bits", Tf + short, 4, 30), A, bool(interp))
    return exp


def _expansion_tables(e_t: float, P: int, Tf: int, A: int, interp: bool) -> Expansion:
    D = _offset_bits(P, A)
    if interp:
        # offset truncation (pi/2) 2^-(A+Dq) <= e_t/8 ; slope rounding 2^(Dq-2-Gs-Tf) <= e_t/8
        Dq = min(D + 1, max(2, math.ceil(math.log2(math.pi / 2 * 8 / e_t)) - A))
        Gs = max(0, math.ceil(Dq - 2 - Tf - math.log2(e_t / 8)))
    else:
        Dq, Gs = D + 1, 0
    value_fmt = FixedFormat(Tf + 1, 1, signed=False)
    value_rom, slope_rom = _table(A, value_fmt, Dq, Gs, interp)
    slope_fmt = FixedFormat(max(1, bits_needed(0, int(slope_rom.max()), signed=False)), 0, signed=False)
    corr_max = (int(slope_rom.max()) << (Dq - 1)) >> Gs if interp else 0
    table_style = "separate"
    if interp:
        # the shared table: same residual (linear interpolation between samples h apart, h^2/8),
        # no slope ROM; its difference is formed modulo 2^C, exact when C <= Tf (2^Tf = 0 mod 2^C
        # and sample 0 is 0, so the wrapped read of sample N-1's neighbour gives sin(pi/2))
        edge_rom, delta_max = _edge_table(A, value_fmt)
        C = max(1, bits_needed(0, delta_max, signed=False))
        if C <= Tf and table_brams(A, [Tf + 1]) < table_brams(A, [Tf + 1, slope_fmt.width]):
            table_style = "shared"
            # offset truncation 2^-Dq (h + 2^-Tf) <= e_t/8; the product's shift rounds to the term LSB
            h = math.pi / 2 * 2.0 ** -A
            Dq = min(D + 1, max(2, math.ceil(math.log2(8 * (h + 2.0 ** -Tf) / e_t))))
            Gs = Dq
            value_rom, slope_rom = edge_rom, np.zeros(0, dtype=np.int64)
            slope_fmt = FixedFormat(C, 0, signed=False)
            corr_max = delta_max  # dq < 2^Dq: the rounded product stays <= the difference
    term_max = int(value_rom.max()) + corr_max + 1
    term_fmt = FixedFormat(bits_needed(-term_max, term_max), bits_needed(-term_max, term_max) - Tf)
    return Expansion(interp, A, Dq, Gs, value_fmt, slope_fmt, table_style, term_fmt, term_max,
                     tuple(int(x) for x in value_rom), tuple(int(x) for x in slope_rom))


@dataclass(frozen=True)
class Multiplier:
    """Terms x weights (the weight ROM, one per lane) -> products."""

    weight_fmt: FixedFormat
    product_fmt: FixedFormat
    product_shift: int
    lanes: int
    steps: int
    weight_rom: tuple = field(repr=False)  # [lane][step]


def product_frac_bits_for(budget: Budget, product_frac_bits) -> int:
    """The products' (and accumulator's) fraction bits: the budget's share over N roundings."""
    if product_frac_bits is None:
        product_frac_bits = max(0, math.ceil(math.log2(budget.N / (2 * BUDGET["products"]))))
    return _check_int("product_frac_bits", product_frac_bits, 0, 30)


def derive_multiplier(budget: Budget, exp: Expansion, weight_frac_bits, Pf: int, lanes: int,
                      weight_bound: int | None = None, product_bound: int | None = None) -> Multiplier:
    """``weight_bound`` / ``product_bound``: the largest magnitudes (integer units) the formats
    hold, at least the model's own (default: exactly those)."""
    Tf, term_max, N = exp.term_fmt.frac_bits, exp.term_max, budget.N
    if weight_frac_bits is None:
        weight_frac_bits = max(0, math.ceil(math.log2(N * term_max / 2.0 ** Tf / (2 * BUDGET["weights"]))))
    Wf = _check_int("weight_frac_bits", weight_frac_bits, 0, 30, derived=budget.why("weight_frac_bits"))
    w_int = np.floor(budget.wt * 2.0 ** Wf + 0.5).astype(np.int64)
    # at least +-1: weights that all round to 0 (a straight line) still get a 2-bit word,
    # which the default 2-bit shift-add digit needs
    own = max(1, int(np.max(np.abs(w_int)))) if w_int.size else 1
    wmax = _at_least("weights", weight_bound, own)
    shift = Tf + Wf - Pf
    if shift < 1:
        raise SpecError(f"product_frac_bits = {Pf}: must be < term_frac_bits + weight_frac_bits = {Tf + Wf}")
    if product_bound is None:
        pmax = (term_max * wmax + (1 << (shift - 1))) >> shift
    else:
        pmax = _at_least("products", product_bound, (term_max * own + (1 << (shift - 1))) >> shift)
    S = steps_for(N, lanes)
    rom = np.zeros(S * lanes, dtype=np.int64)
    rom[:N] = w_int
    return Multiplier(sfix(wmax, Wf), sfix(pmax, Pf), shift, lanes, S,
                      tuple(tuple(int(x) for x in rom[l::lanes]) for l in range(lanes)))


@dataclass(frozen=True)
class Normaliser:
    """theta = v_n mod 2 (the expansion's phase) and lin = bias + w0 v_n (the adder's start value)."""

    phase_bits: int
    norm_guard: int
    ka: int
    kb: int
    lin_guard: int
    k1: int
    k0: int
    lin_width: int       # serial accumulator of k1 x code (exact, no wrap)
    lin_fmt: FixedFormat
    lin_bound: int       # largest |lin| + 1 the formats after it hold
    lin_peak: int        # largest |lin| + 1 of this model (= lin_bound unless an envelope's is given)


def lin_acc_width(k1_bound: int, k0_bound: int, input_bits: int) -> int:
    """The serial k1 x code + k0 accumulator, exact for every code (one guard bit). It holds
    k1's partial products (|k1 c| <= |k1| 2^(B-1)) and then k1 c + k0 + 2^(Gl-1) (k0 with its
    rounding half, Gl = B + 3): a tiny linear weight makes the half the largest of them."""
    reach = lin_acc_reach(k1_bound, k0_bound, input_bits)
    return bits_needed(-reach, reach) + 1


def lin_acc_reach(k1: int, k0: int, input_bits: int) -> int:
    """The largest magnitude the serial k1 x code + k0 accumulator holds (see :func:`lin_acc_width`)."""
    return (abs(int(k1)) << (input_bits - 1)) + abs(int(k0)) + (1 << (input_bits + 2))


def derive_normaliser(inp: InputStage, P: int, q: float, Pf: int, lin_width: int | None = None,
                      lin_bound: int | None = None) -> Normaliser:
    """``lin_width`` / ``lin_bound``: an envelope's (the family's), at least the model's own."""
    model, B = inp.model, inp.input_bits
    w0 = float(model.weights[0])
    a = inp.input_lsb_v / model.input_scale_v
    b = -model.input_offset_v / model.input_scale_v
    # linear term + bias, straight into the accumulator (accumulator units 2^-Pf LSB)
    Gl = B + 3
    k1 = int(math.floor(w0 * a / q * 2.0 ** (Pf + Gl) + 0.5))
    k0 = int(math.floor((w0 * b + model.bias) / q * 2.0 ** (Pf + Gl) + 0.5))
    width = _at_least("the linear accumulator's values", lin_width, lin_acc_width(abs(k1), abs(k0), B))
    lin_vals = [(k1 * c + k0 + (1 << (Gl - 1))) >> Gl for c in (inp.clamp_lo, inp.clamp_hi)]
    peak = max(abs(v) for v in lin_vals) + 1
    bound = _at_least("linear part", lin_bound, peak)
    # normaliser: theta = v_n mod 2 with F fraction bits; guard bits make ka's rounding
    # cost at most 1/4 LSB_v over the code range
    F, Gn = P - 1, B + 1
    ka = int(math.floor(a * 2.0 ** (F + Gn) + 0.5)) % (1 << (P + Gn))
    kb = int(math.floor(b * 2.0 ** (F + Gn) + 0.5)) % (1 << (P + Gn))
    return Normaliser(P, Gn, ka, kb, Gl, k1, k0, width, sfix(bound, Pf), bound, peak)


def acc_bound_for(lin_bound: int, weights, term_max: int, shift: int) -> int:
    """Largest |running sum| + 1: the start value, then every product (rounded) of ``weights``."""
    return lin_bound + sum(((term_max * abs(int(x)) + (1 << (shift - 1))) >> shift) + 1 for x in weights)


def derive_adder(norm: Normaliser, exp: Expansion, mult: Multiplier, acc_bound: int | None = None) -> FixedFormat:
    """The accumulator's format; ``acc_bound``: an envelope's, at least the model's own sums."""
    words = [w for lane in mult.weight_rom for w in lane]
    if acc_bound is None:
        acc_bound = acc_bound_for(norm.lin_bound, words, exp.term_max, mult.product_shift)
    else:
        acc_bound = _at_least("the running sums", acc_bound,
                              acc_bound_for(norm.lin_peak, words, exp.term_max, mult.product_shift))
    # at least one integer bit: the adder rounds by adding 2^(Pf-1) in acc_bits + 1 bits, which
    # must hold it when every weight is far below an output LSB (an order of a two-input model)
    Pf = mult.product_fmt.frac_bits
    fmt = sfix(acc_bound, Pf)
    return fmt if fmt.width > Pf else FixedFormat(Pf + 1, 1)


@dataclass(frozen=True)
class Sequencer:
    """The advance period: one step every ``adv_period`` cycles (the multiplier's pace)."""

    mult_style: str
    mult_digit_bits: int
    adv_period: int


def check_mult_style(mult_style) -> None:
    if mult_style not in MULT_STYLES:
        raise SpecError(f"mult_style {mult_style!r}: must be one of {', '.join(MULT_STYLES)}")


def derive_sequencer(mult_style: str, mult_digit_bits, weight_bits: int) -> Sequencer:
    check_mult_style(mult_style)
    K = _check_int("mult_digit_bits", mult_digit_bits, 1, weight_bits)
    # shift-add: ceil(W/K) cycles per product, then the advance that hands it on
    return Sequencer(mult_style, K, 1 if mult_style == "lut" else -(-weight_bits // K) + 1)


@dataclass(frozen=True)
class Front:
    """The blocks before the multiplier: the input and output stages, the budget, the
    normaliser (its linear part is in the accumulator's units, so the products' fraction bits
    are chosen here) and the expansion.  Every datapath that uses flann_norm and
    flann_expansion derives them here, with its own constraints."""

    input: InputStage
    output: OutputStage
    budget: Budget
    normaliser: Normaliser
    expansion: Expansion
    product_frac_bits: int


def derive_front(model: FlannModel, o: GenOptions, *, terms_hold_code: bool = False) -> Front:
    """The front end's blocks for ``model`` under the options ``o``.  ``terms_hold_code``: the
    terms share a converter with the input code (the float18 datapath), so they are at least as
    wide as the code."""
    parse_device(o.device)
    inp = derive_input(model, o.input_bits, o.input_lsb_v, o.clamp)
    out = derive_output(inp, o.output_bits, o.output_lsb_mm)
    given = {k for k in ("phase_bits", "term_frac_bits", "weight_frac_bits") if getattr(o, k) is not None}
    budget = error_budget(inp.model, out.output_lsb_mm, given)
    P = derive_phase_bits(budget, o.phase_bits)
    exp = derive_expansion(budget, P, o.term_frac_bits, o.table_addr_bits, o.interp,
                           min_term_bits=inp.input_bits if terms_hold_code else 0)
    Pf = product_frac_bits_for(budget, o.product_frac_bits)
    norm = derive_normaliser(inp, P, out.output_lsb_mm, Pf)
    _check_62((("lin accumulator", norm.lin_width), ("normaliser", norm.phase_bits + norm.norm_guard)), budget)
    return Front(inp, out, budget, norm, exp, Pf)


def steps_for(n_trig: int, lanes: int) -> int:
    """Advances that issue every trig term, ``lanes`` per advance."""
    return math.ceil(n_trig / lanes)


def front_end(f: Front, *, model_sha256: str, device: str, lanes: int, adv_period: int,
              serial_interp: bool = False) -> FrontEnd:
    """The :class:`FrontEnd` record of derived front blocks, advanced every ``adv_period`` cycles."""
    return FrontEnd(**_front_fields(f, model_sha256=model_sha256, device=device, lanes=lanes,
                                    adv_period=adv_period, serial_interp=serial_interp))


def _front_fields(f: Front, *, model_sha256: str, device: str, lanes: int, adv_period: int,
                  serial_interp: bool) -> dict:
    i, n, e = f.input, f.normaliser, f.expansion
    return dict(
        model=i.model, model_sha256=model_sha256, device=device.lower(), lanes=lanes, interp=e.interp,
        input_bits=i.input_bits, input_lsb_v=i.input_lsb_v, clamp_lo=i.clamp_lo, clamp_hi=i.clamp_hi,
        phase_bits=n.phase_bits, norm_guard=n.norm_guard, ka=n.ka, kb=n.kb, lin_guard=n.lin_guard, k1=n.k1,
        k0=n.k0, lin_width=n.lin_width, lin_fmt=n.lin_fmt, table_addr_bits=e.table_addr_bits,
        value_fmt=e.value_fmt, slope_fmt=e.slope_fmt, dq_bits=e.dq_bits, slope_guard=e.slope_guard,
        term_fmt=e.term_fmt, table_style=e.table_style, steps=steps_for(f.budget.N, lanes), adv_period=adv_period,
        serial_interp=serial_interp, value_rom=e.value_rom, slope_rom=e.slope_rom,
    )


@dataclass(frozen=True)
class Blocks:
    """A fixed datapath's blocks, before they are stamped into one :class:`Spec`."""

    input: InputStage
    output: OutputStage
    budget: Budget
    normaliser: Normaliser
    expansion: Expansion
    multiplier: Multiplier
    acc_fmt: FixedFormat
    sequencer: Sequencer


def max_lanes(terms: int) -> int:
    """The most lanes a model of ``terms`` terms takes: the lanes share its sin/cos terms
    (a straight line, one term, still gets one lane)."""
    return max(1, terms - 1)


def derive_blocks(model: FlannModel, o: GenOptions) -> Blocks:
    """Every block of the fixed datapath for ``model`` under the options ``o``: the front end,
    then the multiplier, the adder and the sequencer."""
    parse_device(o.device)
    # the lanes and the multiplier style are checked before the widths they shape
    L = _check_int("lanes", o.lanes, 1, max_lanes(model.terms))
    check_mult_style(o.mult_style)
    f = derive_front(model, o)
    mult = derive_multiplier(f.budget, f.expansion, o.weight_frac_bits, f.product_frac_bits, L)
    acc_fmt = derive_adder(f.normaliser, f.expansion, mult)
    check_widths(f.normaliser, f.expansion, mult, acc_fmt, f.budget)
    return Blocks(f.input, f.output, f.budget, f.normaliser, f.expansion, mult, acc_fmt,
                  derive_sequencer(o.mult_style, o.mult_digit_bits, mult.weight_fmt.width))


def _check_62(widths, budget: Budget) -> None:
    for name, width in widths:
        if width > 62:
            raise SpecError(f"{name} would need {width} bits (> 62): "
                            + ("reduce the requested widths" if budget.given else budget.hint))


def check_widths(norm: Normaliser, exp: Expansion, mult: Multiplier, acc_fmt: FixedFormat, budget: Budget) -> None:
    _check_62((("lin accumulator", norm.lin_width), ("normaliser", norm.phase_bits + norm.norm_guard),
               ("accumulator", acc_fmt.width), ("product", exp.term_fmt.width + mult.weight_fmt.width)), budget)


def compose(b: Blocks, *, model_sha256: str, device: str, number_format: str) -> Spec:
    """The :class:`Spec` the twin and the templates read: every block's fields, stamped."""
    e, m, s = b.expansion, b.multiplier, b.sequencer
    front = Front(b.input, b.output, b.budget, b.normaliser, e, m.product_fmt.frac_bits)
    return Spec(
        **_front_fields(front, model_sha256=model_sha256, device=device, lanes=m.lanes, adv_period=s.adv_period,
                        serial_interp=serial_interp_for(e.interp, s.mult_style, s.adv_period)),
        generator_version=__version__, number_format=number_format, mult_style=s.mult_style,
        mult_digit_bits=s.mult_digit_bits, weight_fmt=m.weight_fmt, product_fmt=m.product_fmt,
        product_shift=m.product_shift, acc_fmt=b.acc_fmt, out_fmt=b.output.out_fmt,
        output_lsb_mm=b.output.output_lsb_mm, weight_rom=m.weight_rom, term_bound=int(e.term_max),
    )


def assemble(b: Blocks, *, model_sha256: str = "", device: str, number_format: str = "fixed",
             check_device: bool = True) -> Spec:
    """The composed :class:`Spec` with its error analysis (a warning when it exceeds 1 LSB) and,
    with ``check_device``, refused when the part cannot hold it."""
    spec = compose(b, model_sha256=model_sha256, device=device, number_format=number_format)
    analysis = error_analysis(spec, Sw=b.budget.Sw, Swm=b.budget.Swm, N=b.budget.N)
    spec = replace(spec, analysis=analysis)
    if not analysis["guaranteed_1lsb"]:
        warnings.warn(
            f"these widths bound |hardware - float model| by {analysis['bound_total_lsb']:.3g} output LSB "
            f"(> 1): see the spec analysis for the dominant source"
        )
    if check_device:
        check_fits(spec, parse_device(device)[0])
    return spec


def derive_spec(
    model: FlannModel,
    options: GenOptions | None = None,
    *,
    model_sha256: str = "",
    number_format: str = "fixed",
    check_device: bool = True,
    **overrides,
) -> Spec:
    """Validate options, size every signal by the error budget, compute every constant.

    ``options`` (default: :class:`GenOptions`'s defaults) with ``overrides`` by keyword.
    """
    o = GenOptions.of(options, **overrides)
    if not isinstance(model, FlannModel):
        raise SpecError("model must be a FlannModel (load it with flann.golden.model.load_model)")
    if number_format != "fixed":
        raise SpecError(f"number format {number_format!r}: only 'fixed' is generated")
    return assemble(derive_blocks(model, o), model_sha256=model_sha256, device=o.device,
                    number_format=number_format, check_device=check_device)


def error_analysis(spec: Spec, *, Sw: float, Swm: float, N: int) -> dict:
    """Worst-case bound (output LSB) of each error source, and what each choice costs."""
    F, Tf, A, Dq, Gs = spec.phase_bits - 1, spec.term_fmt.frac_bits, spec.table_addr_bits, spec.dq_bits, spec.slope_guard
    Wf, Pf = spec.weight_fmt.frac_bits, spec.product_fmt.frac_bits
    term_max = spec.term_fmt.max_int / 2.0 ** Tf
    e_phase = math.pi * (Swm * 1.5 + Sw) * 2.0 ** -(F + 1)
    if spec.shared_table:
        # samples' rounding (their convex combination), the product's rounding, linear
        # interpolation h^2/8, offset truncation < 2^-Dq times the difference (<= h + 2^-Tf)
        h = math.pi / 2 * 2.0 ** -A
        e_tab = 2 * 2.0 ** -(Tf + 1) + h * h / 8 + 2.0 ** -Dq * (h + 2.0 ** -Tf)
    elif spec.interp:
        e_tab = 2 * 2.0 ** -(Tf + 1) + (math.pi / 2 * 2.0 ** -(A + 1)) ** 2 / 2 \
            + math.pi / 2 * 2.0 ** -(A + Dq) + 2.0 ** (Dq - 2 - Gs - Tf)
    else:
        e_tab = 2.0 ** -(Tf + 1) + math.pi / 2 * 2.0 ** -(A + 1)
    bounds = {
        "phase": e_phase,
        "table": Sw * e_tab,
        "weights": N * term_max * 2.0 ** -(Wf + 1),
        "products": N * 2.0 ** -(Pf + 1),
        "linear": 2.0 ** -(Pf + 1) + 2.0 ** -(Pf + 4),
    }
    bounds["output_rounding"] = 0.5
    total = sum(bounds.values())
    slope_rom_bits = spec.slope_fmt.width if spec.interp and not spec.shared_table else 0
    rom_bits = (1 << A) * (spec.value_fmt.width + slope_rom_bits)
    wrom_bits = spec.steps * spec.weight_fmt.width
    est = estimate_resources(spec)
    return {
        "bound_lsb": {k: round(v, 6) for k, v in bounds.items()},
        "bound_total_lsb": round(total, 6),
        "guaranteed_1lsb": total <= 1.0,
        "cost": {
            "phase_bits": f"{spec.phase_bits}: phase accumulators {spec.lanes}x{spec.phase_bits} FF + adders; "
                          f"each bit less doubles the phase bound ({bounds['phase']:.3g} LSB)",
            "table": f"{1 << A} x ({spec.value_fmt.width}+{slope_rom_bits}) bits "
                     f"= {rom_bits} ROM bits per lane; one address bit less x4 interpolation residual"
                     + ("; slope = difference of neighbouring samples (second port)" if spec.shared_table else ""),
            "interp": (f"slope product {Dq}x{spec.slope_fmt.width} per lane, "
                       + ("serial between advances" if spec.serial_interp else "array multiplier"))
                      if spec.interp else "off: table step error dominates",
            "weights": f"{spec.weight_fmt.width}-bit weights, {wrom_bits} ROM bits per lane",
            "multiplier": f"{spec.term_fmt.width}x{spec.weight_fmt.width} {spec.mult_style}, "
                          f"{spec.adv_period} cycle(s) per step",
        },
        "estimate": est,
    }


def estimate_resources(spec: Spec) -> dict:
    """Rough pre-synthesis estimate (LUT4, FF, block RAM) used to reject hopeless requests.

    Coefficients calibrated on `flann synth` (GHDL + yosys synth_xilinx -family xcv) of the
    51-term default in both multiplier styles, the shift-add ones again on the 40 e2e designs of
    bench/small_parts.py (1.00-1.13x measured); ``flann synth`` gives the measured figures.
    """
    L = spec.lanes
    T, W = spec.term_fmt.width, spec.weight_fmt.width
    P, A = spec.phase_bits, spec.table_addr_bits
    C, Dq = spec.slope_fmt.width, spec.dq_bits
    serial = spec.serial_interp
    # shift-add: one adder per weight digit, and the weight ROM when it stays in LUTs
    rom = spec.steps * W / 16 if spec.steps * W <= 2048 else 0
    mult = 5.3 * T * W if spec.mult_style == "lut" else 3.2 * (T + W) + 1.5 * T * (spec.mult_digit_bits - 1) + rom
    # slope correction: array multiplier, or serial between advances (shift-add designs)
    interp = 0 if not spec.interp else (6.3 * (Dq + C) if serial else 4.6 * Dq * (C + 1))
    if spec.shared_table:  # the difference's subtractor and the second port's address increment
        interp += C + A
    expansion = interp + 3.4 * P - T  # the quadrant's negation folded into one adder
    norm = P + spec.norm_guard + spec.lin_width  # LSB first: one adder per product, no offset adder
    adder = 3.6 * spec.acc_fmt.width + (L - 1) * spec.acc_fmt.width
    luts = L * (mult + expansion) + norm + adder + 30
    # the normaliser's accumulators and its output registers
    ffs = L * (2 * P + 3 * T + spec.product_fmt.width + W) + 2 * norm + spec.acc_fmt.width + 40
    # each lane reads its own copy; a bit no entry sets is no memory bit (synthesis drops it:
    # sin below pi/2 never reaches the value format's integer bit)
    value_bits = bits_needed(0, max(spec.value_rom), signed=False) if spec.value_rom else spec.value_fmt.width
    tables = [value_bits] + ([spec.slope_fmt.width] if spec.interp and not spec.shared_table else [])
    brams = L * table_brams(A, tables)
    if spec.steps * W > 2048:  # small weight ROMs go to LUTs
        brams += L * math.ceil(spec.steps * W / BRAM_BITS)
    return {"luts": int(luts), "ffs": int(ffs), "brams": int(brams)}


def check_fits(spec: Spec, part: str) -> None:
    est = spec.analysis.get("estimate") or estimate_resources(spec)
    dev = spartan2.device(part)
    if est["luts"] <= dev.luts and est["brams"] <= dev.brams:
        return
    fits = [d.name for d in spartan2.DEVICES if est["luts"] <= d.luts and est["brams"] <= d.brams]
    cheaper = ["fewer terms"] + (["fewer lanes"] if spec.lanes > 1 else []) + \
        (["mult_style=shiftadd"] if spec.mult_style != "shiftadd" else [])
    hint = f"smallest part that could hold it: {fits[0]}" if fits else \
        f"no Spartan-II holds it: {', '.join(cheaper[:-1])}{' or ' if len(cheaper) > 1 else ''}{cheaper[-1]}"
    raise SpecError(
        f"{spec.model.terms} terms x {spec.lanes} lane(s) ({spec.mult_style}) need about "
        f"{est['luts']} LUT4 and {est['brams']} block RAMs; {part} has {dev.luts} and {dev.brams} "
        f"({hint})"
    )


__all__ = ["max_lanes", "Spec", "serial_interp_for", "Front", "derive_front", "FrontEnd", "front_end", "steps_for", "derive_spec", "table_brams", "round_sig", "MULT_STYLES", "parse_device", "estimate_resources",
           "error_analysis", "BUDGET", "CLOCK_HZ", "Blocks", "derive_blocks", "compose", "assemble", "sfix",
           "InputStage", "derive_input", "OutputStage", "derive_output", "Budget", "error_budget",
           "derive_phase_bits", "Expansion", "derive_expansion", "Multiplier", "product_frac_bits_for",
           "derive_multiplier", "Normaliser", "derive_normaliser", "lin_acc_width", "acc_bound_for", "derive_adder",
           "Sequencer", "derive_sequencer", "check_mult_style", "check_widths"]
