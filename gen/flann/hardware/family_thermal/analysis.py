"""Stage-by-stage error of the family design with temperature against its float model (``flann
trace DIR``).

"""

from __future__ import annotations

import numpy as np

from ...analysis.plugin import Insight
from ...analysis.two_input_trace import ThermalTraceResult, rms as _rms
from ..family.spec import clamp_codes
from .spec import FamilyThermalSpec, order_models
from .twin import FlannFamilyThermalTop
from .verify import temperature_codes


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


def trace(spec: FamilyThermalSpec) -> ThermalTraceResult:
    """The stages above over every voltage code at the temperature codes ``flann sim`` runs inside
    the calibrated ones, with the memories' initial image (the design's first member)."""
    m, q, t = spec.model, spec.output_lsb_mm, spec.temp
    temps = [c for c in temperature_codes(spec) if t.lo <= c <= t.hi]
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


INSIGHT = Insight(trace=trace)

__all__ = ["INSIGHT", "trace"]
