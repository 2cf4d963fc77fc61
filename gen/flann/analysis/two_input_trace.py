"""What the trace of a design with temperature returns (:class:`ThermalTraceResult`) and draws:
each two-input datapath's folder computes its own stages (its ``analysis.py``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..fileio import atomic_save_figure


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
    stage_text: dict = field(repr=False, default_factory=dict)   # stage -> what it is, in words

    def plot(self, path, title: str = "") -> None:
        plot_thermal_trace(self, path, title)

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


def rms(a) -> float:
    return float(np.sqrt(np.mean(np.square(a)))) if np.size(a) else 0.0


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


__all__ = ["ThermalTraceResult", "plot_thermal_trace", "rms"]
