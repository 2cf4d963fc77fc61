"""One design for a family of sensors, each compensated for temperature: x(v, T).

Model (per sensor, :func:`.build.fit_sensor`): a two-input FLANN without the input gain
correction, ``x = sum_j t_n^j f_j(v)`` with ``f_j`` a one-input FLANN (bias, linear and
trigonometric terms of one shared normalised voltage), written as a ``flann-thermal-model/1``
(``input_gain_t`` and ``input_offset_t_v`` empty).  ``t_n`` is chosen so the hardware forms it
exactly, with no multiply: ``t_n = (tau - mid) / 2^S`` for the temperature code ``tau``
clamped to the family's calibrated codes, ``mid`` the middle code and ``2^S`` the smallest
power of two holding half the calibrated span (so ``|t_n| <= 1``).  The temperature
normalisation is the design's (every sensor of the family is calibrated over one range);
what differs between sensors -- every order's weights, bias, input scale and clamp -- is in
the weight memories.

Hardware: order j is the family datapath (:mod:`flann.hardware.family`, unchanged: its
normaliser, expansion, serial shift-add multiplier and adder) with its own weight memory;
every order runs on the same sample, then the top combines them by Horner in t_n through one
serial shift-add multiplier (one bit of t_n per cycle) and rounds and saturates once.

Error analysis (|hardware - float| at the same clamped codes, output LSB q): every order is
sized by the family's own analysis for an output LSB q / 2^K (its error <= 1 of those LSBs,
weighted by |t_n|^j <= 1), each of the P - 1 Horner steps rounds once (1/2 of q / 2^K), t_n
is exact, and the final rounding is 1/2 q.  So the pre-rounding error is at most
(P + (P - 1)/2) q / 2^K <= q / 2 with K = ceil(log2(3P - 1)); the twin's measured figure is
``analysis.twin_vs_float_lsb``.  The default q is the family's own choice for the order-0
models (a quarter of the finest output step per input code, on the 1-2-5 series).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ...errors import SpecError
from ...golden.family import DEFAULT_RIDGE
from ...golden.model import FlannModel
from ...golden.thermal import ThermalModel
from ...numeric.fixed import FixedFormat, bits_needed, nearest_codes, signed_range
from ..delegate import delegated
from ..family.spec import DEFAULT_MARGIN, FamilySpec, clamp_codes, derive_family, member_spec

DEFAULT_ORDERS = 3          # a 3-temperature calibration determines 3 orders
MAX_ORDERS = 4


@dataclass(frozen=True)
class TempNorm:
    """The design's temperature code and its exact normalisation t_n = (clamp(tau) - mid) / 2^shift."""

    bits: int
    lsb_c: float
    lo: int          # calibrated codes: lower and higher codes clamp (out_sat)
    hi: int
    mid: int
    shift: int

    @property
    def offset_c(self) -> float:
        return self.mid * self.lsb_c

    @property
    def scale_c(self) -> float:
        return (1 << self.shift) * self.lsb_c

    @property
    def code_min(self) -> int:
        return signed_range(self.bits)[0]

    @property
    def code_max(self) -> int:
        return signed_range(self.bits)[1]

    @property
    def t_bits(self) -> int:
        """Width of the signed t_n code (|tau - mid| <= 2^shift)."""
        return self.shift + 2

    def t_code(self, tau) -> np.ndarray:
        t = np.clip(np.asarray(tau, dtype=np.int64), self.lo, self.hi)
        return t - self.mid

    def to_dict(self) -> dict:
        return {"bits": self.bits, "lsb_c": self.lsb_c, "clamp_codes": [self.lo, self.hi], "mid_code": self.mid,
                "shift": self.shift, "offset_c": self.offset_c, "scale_c": self.scale_c}

    @classmethod
    def from_dict(cls, d: dict) -> "TempNorm":
        try:
            return cls(int(d["bits"]), float(d["lsb_c"]), int(d["clamp_codes"][0]), int(d["clamp_codes"][1]),
                       int(d["mid_code"]), int(d["shift"]))
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise SpecError(f"manifest 'family_thermal.temperature' entry is incomplete ({exc})") from None


