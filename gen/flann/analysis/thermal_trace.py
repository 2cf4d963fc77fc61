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

from dataclasses import dataclass, field

import numpy as np

from ..errors import FlannError
from ..fileio import atomic_save_figure
from ..golden.thermal import corrected_voltage
from ..hardware.family.spec import clamp_codes
from ..hardware.family_thermal.spec import FamilyThermalSpec, order_models
from ..hardware.family_thermal.twin import FlannFamilyThermalTop
from ..hardware.thermal.spec import ThermalSpec
from ..hardware.thermal.twin import FlannThermalTop
from ..verify.temperatures import family_thermal_temperature_codes, thermal_temperature_codes

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


@dataclass
class ThermalTraceResult:
    n_points: int
    voltage_codes: int
    temperature_codes: list
    total: dict
    stages: dict
    orders: list
    dominant: dict
    identity_residual_mm: float
    output_lsb_mm: float
    volts: np.ndarray = field(repr=False, default=None)
    curves: dict = field(repr=False, default_factory=dict)
    hdl: dict | None = None
    fmt: str = "thermal"
    beyond_limits: int = 0   # samples left out: the float model beyond the output limits there
    stage_text: dict = field(repr=False, default_factory=lambda: dict(STAGE_TEXT))

    def to_dict(self) -> dict:
        d = {"format": self.fmt, "points": self.n_points, "voltage_codes": self.voltage_codes,
             "temperature_codes": self.temperature_codes, "total": self.total, "stages": self.stages,
             "orders": self.orders, "dominant": self.dominant,
             "identity_residual_mm": self.identity_residual_mm, "output_lsb_mm": self.output_lsb_mm,
             "beyond_limits": self.beyond_limits}
        if self.hdl is not None:
            d["hdl"] = self.hdl
        return d

    def text(self) -> str:
        t, q = self.total, self.output_lsb_mm
        lines = [f"flann trace ({self.fmt}): {self.voltage_codes} voltage codes x {len(self.temperature_codes)} "
                 f"temperature codes, |hardware - float| max {t['max_mm']:.3g} mm ({t['max_mm'] / q:.3f} LSB; "
                 f"at {t['peak_v']:+.4g} V, {t['peak_temperature_c']:g} degC), rms {t['rms_mm']:.3g} mm",
                 "", f"{'stage':<14} {'rms mm':>10} {'max mm':>10} {'bound mm':>10} {'share':>7}  what"]
        for s, d in self.stages.items():
            bound = "" if d["bound_mm"] is None else f"{d['bound_mm']:.3g}"
            lines.append(f"{s:<14} {d['rms_mm']:>10.3g} {d['max_mm']:>10.3g} {bound:>10} {d['share']:>6.1%}  "
                         f"{self.stage_text[s]}")
        lines += ["", "orders (each t_n^j x its datapath's error): " + "; ".join(
            f"order {o['order']} rms {o['rms_mm']:.3g} mm, max {o['max_mm']:.3g} mm" for o in self.orders)]
        d = self.dominant
        lines.append(f"dominant stage: {d['stage']} ({self.stage_text[d['stage']]}, {d['share']:.0%} of the error "
                     f"variance)")
        if self.beyond_limits:
            lines.append(f"{self.beyond_limits} samples not traced: pairs where the float model leaves the calibrated "
                         "displacements, which the output holds at its limits")
        if self.hdl is not None:
            h = self.hdl
            lines.append(f"HDL (GHDL, {h['top']}): {h['codes']} samples simulated, {h['mismatches']} mismatches "
                         "vs the twin")
        return "\n".join(lines)


def _rms(a) -> float:
    return float(np.sqrt(np.mean(np.square(a)))) if np.size(a) else 0.0


def _voltage_codes(spec: ThermalSpec) -> np.ndarray:
    codes = np.arange(spec.clamp_lo, spec.clamp_hi + 1, dtype=np.int64)
    if codes.size <= MAX_VOLTAGE_CODES:
        return codes
    return np.unique(np.linspace(spec.clamp_lo, spec.clamp_hi, MAX_VOLTAGE_CODES).round().astype(np.int64))


def trace_thermal(spec: ThermalSpec) -> ThermalTraceResult:
    """The stages (module docstring) over the calibrated voltage codes (at most
    ``MAX_VOLTAGE_CODES``) at the temperature codes ``flann sim`` runs, inside the calibrated ones."""
    m, q = spec.model, spec.output_lsb_mm
    temps = [t for t in thermal_temperature_codes(spec)[0] if spec.temp_lo <= t <= spec.temp_hi]
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
                              beyond_limits=int(np.count_nonzero(~inside)))


# the family design with temperature (flann_family_thermal_top): t_n is exact (tau - mid over a
# power of two), there is no input correction and no interpolation; so the error is
#   out - sum_j t^j f_j(v)  =  sum_j t^j (p_j - f_j(v))   orders   each order's family datapath
#                            + (acc - sum_j t^j p_j)      horner   the Horner roundings in t_n
#                            + (out - acc)                output   rounding to the output LSB, saturation
FAMILY_STAGE_TEXT = {
    "orders": "each order's family datapath (weights from its memory), x t_n^j",
    "horner": "Horner in t_n over the orders (roundings)",
    "output": "output rounding/saturation",
}


