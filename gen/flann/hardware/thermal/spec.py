"""Fixed-point spec of the two-input FLANN x(v, T), composed of the one-input datapath.

Datapath (one sample = an ADC code ``in_data`` and a temperature code ``in_temp``)::

    in_temp --clamp to the calibrated codes--> tau --x const + const--> t_n  (FT fraction bits)
    t_n --Horner (gain, offset polynomials)--> G(t_n) (FG bits), O(t_n) (fine codes)
    in_data --clamp--> c --(c G + O), one rounding--> c' = node + frac  (grid lsb/2^E, FR more bits)
    node, node + 1 --one-input datapath of order j (hardware/fixed, output LSB q / 2^K)--> a_j, b_j
    f_j = a_j + (b_j - a_j) frac          (linear interpolation between two grid codes)
    f_0 + t_n (f_1 + t_n f_2) --Horner, rounding at each multiply--> round to q,
        saturate at the calibrated displacement limits (out_lo, out_hi), out_sat there

Every one-input block is :mod:`flann.hardware.fixed` unchanged (its spec sized by its own
error budget for the order's FLANN on the fine grid); the temperature terms and the cross
products are multiplies by t_n, the same kind of multiply the serial multiplier does.

Error analysis (|hardware - float| <= 1 output LSB q for every voltage and temperature
code, the float model taken at the same clamped codes), pre-rounding share <= q/2:

* each order's datapath: its own bound (its error analysis, in its LSBs q/2^K) at each node,
  + 1/2 for the interpolation product's rounding, times |t_n|^j <= 1; K is sized for 1 LSB
  per order, then each order's quarter-wave table is made smaller (fewer block RAMs) where
  the whole bound stays within 1/2 LSB (``_smaller_tables``)
* the Horner roundings:   (orders - 1) q / 2^(K+1)
* linear interpolation over one grid step h = lsb/2^E: max|d2x/dv'2| h^2 / 8
* c' rounded to FR bits below the grid: max|dx/dv'| h 2^-(FR+1)
* the gain's roundings: max|dx/dv'| |v|max (orders) 2^-FG
* t_n's rounding:         max|dx/dt_n| 2^-(FT+1)

The interpolation is what lets the output LSB go below the sensor's steepest slope times
an ADC step: the one-input datapath takes at most 16-bit codes, so with a 16-bit ADC the
corrected voltage has no finer grid to be rounded to.

K, FR, FG and FT are the smallest that keep their share (``SHARE``), E = 16 - input_bits (the
one-input datapath's widest input; negative for a wider ADC, up to ``MAX_INPUT_BITS``, whose
low bits then reach the orders through the interpolation fraction: FR >= -E); the default output LSB q is, as for the one-input
design, a quarter of the larger of the output step per input code and the model's held-out
RMS error, on the 1-2-5 series, or coarser when the interpolation's curvature error needs it; ``ThermalSpec.analysis`` lists every bound.  The slopes are taken
numerically from the float model over the calibrated voltage and temperature ranges.
The VHDL is rendered by :mod:`.render` (``flann_thermal_top``).

Output limits.  The input clamp is one rectangle (calibrated voltages x calibrated
temperatures), but at each temperature the sensor covers only part of the voltage range: a
(voltage, temperature) pair the sensor never gives (the top of the voltage range at the
temperature whose span is smallest) evaluates the polynomial in t_n outside the calibration,
and the model extrapolates there (45 mm on a +-25 mm sensor).  So the output is saturated at
the calibrated displacement range (the model's ``displacement_range_mm``, the positions it
was trained on) widened by ``flann.golden.thermal.OUTPUT_MARGIN`` of its span on each side
(the fit's own error at the stroke's ends), rounded outward to the output LSB: ``out_lo``, ``out_hi``
(:func:`output_limit_codes`), and ``out_sat`` is raised there.  ``float_reference`` is the
float model saturated at the same limits (in mm: the codes x q), so |hardware - reference|
keeps its bound (a saturation is 1-Lipschitz) and a saturated output equals its reference.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ...errors import SpecError
from ...golden.model import FlannModel
from ...golden.thermal import ThermalModel, corrected_voltage
from ...numeric.fixed import FixedFormat, InputCodes, TempCodes, bits_needed, signed_range
from ..fixed.spec import Spec, derive_spec, nice_125

MAX_FINE_BITS = 16          # the one-input datapath's widest input
# the top's own input may be wider (an 18- or 20-bit ADC): its grid is then coarser than the
# code (E < 0) and c''s FR fraction bits (>= -E) carry the code's low bits into the interpolation
MAX_INPUT_BITS = 24
# Share of the 0.5-LSB pre-rounding budget per source (output LSBs).
SHARE = {"orders": 0.2, "horner": 0.05, "curvature": 0.1, "fraction": 0.05, "gain": 0.05,
         "temperature": 0.05}
def output_limit_codes(model: ThermalModel, q: float) -> tuple[int, int]:
    """(out_lo, out_hi): the model's output limits (:meth:`ThermalModel.output_limits_mm`) in
    output LSBs q, rounded outward."""
    lo, hi = model.output_limits_mm()
    return math.floor(lo / q + 1e-9), math.ceil(hi / q - 1e-9)


@dataclass(frozen=True)
class ThermalSpec(InputCodes, TempCodes):
    model: ThermalModel = field(repr=False, compare=False)
    input_bits: int
    input_lsb_v: float
    temp_bits: int
    temp_lsb_c: float
    clamp_lo: int                  # voltage codes of the calibrated range
    clamp_hi: int
    temp_lo: int                   # temperature codes of the calibrated range
    temp_hi: int
    fine_bits: int                 # E: the order datapaths' grid is lsb / 2^E
    interp_bits: int               # FR: bits of c' below that grid (interpolation fraction)
    t_frac_bits: int               # FT
    t_scale_int: int               # t_n = round((tau * t_scale_int + t_offset_int) / 2^t_shift)
    t_offset_int: int
    t_shift: int
    g_frac_bits: int               # FG
    gain_int: tuple[int, ...]      # 1, g1, g2 at FG bits
    offset_int: tuple[int, ...]    # 0, o1, o2 in grid codes at FR + FG fraction bits
    inner_bits: int                # K: order outputs in q / 2^K
    output_lsb_mm: float           # q
    out_fmt: FixedFormat
    out_lo: int                    # the output saturates at these codes (output_limit_codes)
    out_hi: int
    orders: tuple[Spec, ...] = field(repr=False)
    analysis: dict = field(default_factory=dict, compare=False)

    @property
    def horner_degree(self) -> int:
        """D: the gain and offset polynomials' degree in t_n."""
        return len(self.gain_int) - 1

    @property
    def order_latency(self) -> int:
        return max(o.latency_cycles for o in self.orders)

    @property
    def latency_cycles(self) -> int:
        """Clock edges from the accepting edge to out_valid (flann_thermal_top's sequence: t_n,
        the Horner start and D steps + 1, c', the node, then each order datapath run at the node
        and the next node (start, wait, ready again), the interpolation, the Horner in t_n over
        the orders (start, orders steps) and the output register)."""
        m, d, p = top_widths(self)["mul_b_bits"], self.horner_degree, len(self.orders)
        base = 1 + 1 + (self.horner_degree + 1) + 2 + 2 * (self.order_latency + 3) + 2 + p + 1
        # each product through the serial multiplier: load, one cycle per multiplier bit, use
        return base + (m + 1) + d * (2 * m + 2) + (m + 1) + (p * (m + 2) - 1) + (p - 1) * (m + 1)

    @property
    def cycles_per_sample(self) -> int:
        return self.latency_cycles + 1

    def to_dict(self) -> dict:
        """The spec as stamped in headers and manifest.json (every order's spec as its own)."""
        return {
            "number_format": "fixed", "input_bits": self.input_bits, "input_lsb_v": self.input_lsb_v,
            "temp_bits": self.temp_bits, "temp_lsb_c": self.temp_lsb_c,
            "clamp_codes": [self.clamp_lo, self.clamp_hi], "temp_clamp_codes": [self.temp_lo, self.temp_hi],
            "fine_bits": self.fine_bits, "interp_bits": self.interp_bits, "t_frac_bits": self.t_frac_bits,
            "t_scale_int": self.t_scale_int, "t_offset_int": self.t_offset_int, "t_shift": self.t_shift,
            "g_frac_bits": self.g_frac_bits, "gain_int": list(self.gain_int),
            "offset_int": list(self.offset_int), "inner_bits": self.inner_bits,
            "output_lsb_mm": self.output_lsb_mm, "output": self.out_fmt.describe(),
            "output_limit_codes": [self.out_lo, self.out_hi],
            "orders": [o.to_dict() for o in self.orders],
        }

    @property
    def output_limits_mm(self) -> tuple[float, float]:
        """The output's saturation limits (mm): out_lo and out_hi times the output LSB."""
        return self.out_lo * self.output_lsb_mm, self.out_hi * self.output_lsb_mm

    def float_model(self, codes, temp_codes) -> np.ndarray:
        """The float model (mm) at the clamped voltage and temperature codes, not saturated."""
        c = np.clip(np.asarray(codes, dtype=np.int64), self.clamp_lo, self.clamp_hi)
        t = np.clip(np.asarray(temp_codes, dtype=np.int64), self.temp_lo, self.temp_hi)
        return self.model.predict(c * self.input_lsb_v, t * self.temp_lsb_c)

    def float_reference(self, codes, temp_codes) -> np.ndarray:
        """The float model (mm) at the clamped voltage and temperature codes, saturated at the
        output limits as the hardware's output is (where it saturates, the reference is the limit)."""
        return np.clip(self.float_model(codes, temp_codes), *self.output_limits_mm)


