"""The FLANN datapath in float18 (the seed's number format): spec and bit-true twin.

The float18 design is the shared front end (the fixed datapath's input stage, normaliser and
expansion, derived by the same block derives into a
:class:`~flann.hardware.fixed.spec.FrontEnd`: the same ``flann_norm`` / ``flann_expansion``
entities and twins) plus the seed's 18-bit floating-point multiplier and adder::

    code --clamp--> c ------------------------------.
    code --flann_norm--> theta --flann_expansion--> terms (fixed, Tf fraction bits)
                                                      |
                    flann_f18_cvt: fixed -> float18 (RNE)   [term 0 is c itself]
                    flann_f18_mul: x weight (float18 ROM)
                    flann_f18_add: running sum, one term at a time, in model term order
                    out_data = float18 code of the displacement in mm

Term 0 (the linear term w0 v_n) enters as the clamped code c read as a term value
c * 2^-Tf (exact in float18: |c| < 2^12), with weight w0 * (lsb / scale) * 2^Tf; the
scaling by 2^Tf is exact, so the product is RNE(c * w0 lsb / scale).  The offset part
w0 * (-offset / scale) and the bias form the running sum's start value.  The sum order
(start, term 0, term 1, ..., term N-1) is the hardware's and is part of the bit-true
definition: float addition is not associative.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...errors import SpecError
from ...numeric.float18 import FLOAT18, FlannF18Add, FlannF18Mul, FloatFormat, FloatOut
from ...golden.model import FlannModel
from ..fixed.latency import EXPANSION_ADVANCES, SEQ_START_EDGES, norm_latency
from ..fixed.spec import FrontEnd, derive_front, front_end
from ..delegate import delegated
from ..options import GenOptions
from ..twin import TopOut

TOP = "flann_f18_top"
TOP_DRAIN_EDGES = 3  # flann_f18_top after the adder: sum register and count, done_r, output register
CVT = "flann_f18_cvt"
from ..fixed.twin import FlannExpansion, FlannNorm

# options of the fixed-point spec that the float18 datapath shares (input stage, expansion);
# every other generator option (widths of weights/products/output, multiplier style, ...)
# belongs to the fixed datapath only
FRONT_END_OPTIONS = ("device", "input_bits", "input_lsb_v", "clamp", "phase_bits", "table_addr_bits",
                     "interp", "term_frac_bits", "model_sha256", "check_device", "lanes")


def float18_options(options: GenOptions, fixed_too: bool = False) -> dict:
    """Generator options for the float18 design.  Fixed-only options left at their defaults
    are dropped; given explicitly they are kept, so that the spec rejects them with a clear
    message, unless ``fixed_too`` (a comparison where they are meant for the fixed design)."""
    changed = options.changed()
    return {k: v for k, v in options.to_kwargs().items()
            if k in FRONT_END_OPTIONS or (k in changed and not fixed_too)}


@dataclass(frozen=True)
class F18Spec:
    """The shared fixed-point front end (input, normaliser, expansion) plus the float18
    arithmetic constants."""

    front: FrontEnd = field(repr=False)
    fmt: FloatFormat
    weight_codes: tuple[int, ...]   # model term order; [0] is the code term's weight
    start_code: int                 # bias + w0 * (-offset / scale)

    number_format = "float18"

    # the shared front end's own values, under the same names
    model = delegated("front.model")
    # cycles per term: the adder's latency (its result forwarded), the front end's pace
    adv_period = delegated("front.adv_period")
    code_min = delegated("front.code_min")
    code_max = delegated("front.code_max")
    terms = delegated("front.model.terms")
    term_frac_bits = delegated("front.term_fmt.frac_bits")

    @property
    def n_advs(self) -> int:
        """Expansion advances: one per trig term, plus the expansion's own to bring the first term out."""
        return self.front.steps + EXPANSION_ADVANCES

    @property
    def latency_cycles(self) -> int:
        """Accepting edge to the edge that raises out_valid (checked by the top-level bench)."""
        # flann_norm, flann_seq's start, the advances (the last term is captured at advance
        # n_advs - 1), then converter + multiplier + adder, then this top's own three edges:
        # the sum register and count, done_r (flann_seq's in_done), the output register
        return (norm_latency(self.front.input_bits) + SEQ_START_EDGES + (self.n_advs - 1) * self.adv_period
                + FlannF18Cvt.latency + FlannF18Mul.latency + FlannF18Add.latency + TOP_DRAIN_EDGES)

    @property
    def cycles_per_sample(self) -> int:
        return self.latency_cycles + 1

    def golden_weights(self) -> np.ndarray:
        """Exact (float64) constants the float18 ROM approximates, same order and scaling."""
        m = self.model
        w = np.asarray(m.weights, dtype=float).copy()
        w[0] = w[0] * (self.front.input_lsb_v / m.input_scale_v) * 2.0 ** self.term_frac_bits
        return w

    def golden_start(self) -> float:
        m = self.model
        return m.bias + m.weights[0] * (-m.input_offset_v / m.input_scale_v)

    def float_reference(self, codes) -> np.ndarray:
        return self.front.float_reference(codes)

    def to_dict(self) -> dict:
        d = self.front.to_dict()
        d.update(number_format="float18", float=self.fmt.to_dict(), adv_period=self.adv_period,
                 sum_order="start, code term, trig terms in model order (sequential)")
        return d