def trace_family_thermal(spec: FamilyThermalSpec) -> ThermalTraceResult:
    """The stages above over every voltage code at the temperature codes ``flann sim`` runs inside
    the calibrated ones, with the memories' initial image (the design's first member)."""
    m, q, t = spec.model, spec.output_lsb_mm, spec.temp
    temps = [c for c in family_thermal_temperature_codes(spec) if t.lo <= c <= t.hi]
    vc = np.arange(spec.code_min, spec.code_max + 1, dtype=np.int64)
    c = np.tile(vc, len(temps))
    tau = np.repeat(np.asarray(temps, dtype=np.int64), vc.size)
    tr = FlannFamilyThermalTop(spec).trace(c, tau)
    kq = q / 2.0 ** spec.inner_bits                       # the orders' LSB (mm)
    clo, chi = clamp_codes(m.voltage_range_v, spec.input_lsb_v, spec.code_min, spec.code_max)   # float_reference's
    v = np.clip(c, clo, chi) * spec.input_lsb_v
    t_n = tr.t_n.astype(float) / 2.0 ** t.shift
    f = [om.predict(v) for om in order_models(m)]
    x0 = spec.float_reference(c, tau)
    parts = [p.astype(float) * kq for p in tr.parts]
    x1 = sum(p * t_n ** j for j, p in enumerate(parts))
    acc = tr.acc.astype(float) * kq
    out = tr.out_data.astype(float) * q
    pieces = {"orders": x1 - x0, "horner": acc - x1, "output": out - acc}
    err = out - x0
    # the float model is sum_j t_n^j f_j with the design's exact t_n: what is left is rounding
    resid = float(max(np.max(np.abs(sum(pieces.values()) - err)),
                      np.max(np.abs(sum(fj * t_n ** j for j, fj in enumerate(f)) - x0))))
    var = {k: _rms(p) ** 2 for k, p in pieces.items()}
    vsum = sum(var.values()) or 1.0
    P = spec.orders
    bounds = {"orders": P * kq, "horner": (P - 1) / 2 * kq, "output": 0.5 * q}   # spec.py's error analysis
    stages = {k: {"rms_mm": _rms(p), "max_mm": float(np.max(np.abs(p))), "share": var[k] / vsum,
                  "bound_mm": bounds[k]} for k, p in pieces.items()}
    orders = [{"order": j, "rms_mm": _rms(t_n ** j * (p - fj)), "max_mm": float(np.max(np.abs(t_n ** j * (p - fj))))}
              for j, (p, fj) in enumerate(zip(parts, f))]
    dom = max(stages, key=lambda k: stages[k]["rms_mm"])
    k = int(np.argmax(np.abs(err)))
    total = {"max_mm": float(np.abs(err).max()), "rms_mm": _rms(err), "peak_v": float(c[k] * spec.input_lsb_v),
             "peak_temperature_c": float(tau[k] * t.lsb_c)}
    return ThermalTraceResult(n_points=int(c.size), voltage_codes=int(vc.size), temperature_codes=temps,
                              total=total, stages=stages, orders=orders,
                              dominant={"stage": dom, "share": stages[dom]["share"]},
                              identity_residual_mm=resid, output_lsb_mm=q, volts=c * spec.input_lsb_v,
                              curves={**pieces, "total": err}, fmt="family_thermal",
                              stage_text=dict(FAMILY_STAGE_TEXT))


def plot_thermal_trace(result: ThermalTraceResult, path, title: str = "") -> None:
    """Error and each stage's contribution vs input voltage, every traced temperature (PNG)."""
    # matplotlib is heavy and only needed for plots: imported when one is drawn
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    v = result.volts
    fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    ax0.plot(v, result.curves["total"], ".", ms=1, color="k")
    ax0.axhline(result.output_lsb_mm, color="tab:red", lw=0.6, ls="--", label="±1 output LSB")
    ax0.axhline(-result.output_lsb_mm, color="tab:red", lw=0.6, ls="--")
    ax0.set_ylabel("hardware − float (mm)")
    ax0.legend(loc="upper left", fontsize=8)
    ax0.set_title(title or f"flann trace ({result.fmt}): {len(result.temperature_codes)} temperature codes")
    ax0.grid(alpha=0.3)
    for s in sorted(result.stages, key=lambda s: -result.stages[s]["rms_mm"]):
        if result.stages[s]["max_mm"] > 0:
            ax1.plot(v, result.curves[s], ".", ms=1, label=f"{s} (rms {result.stages[s]['rms_mm']:.2g})")
    ax1.set_xlabel("input (V)")
    ax1.set_ylabel("contribution (mm)")
    ax1.legend(loc="upper left", fontsize=7, ncol=2, markerscale=8)
    ax1.grid(alpha=0.3)
    fig.tight_layout()
    atomic_save_figure(fig, path)
    plt.close(fig)


__all__ = ["ThermalTraceResult", "STAGES", "plot_thermal_trace", "trace_thermal", "trace_family_thermal"]