def _order_model(model: ThermalModel, j: int, vrange) -> FlannModel:
    weights = model.weights[j] or (0.0,)
    return FlannModel(weights=weights, bias=model.bias[j], input_offset_v=model.input_offset_v,
                      input_scale_v=model.input_scale_v, voltage_range_v=vrange,
                      displacement_range_mm=model.displacement_range_mm)


def _grid(model: ThermalModel, n: int = 257):
    vlo, vhi = sorted(model.voltage_range_v)
    tlo, thi = sorted(model.temperature_range_c)
    v, t = np.meshgrid(np.linspace(vlo, vhi, n), np.linspace(tlo, thi, 33))
    return v.ravel(), t.ravel()


def _slopes(model: ThermalModel) -> tuple[float, float, float, tuple[float, float]]:
    """(max |dx/dv'| per V, max |d2x/dv'2| per V^2, max |dx/dt_n|, range of v') over the
    calibrated ranges."""
    v, t = _grid(model, 2049)
    v_n, t_n = model.normalise(v, t)
    v_c = v_n * model.input_scale_v + model.input_offset_v
    h = 1e-4 * model.input_scale_v

    def at(shift):
        parts = model.order_outputs((v_c + shift - model.input_offset_v) / model.input_scale_v)
        return sum(part * t_n ** j for j, part in enumerate(parts))

    mid, up, down = at(0.0), at(h), at(-h)
    dxdv = (up - down) / (2 * h)
    d2xdv2 = (up - 2 * mid + down) / h ** 2
    dt = 1e-6 * model.temperature_scale_c
    dxdt = (model.predict(v, t + dt) - model.predict(v, t - dt)) / (2 * dt) * model.temperature_scale_c
    return (float(np.max(np.abs(dxdv))), float(np.max(np.abs(d2xdv2))), float(np.max(np.abs(dxdt))),
            (float(v_c.min()), float(v_c.max())))