def derive_f18_spec(model: FlannModel, **options) -> F18Spec:
    """Float18 spec: the shared front end, float18 constants."""
    options = {k: v for k, v in options.items() if v is not None and k != "number_format"}
    for k in options:
        if k not in FRONT_END_OPTIONS:
            raise SpecError(f"{k.replace('_', '-')}: applies to the fixed format only, not float18 "
                            "(which has its own multiplier and adder)")
    if options.get("lanes", 1) != 1:
        raise SpecError("lanes: the float18 datapath has one lane (sequential float sum), got "
                        f"{options['lanes']}")
    options.pop("lanes", None)
    options.pop("number_format", None)
    # The fixed design's device estimate (multiplier, accumulator) does not apply: `flann synth`
    # measures the float18 design itself.
    options.pop("check_device", None)
    sha = options.pop("model_sha256", "")
    o = GenOptions.of(None, **options)
    if not isinstance(model, FlannModel):
        raise SpecError("model must be a FlannModel (load it with flann.golden.model.load_model)")
    # small trig weights need only narrow terms, but the code shares the term converter: the
    # expansion widens the terms to the code's width (more precision than the budget asks).
    # The front end takes an advance every adder latency and forms the slope correction in one
    # step (the array form: only a shift-add multiplier's idle cycles make the serial one pay).
    front = front_end(derive_front(model, o, terms_hold_code=True), model_sha256=sha, device=o.device, lanes=1,
                      adv_period=FlannF18Add.latency)
    fmt = FLOAT18
    Tf = front.term_fmt.frac_bits
    if front.input_bits > fmt.sig_bits:
        drop = front.input_bits - fmt.sig_bits
        raise SpecError(f"input_bits = {front.input_bits}: float18 holds input codes exactly only up to "
                        f"{fmt.sig_bits} bits: feed it the converter's top {fmt.sig_bits} bits (--input-bits "
                        f"{fmt.sig_bits} --input-lsb-v {front.input_lsb_v * 2 ** drop:.6g}) or generate the "
                        "fixed-point design")
    if front.term_fmt.width < front.input_bits:
        raise SpecError(f"term width {front.term_fmt.width} < input_bits {front.input_bits}: the code "
                        "cannot share the term converter")
    if Tf > fmt.bias - 1:
        raise SpecError(f"term_frac_bits = {Tf}: float18 cannot hold 2^-{Tf} (min normal 2^{1 - fmt.bias})")
    spec = F18Spec(front=front, fmt=fmt, weight_codes=(), start_code=0)
    w = spec.golden_weights()
    for i, x in enumerate(w):
        if abs(x) > float(fmt.max_value):
            raise SpecError(f"weight {i} = {x:.4g} exceeds float18's max finite {float(fmt.max_value):.4g}")
    start = spec.golden_start()
    if not math.isfinite(start) or abs(start) > float(fmt.max_value):
        raise SpecError(f"bias {start:.4g} exceeds float18's range")
    return F18Spec(front=front, fmt=fmt, weight_codes=tuple(int(c) for c in fmt.encode_array(w)),
                   start_code=int(fmt.encode_array([start])[0]))