def temp_norm(temperature_range_c, bits: int, lsb_c: float) -> TempNorm:
    """The design's temperature normalisation for a calibrated range (degC)."""
    if not 2 <= int(bits) <= 16:
        raise SpecError(f"--temp-bits {bits}: must be 2..16")
    if not (isinstance(lsb_c, (int, float)) and lsb_c > 0 and math.isfinite(lsb_c)):
        raise SpecError(f"--temp-lsb-c {lsb_c!r}: must be a number > 0")
    t_lo, t_hi = sorted(float(t) for t in temperature_range_c)
    lo, hi = (int(c) for c in nearest_codes([t_lo, t_hi], lsb_c, -np.inf, np.inf))   # as the converter rounds
    cmin, cmax = signed_range(bits)
    if lo < cmin or hi > cmax:
        raise SpecError(f"calibrated temperatures {t_lo:g}..{t_hi:g} degC are codes {lo}..{hi}, outside the "
                        f"{bits}-bit temperature code ({cmin}..{cmax} x {lsb_c:g} degC): raise --temp-bits or "
                        "--temp-lsb-c")
    if hi - lo < 2:
        raise SpecError(f"calibrated temperatures {t_lo:g}..{t_hi:g} degC span {hi - lo} temperature code(s): "
                        "need recordings at several temperatures, or a finer --temp-lsb-c")
    mid = (lo + hi) // 2
    half = max(hi - mid, mid - lo)
    return TempNorm(int(bits), float(lsb_c), lo, hi, mid, max(1, (half - 1).bit_length()))


def order_models(model: ThermalModel, grid: int = 257) -> list[FlannModel]:
    """The one-input FLANN of each temperature order (one shared voltage normalisation)."""
    if model.input_gain_t or model.input_offset_t_v:
        raise SpecError("a two-input model with an input gain correction (flann train --temperature): the family "
                        "design takes the form x = sum_j t_n^j f_j(v) (train its members from recordings in "
                        "flann gen --family)")
    lo, hi = sorted(model.voltage_range_v)
    out = []
    for w, b in zip(model.weights, model.bias):
        m = FlannModel(weights=tuple(w), bias=float(b), input_offset_v=model.input_offset_v,
                       input_scale_v=model.input_scale_v, voltage_range_v=(lo, hi))
        y = m.predict(np.linspace(lo, hi, grid))
        out.append(replace(m, displacement_range_mm=(float(np.min(y)), float(np.max(y)))))
    return out


def inner_bits(orders: int) -> int:
    """K: orders at q / 2^K so (P + (P - 1)/2) q / 2^K <= q / 2."""
    return max(1, (3 * orders - 2).bit_length())


@dataclass(frozen=True)
class FamilyThermalSpec:
    fam: FamilySpec               # every order's datapath: one set of formats, output LSB q / 2^K
    model: ThermalModel = field(repr=False, compare=False)   # the memories' initial sensor
    orders: int                   # P: temperature orders
    temp: TempNorm
    inner_bits: int               # K: the orders' outputs are in q / 2^K
    output_lsb_mm: float          # q
    out_fmt: FixedFormat
    analysis: dict = field(default_factory=dict, compare=False)
    image: str = field(default="", compare=False)   # which sensor's weight image ``model`` is (flann eval)

    # -- codes: the orders' datapath's and the temperature normaliser's ----------------
    input_bits = delegated("fam.spec.input_bits")
    input_lsb_v = delegated("fam.spec.input_lsb_v")
    code_min = delegated("fam.spec.code_min")
    code_max = delegated("fam.spec.code_max")
    temp_bits = delegated("temp.bits")
    temp_lsb_c = delegated("temp.lsb_c")
    temp_code_min = delegated("temp.code_min")
    temp_code_max = delegated("temp.code_max")
    temp_lo = delegated("temp.lo")
    temp_hi = delegated("temp.hi")

    # -- shape --------------------------------------------------------------------------
    @property
    def sel_bits(self) -> int:
        """cfg_addr bits above an order's memory address: which order's memory is written."""
        return max(1, (self.orders - 1).bit_length())

    @property
    def cfg_addr_bits(self) -> int:
        return self.fam.addr_bits + self.sel_bits

    @property
    def image_words(self) -> int:
        """A sensor's image: every order's memory in turn (order j from j x mem_depth)."""
        return self.orders * self.fam.mem_depth

    order_bits = delegated("fam.spec.out_fmt.width")

    @property
    def acc_bits(self) -> int:
        """The Horner accumulator: |sum_j t_n^j f_j| <= P x the largest order output."""
        return self.order_bits + max(1, (self.orders - 1).bit_length()) + 1

    @property
    def step_cycles(self) -> int:
        """One Horner step: a bit of t_n per cycle, then one cycle to round and add."""
        return self.temp.t_bits + 1

    @property
    def latency_cycles(self) -> int:
        """Edges from the accepting edge to out_valid: the orders' datapath, the edge that takes
        their outputs, the Horner steps, the output register."""
        return self.fam.latency_cycles + 1 + (self.orders - 1) * self.step_cycles + 1

    @property
    def cycles_per_sample(self) -> int:
        return self.latency_cycles + 1

    def float_reference(self, codes, temp_codes) -> np.ndarray:
        """The float model (mm) at the codes as the hardware sees them (both clamped)."""
        m = self.model
        s = self.fam.spec
        clo, chi = clamp_codes(m.voltage_range_v, s.input_lsb_v, s.code_min, s.code_max)
        c = np.clip(np.asarray(codes, dtype=np.int64), clo, chi)
        t = np.clip(np.asarray(temp_codes, dtype=np.int64), self.temp.lo, self.temp.hi)
        c, t = np.broadcast_arrays(c, t)
        return m.predict(c * s.input_lsb_v, t * self.temp.lsb_c)

    def to_dict(self) -> dict:
        return {"orders": self.orders, "inner_bits": self.inner_bits, "output_lsb_mm": self.output_lsb_mm,
                "output_bits": self.out_fmt.width, "order_output_lsb_mm": self.fam.spec.output_lsb_mm,
                "order_output_bits": self.order_bits, "acc_bits": self.acc_bits, "t_bits": self.temp.t_bits,
                "temperature": self.temp.to_dict(), "cfg_addr_bits": self.cfg_addr_bits,
                "image_words": self.image_words, "latency_cycles": self.latency_cycles}