def _frac_bits_for(bound_per_unit: float, share: float, lo: int = 4, hi: int = 40) -> int:
    """Smallest F with bound_per_unit * 2^-F <= share."""
    for f in range(lo, hi + 1):
        if bound_per_unit * 2.0 ** -f <= share:
            return f
    raise SpecError(f"no width up to {hi} bits keeps this error within {share:g}")


MAX_LSB_RAISES = 12


def _size(model, q, slope_v, slope_t, h, vmax, lsb, tlsb, fine, input_bits, vrange):
    """Every width for output LSB q, and the order datapaths (SpecError if one cannot be built)."""
    p = model.orders
    fr = _frac_bits_for(slope_v * h * 0.5, SHARE["fraction"] * q, lo=max(0, -fine))
    fg = _frac_bits_for(slope_v * vmax * p, SHARE["gain"] * q)
    ft = _frac_bits_for(slope_t * 0.5, SHARE["temperature"] * q)
    k = max(_frac_bits_for(1.5 * p, SHARE["orders"], lo=0),
            _frac_bits_for(0.5 * (p - 1), SHARE["horner"], lo=0))
    # t_n = (tau * tlsb - t_off) / t_scale at FT bits, by one multiply-add and a shift
    shift = 24
    t_scale_int = round(tlsb / model.temperature_scale_c * 2.0 ** (ft + shift))
    t_offset_int = round(-model.temperature_offset_c / model.temperature_scale_c * 2.0 ** (ft + shift))
    gain_int = (1 << fg,) + tuple(round(g * 2.0 ** fg) for g in model.input_gain_t)
    offset_int = (0,) + tuple(round(o / h * 2.0 ** (fr + fg)) for o in model.input_offset_t_v)
    # the order datapaths clamp c' to the corrected voltages' range (vrange: a little wider
    # than the analysis grid saw, within the ADC's span), as the one-input design its code
    specs = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for j in range(p):
            specs.append(derive_spec(_order_model(model, j, vrange), input_bits=input_bits + fine,
                                     input_lsb_v=lsb / 2 ** fine, output_lsb_mm=q / 2 ** k))
    return fr, fg, ft, k, t_scale_int, t_offset_int, shift, gain_int, offset_int, tuple(specs)