# -- twins ---------------------------------------------------------------------------------
class FlannF18Cvt:
    """Twin of ``flann_f18_cvt``: signed fixed (``frac_bits`` fraction bits) -> float18, RNE."""

    entity = CVT
    latency = 1

    def __init__(self, frac_bits: int, fmt: FloatFormat = FLOAT18):
        self.frac_bits = frac_bits
        self.fmt = fmt

    def process(self, in_data) -> FloatOut:
        """Every value of ``in_data`` (any shape), vectorised; ``out_y`` as the entity gives it
        ``latency`` cycles later."""
        return FloatOut(out_y=self._convert(in_data))

    def _convert(self, ints) -> np.ndarray:
        a = np.asarray(ints, dtype=np.int64)
        if a.size and np.abs(a).max() >= 2 ** 53:
            raise ValueError("fixed value too wide for the float64 path")
        return self.fmt.encode_array(np.ldexp(a.astype(float), -self.frac_bits))


@dataclass
class F18Trace:
    """Every stage of the float18 twin (codes are float18 codes, int64)."""

    codes: np.ndarray          # input codes as given
    code: np.ndarray           # clamped
    sat_in: np.ndarray
    fixed_terms: np.ndarray    # (n, N): [c, trig terms...] as Tf-fraction integers
    terms: np.ndarray          # (n, N) float18 codes after conversion
    products: np.ndarray       # (n, N) float18 codes
    running: np.ndarray        # (n, N) float18 codes after each add
    out: np.ndarray            # (n,) float18 code
    sat: np.ndarray            # (n,) input clamped or output at +-max finite


class FlannF18Top:
    """Twin of ``flann_f18_top``: out_data (float18 code) and out_sat for each input code."""

    entity = TOP

    def __init__(self, spec: F18Spec):
        self.spec = spec
        self.latency = spec.latency_cycles
        self.norm = FlannNorm(spec.front)
        self.expansion = FlannExpansion(spec.front)
        self.cvt = FlannF18Cvt(spec.term_frac_bits, spec.fmt)
        self.fmt = spec.fmt

    def trace(self, codes) -> F18Trace:
        s = self.spec
        fmt = self.fmt
        codes = np.asarray(codes, dtype=np.int64)
        n = self.norm.process(codes)
        e = self.expansion.process(n.out_theta)
        trig = e.out_terms.reshape(codes.size, -1)[:, : s.terms - 1]
        fixed = np.concatenate([n.code[:, None], trig], axis=1)
        terms = self.cvt.process(fixed).out_y
        w = np.asarray(s.weight_codes, dtype=np.int64)[None, :]
        products = fmt.mul_array(terms, np.broadcast_to(w, terms.shape))
        running = np.empty_like(products)
        acc = np.full(codes.size, s.start_code, dtype=np.int64)
        for i in range(s.terms):
            acc = fmt.add_array(acc, products[:, i])
            running[:, i] = acc
        out = running[:, -1]
        sat = n.out_sat | ((out & fmt.max_code) == fmt.max_code)
        return F18Trace(codes=codes, code=n.code, sat_in=n.out_sat, fixed_terms=fixed, terms=terms,
                        products=products, running=running, out=out, sat=sat)

    def process(self, codes) -> TopOut:
        t = self.trace(codes)
        return TopOut(out_data=t.out, out_sat=t.sat)

    def out_mm(self, codes) -> np.ndarray:
        return self.fmt.decode_array(self.process(codes).out_data)

    def all_codes(self) -> np.ndarray:
        return np.arange(self.spec.code_min, self.spec.code_max + 1, dtype=np.int64)

    def error_vs_float(self, codes=None) -> dict:
        """max |twin - float model| in mm over ``codes`` (default every code); no output LSB in float18."""
        codes = self.all_codes() if codes is None else np.asarray(codes, dtype=np.int64)
        e = float(np.max(np.abs(self.out_mm(codes) - self.spec.float_reference(codes))))
        return {"max_err_lsb": None, "max_err_mm": e, "codes": int(codes.size)}


__all__ = ["float18_options", "FRONT_END_OPTIONS", "F18Spec", "derive_f18_spec", "FlannF18Cvt", "FlannF18Top", "F18Trace"]
