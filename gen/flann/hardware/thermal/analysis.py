"""Stage-by-stage error of a two-input (thermal) design against its float model.

For every voltage code c at every traced temperature code tau (both inside the calibrated
codes), the twin's output error splits exactly (telescoping) into one contribution per stage
of ``flann_thermal_top``, with ``G(t, v') = sum_j t^j f_j(v')`` the float model as a function
of the normalised temperature and the corrected voltage::

    out - G(t, v'(t))         t, v'(t): the exact t_n and corrected voltage of the codes
      = G(t_h, v'(t_h)) - G(t, v'(t))             temperature    t_n rounded to FT bits
      + G(t_h, v'_h) - G(t_h, v'(t_h))            correction     gain/offset polynomials, c' rounded
      + sum_j t_h^j (lerp_j - f_j(v'_h))          interpolation  f_j linear between two grid nodes
      + sum_j t_h^j (p_j - lerp_j)                orders         each order's datapath at the nodes
      + (acc - sum_j t_h^j p_j)                   horner         the Horner roundings in t_n
      + (out - acc)                               output         rounding to the output LSB, saturation

where t_h, v'_h are the hardware's t_n and c' (in volts), lerp_j the float f_j interpolated
between the grid nodes the hardware reads, p_j the order datapaths' interpolated outputs and
acc the Horner sum before the output rounding.  Each stage is shown next to its bound from the
spec's error analysis (``ThermalSpec.analysis``).
"""

from __future__ import annotations

import numpy as np

from ...analysis.plugin import Insight
from ...analysis.two_input_trace import ThermalTraceResult, rms as _rms
from ...errors import FlannError
from ...golden.thermal import corrected_voltage
from .spec import ThermalSpec
from .twin import FlannThermalTop
from .verify import temperature_codes

STAGES = ("temperature", "correction", "interpolation", "orders", "horner", "output")
STAGE_TEXT = {
    "temperature": "t_n from the temperature code (rounded to FT bits)",
    "correction": "gain and offset in t_n, c' rounded below the grid",
    "interpolation": "linear interpolation between two grid codes",
    "orders": "each order's one-input datapath at the grid codes",
    "horner": "Horner in t_n over the orders (roundings)",
    "output": "output rounding/saturation",
}
# the spec's analysis bound (output LSBs) of each stage
BOUNDS = {"temperature": ("temperature_lsb",), "correction": ("fraction_lsb", "gain_rounding_lsb"),
          "interpolation": ("interpolation_lsb",), "orders": ("orders_lsb",), "horner": ("horner_lsb",)}
MAX_VOLTAGE_CODES = 1 << 16   # more codes (an ADC wider than 16 bits): evenly spaced, both ends


def _voltage_codes(spec: ThermalSpec) -> np.ndarray:
    codes = np.arange(spec.clamp_lo, spec.clamp_hi + 1, dtype=np.int64)
    if codes.size <= MAX_VOLTAGE_CODES:
        return codes
    return np.unique(np.linspace(spec.clamp_lo, spec.clamp_hi, MAX_VOLTAGE_CODES).round().astype(np.int64))


def trace(spec: ThermalSpec) -> ThermalTraceResult:
    """The stages (module docstring) over the calibrated voltage codes (at most
    ``MAX_VOLTAGE_CODES``) at the temperature codes ``flann sim`` runs, inside the calibrated ones."""
    m, q = spec.model, spec.output_lsb_mm
    temps = [t for t in temperature_codes(spec)[0] if spec.temp_lo <= t <= spec.temp_hi]
    if not temps:
        raise FlannError("trace: no temperature code inside the calibrated range")
    vc = _voltage_codes(spec)
    c = np.tile(vc, len(temps))
    tau = np.repeat(np.asarray(temps, dtype=np.int64), vc.size)
    # pairs the sensor never gave, where the float model leaves the calibrated displacements:
    # the output saturates there by design, not by an arithmetic stage (counted, not traced)
    lo, hi = spec.output_limits_mm
    x_float = spec.float_model(c, tau)
    inside = (x_float >= lo) & (x_float <= hi)
    c, tau = c[inside], tau[inside]
    tr = FlannThermalTop(spec).trace(c, tau)
    h = spec.input_lsb_v / 2.0 ** spec.fine_bits          # the order datapaths' grid (V)
    kq = q / 2.0 ** spec.inner_bits                       # the orders' LSB (mm)

    def f(v_c):                                           # f_j at corrected voltages
        return m.order_outputs((v_c - m.input_offset_v) / m.input_scale_v)

    def g(t, parts):
        return sum(p * t ** j for j, p in enumerate(parts))

    v = c * spec.input_lsb_v
    t_f = (tau * spec.temp_lsb_c - m.temperature_offset_c) / m.temperature_scale_c
    t_h = tr.t_n / 2.0 ** spec.t_frac_bits
    x0 = g(t_f, f(corrected_voltage(v, t_f, m.input_gain_t, m.input_offset_t_v)))
    x1 = g(t_h, f(corrected_voltage(v, t_h, m.input_gain_t, m.input_offset_t_v)))
    fine = tr.fine_code.astype(float) / 2.0 ** spec.interp_bits
    x2 = g(t_h, f(fine * h))
    node = np.floor(fine)
    frac = fine - node
    lerp = [a + (b - a) * frac for a, b in zip(f(node * h), f((node + 1) * h))]
    x3 = g(t_h, lerp)
    parts = [p.astype(float) * kq for p in tr.parts]
    x4 = g(t_h, parts)
    acc = tr.acc.astype(float) * kq
    out = tr.out_data.astype(float) * q
    pieces = {"temperature": x1 - x0, "correction": x2 - x1, "interpolation": x3 - x2,
              "orders": x4 - x3, "horner": acc - x4, "output": out - acc}
    err = out - x0
    resid = float(np.max(np.abs(sum(pieces.values()) - err)))
    var = {k: _rms(p) ** 2 for k, p in pieces.items()}
    vsum = sum(var.values()) or 1.0
    a = spec.analysis
    stages = {k: {"rms_mm": _rms(p), "max_mm": float(np.max(np.abs(p))), "share": var[k] / vsum,
                  "bound_mm": (sum(a[b] for b in BOUNDS[k]) * q if k in BOUNDS else 0.5 * q)}
              for k, p in pieces.items()}
    orders = [{"order": j, "rms_mm": _rms(t_h ** j * (p - lp)), "max_mm": float(np.max(np.abs(t_h ** j * (p - lp))))}
              for j, (p, lp) in enumerate(zip(parts, lerp))]
    dom = max(stages, key=lambda k: stages[k]["rms_mm"])
    k = int(np.argmax(np.abs(err)))
    total = {"max_mm": float(np.abs(err).max()), "rms_mm": _rms(err), "peak_v": float(v[k]),
             "peak_temperature_c": float(tau[k] * spec.temp_lsb_c)}
    curves = {s: p for s, p in pieces.items()}
    curves["total"] = err
    return ThermalTraceResult(n_points=int(c.size), voltage_codes=int(vc.size), temperature_codes=temps,
                              total=total, stages=stages, orders=orders,
                              dominant={"stage": dom, "share": stages[dom]["share"]},
                              identity_residual_mm=resid, output_lsb_mm=q, volts=v, curves=curves,
                              beyond_limits=int(np.count_nonzero(~inside)), stage_text=dict(STAGE_TEXT))


INSIGHT = Insight(trace=trace)

__all__ = ["INSIGHT", "trace", "STAGES"]