def _orders_lsb(specs, k: int) -> float:
    """Each order's datapath bound (its own error analysis, in its LSBs q / 2^K) + 1/2 for the
    interpolation product's rounding, times |t_n|^j <= 1, in output LSBs."""
    return sum(o.analysis["bound_total_lsb"] + 0.5 for o in specs) / 2 ** k


TABLE_STEPS = 2   # at most this many address bits fewer than the order's own error budget picks


def _smaller_tables(specs, k: int, rest: float) -> tuple:
    """The order datapaths with fewer quarter-wave table words where the whole pre-rounding bound
    (``rest`` from the other sources) stays within 1/2 LSB and it saves block RAMs: every order
    has a table of its own, each sized by its own budget, where the orders share the output's."""
    specs = list(specs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for j, o in enumerate(list(specs)):
            for a in range(o.table_addr_bits - 1, o.table_addr_bits - 1 - TABLE_STEPS, -1):
                try:
                    cand = derive_spec(o.model, input_bits=o.input_bits, input_lsb_v=o.input_lsb_v,
                                       output_lsb_mm=o.output_lsb_mm, table_addr_bits=a)
                except SpecError:
                    break
                trial = specs[:j] + [cand] + specs[j + 1:]
                if (cand.analysis["estimate"]["brams"] >= specs[j].analysis["estimate"]["brams"]
                        or rest + _orders_lsb(trial, k) > 0.5):
                    break
                specs = trial
    return tuple(specs)


def derive_thermal_spec(model: ThermalModel, *, input_bits: int, input_lsb_v: float, temp_bits: int,
                        temp_lsb_c: float, output_lsb_mm: float | None = None) -> ThermalSpec:
    if not isinstance(model, ThermalModel):
        raise SpecError("model must be a two-input ThermalModel")
    if not (isinstance(input_bits, int) and 4 <= input_bits <= MAX_INPUT_BITS):
        raise SpecError(f"input_bits = {input_bits!r}: must be an integer in 4..{MAX_INPUT_BITS}")
    if not (isinstance(temp_bits, int) and 2 <= temp_bits <= 16):
        raise SpecError(f"--temp-bits {temp_bits!r}: must be an integer in 2..16")
    for name, val in (("input_lsb_v", input_lsb_v), ("--temp-lsb-c", temp_lsb_c)):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and val > 0):
            raise SpecError(f"{name} = {val!r}: must be a positive number")
    lsb, tlsb = float(input_lsb_v), float(temp_lsb_c)
    vlo, vhi = sorted(model.voltage_range_v)
    tlo_c, thi_c = sorted(model.temperature_range_c)
    cmin, cmax = signed_range(input_bits)
    clo, chi = max(cmin, math.ceil(vlo / lsb - 1e-9)), min(cmax, math.floor(vhi / lsb + 1e-9))
    tmin, tmax = signed_range(temp_bits)
    tlo, thi = math.ceil(tlo_c / tlsb - 1e-9), math.floor(thi_c / tlsb + 1e-9)
    if not (tmin <= tlo <= thi <= tmax):
        raise SpecError(f"--temp-bits {temp_bits} x --temp-lsb-c {tlsb:g} degC cover "
                        f"{tmin * tlsb:g}..{tmax * tlsb:g} degC, not the calibrated "
                        f"{tlo_c:g}..{thi_c:g} degC")
    if clo > chi:
        raise SpecError(f"input_lsb_v = {lsb:g} V: the trained range holds no input code")

    slope_v, curve_v, slope_t, (vc_lo, vc_hi) = _slopes(model)
    fine = MAX_FINE_BITS - input_bits
    h = lsb / 2 ** fine                        # the order datapaths' grid step (V)
    vmax = max(abs(vlo), abs(vhi))
    curvature_mm = curve_v * h * h / 8
    if output_lsb_mm is None:
        step = float(np.ptp(model.displacement_range_mm)) / max(1, chi - clo)
        acc = float(model.training.get("cv_rms_error_mm", 0.0) or 0.0)
        q = nice_125(max(step, acc) / 4, up=False)
        if curvature_mm > 0:   # a model without curvature (all weights zero) sets no floor
            q = max(q, nice_125(curvature_mm / SHARE["curvature"], up=True))
    else:
        q = output_lsb_mm
    if not (isinstance(q, (int, float)) and math.isfinite(q) and q > 0):
        raise SpecError(f"output_lsb_mm = {q!r}: must be a positive number of mm")
    q = float(q)
    if curvature_mm > SHARE["curvature"] * q * (1 + 1e-9):
        raise SpecError(f"output LSB {q:g} mm is finer than the {input_bits}-bit input allows "
                        f"(interpolating between codes alone is {curvature_mm / q:.3g} LSB): "
                        f"use an output LSB >= {nice_125(curvature_mm / SHARE['curvature'], up=True):g} mm")
    asked, why = q, ""
    for _ in range(MAX_LSB_RAISES):
        try:
            parts = _size(model, q, slope_v, slope_t, h, vmax, lsb, tlsb, fine, input_bits,
                          (max(vc_lo - 0.01 * (vc_hi - vc_lo), cmin * lsb),
                           min(vc_hi + 0.01 * (vc_hi - vc_lo), cmax * lsb)))
            break
        except SpecError as exc:
            if output_lsb_mm is not None:
                raise
            why = str(exc)
            q = nice_125(q * 1.5, up=True)
    else:
        raise SpecError(f"no output LSB from {asked:g} mm up builds the order datapaths ({why})")
    fr, fg, ft, k, t_scale_int, t_offset_int, shift, gain_int, offset_int, specs = parts
    p = model.orders
    ymax = float(np.max(np.abs(model.displacement_range_mm))) * 1.05
    out_lo, out_hi = output_limit_codes(model, q)
    out_bits = bits_needed(min(-math.ceil(ymax / q), out_lo), max(math.ceil(ymax / q), out_hi))
    analysis = {
        "slope_mm_per_v": slope_v, "slope_mm_per_t_n": slope_t,
        "curvature_mm_per_v2": curve_v,
        "orders_lsb": 1.5 * p / 2 ** k, "horner_lsb": (p - 1) / 2 ** (k + 1),
        "interpolation_lsb": curvature_mm / q, "fraction_lsb": slope_v * h * 0.5 * 2.0 ** -fr / q,
        "gain_rounding_lsb": slope_v * vmax * p * 2.0 ** -fg / q,
        "temperature_lsb": slope_t * 0.5 * 2.0 ** -ft / q,
    }
    analysis["orders_lsb"] = _orders_lsb(specs, k)
    rest = sum(v for key, v in analysis.items() if key.endswith("_lsb") and key != "orders_lsb")
    specs = _smaller_tables(specs, k, rest)
    analysis["orders_lsb"] = _orders_lsb(specs, k)
    analysis["pre_rounding_lsb"] = rest + analysis["orders_lsb"]
    analysis["output_limits_mm"] = [out_lo * q, out_hi * q]
    if q != asked:
        analysis["output_lsb_raised_from_mm"] = asked
        analysis["output_lsb_raised_because"] = why
    return ThermalSpec(model=model, input_bits=input_bits, input_lsb_v=lsb, temp_bits=temp_bits,
                       temp_lsb_c=tlsb, clamp_lo=clo, clamp_hi=chi, temp_lo=tlo, temp_hi=thi,
                       fine_bits=fine, interp_bits=fr, t_frac_bits=ft, t_scale_int=t_scale_int,
                       t_offset_int=t_offset_int, t_shift=shift, g_frac_bits=fg,
                       gain_int=gain_int, offset_int=offset_int, inner_bits=k, output_lsb_mm=q,
                       out_fmt=FixedFormat(out_bits, out_bits, signed=True), out_lo=out_lo, out_hi=out_hi,
                       orders=specs,
                       analysis=analysis)