def check_member(spec: FamilyThermalSpec, model: ThermalModel) -> list:
    """Each order's fixed Spec of ``model`` under the design's formats; FitError (one line) if not."""
    if len(model.bias) != spec.orders:
        raise SpecError(f"the model has {len(model.bias)} temperature order(s), the design {spec.orders}")
    if not (math.isclose(model.temperature_offset_c, spec.temp.offset_c, abs_tol=1e-9)
            and math.isclose(model.temperature_scale_c, spec.temp.scale_c, rel_tol=1e-12)):
        raise SpecError(f"the model's temperature normalisation ({model.temperature_offset_c:g}, "
                        f"{model.temperature_scale_c:g} degC) is not the design's ({spec.temp.offset_c:g}, "
                        f"{spec.temp.scale_c:g} degC)")
    return [member_spec(spec.fam, m) for m in order_models(model)]


def derive_family_thermal(models: list[ThermalModel], temp: TempNorm, *, names=(), margin: float = DEFAULT_MARGIN,
                          output_lsb_mm: float | None = None, output_bits: int | None = None,
                          ridge: float = DEFAULT_RIDGE, **options) -> FamilyThermalSpec:
    """Size one design for every sensor (every order of every sensor is a member of the
    family the orders share); the first sensor initialises the memories."""
    if not models:
        raise SpecError("a family needs at least one sensor")
    P = len(models[0].bias)
    if not 1 <= P <= MAX_ORDERS or any(len(m.bias) != P for m in models):
        raise SpecError(f"every sensor needs the same number of temperature orders (1..{MAX_ORDERS})")
    per = [order_models(m) for m in models]
    if output_lsb_mm is None:   # the family's choice for the order-0 (mid-temperature) models
        output_lsb_mm = derive_family([p[0] for p in per], margin=margin, output_bits=None, **options,
                                      check_device=False).spec.output_lsb_mm
    K = inner_bits(P)
    members = [m for p in per for m in p]
    fam = derive_family(members, names=tuple(f"{n}.t{j}" for n in names for j in range(P)), margin=margin,
                        ridge=ridge, output_lsb_mm=output_lsb_mm / (1 << K), **options, check_device=False)
    s = fam.spec
    if output_bits is None:
        ymax = 0.0
        for m in models:
            lo, hi = sorted(m.voltage_range_v)
            vv, tt = np.meshgrid(np.linspace(lo, hi, 129), np.linspace(temp.lo, temp.hi, 9) * temp.lsb_c)
            ymax = max(ymax, float(np.max(np.abs(m.predict(vv.ravel(), tt.ravel())))))
        r = math.ceil(ymax * (1 + margin) / output_lsb_mm)
        output_bits = bits_needed(-r, r)
    out_fmt = FixedFormat(int(output_bits), int(output_bits))
    spec = FamilyThermalSpec(fam=fam, model=models[0], orders=P, temp=temp, inner_bits=K,
                             output_lsb_mm=float(output_lsb_mm), out_fmt=out_fmt)
    for m in models:
        check_member(spec, m)
    return replace(spec, analysis={"bound_lsb": (P + (P - 1) / 2) / (1 << K) + 0.5})


__all__ = ["FamilyThermalSpec", "TempNorm", "temp_norm", "order_models", "derive_family_thermal", "check_member",
           "inner_bits", "DEFAULT_ORDERS", "MAX_ORDERS"]