def _sbits(bound: float) -> int:
    """Signed width holding +-bound."""
    b = int(math.ceil(abs(bound)))
    return bits_needed(-b, b)


def top_widths(spec: "ThermalSpec") -> dict:
    """Every register width of flann_thermal_top, from the integer ranges of the spec: each
    value's bound, with one bit of margin where a bound is a sum of bounds."""
    s = spec
    p, d = len(s.orders), s.horner_degree
    t_max = max(abs(s.temp_lo), abs(s.temp_hi)) * abs(s.t_scale_int) + abs(s.t_offset_int)
    tn_bits = _sbits((t_max >> s.t_shift) + 2)
    t_scale_bits = _sbits(s.t_scale_int)
    t_pre_bits = max(s.temp_bits + t_scale_bits, _sbits(s.t_offset_int)) + 1
    growth = (2.0 ** (tn_bits - 1)) / 2.0 ** s.t_frac_bits      # |t_n| bound in units of 1
    gain_bits = _sbits(sum(abs(g) * growth ** k for k, g in enumerate(s.gain_int)) + d + 1) + 1
    offset_bits = _sbits(sum(abs(o) * growth ** k for k, o in enumerate(s.offset_int)) + d + 1) + 1
    shift = s.fine_bits + s.interp_bits
    fine_pre_bits = s.input_bits + shift + gain_bits + 1
    fine_bound = (2 ** (s.input_bits - 1)) * 2 ** shift * 2 ** (gain_bits - 1) / 2 ** s.g_frac_bits \
        + 2 ** (offset_bits - 1) / 2 ** s.g_frac_bits + 2
    fine_bits_w = min(_sbits(fine_bound) + 1, fine_pre_bits)
    node_bits = s.orders[0].input_bits
    if any(o.input_bits != node_bits for o in s.orders):
        raise SpecError("the order datapaths must share one input width")
    node_w = max(fine_bits_w - s.interp_bits, node_bits) + 1
    frac_w = s.interp_bits + 1      # c' between its node and the next (interp_bits), signed
    ord_bits = max(o.out_fmt.width for o in s.orders) + 1
    part_bits = ord_bits + 2
    acc_bits = part_bits + p + 1 + max(0, math.ceil(math.log2(max(growth, 1.0))) * p)
    if s.out_fmt.width > acc_bits:
        raise SpecError(f"output width {s.out_fmt.width} exceeds the accumulator's {acc_bits} bits")
    mul_b_bits = max(s.temp_bits, tn_bits, gain_bits, frac_w)
    mul_a_bits = max(t_scale_bits, gain_bits, offset_bits, s.input_bits + shift, ord_bits + 1, acc_bits)
    # the serial multiplier's shifted operand and product: m_a shifts left once per bit of m_b
    mul_p_bits = mul_a_bits + mul_b_bits
    return dict(tn_bits=tn_bits, t_scale_bits=t_scale_bits, t_pre_bits=t_pre_bits, gain_bits=gain_bits,
                offset_bits=offset_bits, fine_shift=shift, fine_pre_bits=fine_pre_bits, fine_bits_w=fine_bits_w,
                node_bits=node_bits, node_w=node_w, frac_w=frac_w, ord_bits=ord_bits, part_bits=part_bits,
                acc_bits=acc_bits, mul_a_bits=mul_a_bits, mul_b_bits=mul_b_bits, mul_p_bits=mul_p_bits)


def corrected_codes_float(spec: ThermalSpec, codes, temp_codes) -> np.ndarray:
    """c' in grid codes without rounding (what the twin's integers approximate)."""
    m = spec.model
    t_n = (np.asarray(temp_codes) * spec.temp_lsb_c - m.temperature_offset_c) / m.temperature_scale_c
    v = corrected_voltage(np.asarray(codes) * spec.input_lsb_v, t_n, m.input_gain_t, m.input_offset_t_v)
    return v / spec.input_lsb_v * 2 ** spec.fine_bits


__all__ = ["ThermalSpec", "derive_thermal_spec", "corrected_codes_float", "top_widths", "output_limit_codes"]
