"""PNG plots of the physics: simulated curve with each effect's contribution; a calibration."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..fileio import atomic_save_figure  # noqa: E402
from ..recordings import Recordings  # noqa: E402
from .fit import FitResult  # noqa: E402
from .lvdt import coupling_table, flux_profile, ideal_output_v  # noqa: E402
from .sensor import Sensor  # noqa: E402
from .simulate import contributions_v  # noqa: E402


def _save(fig, path: str | Path) -> None:
    try:
        atomic_save_figure(fig, path)
    finally:
        plt.close(fig)


def plot_simulation(s: Sensor, rec: Recordings, path: str | Path) -> None:
    """Top: recordings, ideal and simulated curves; bottom: each enabled effect's
    contribution (output with only that effect minus ideal) along the recorded run."""
    x = rec.displacement_mm
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True,
                                   gridspec_kw={"height_ratios": [3, 2]})
    xf = np.linspace(x.min(), x.max(), 600)
    ax1.plot(xf, ideal_output_v(s, xf), "k-", lw=1, label="ideal (no effects)")
    for sign, style, label in ((1, "C0.", "recorded, forward"), (-1, "C1.", "recorded, reverse")):
        m = rec.direction == sign if rec.direction is not None else np.ones(x.size, bool)
        if m.any():
            ax1.plot(x[m], rec.voltage_v[m], style, ms=3, label=label)
    ax1.set_ylabel("output (V)")
    ax1.set_title(f"{s.name}: simulated LVDT output")
    ax1.grid(alpha=0.3)
    ax1.legend(fontsize=8)
    contrib = contributions_v(s, x, rec.direction, rec.temperature_c, rec.time_s)
    if len(contrib) == 1:   # only "all", which is then the ideal: nothing to draw or name
        ax2.text(0.5, 0.5, "no effects enabled", ha="center", va="center",
                 transform=ax2.transAxes)
        contrib = {}
    # One line per pass in run order (not sorted): direction- and time-dependent effects
    # (backlash, drift) then show as separate forward/reverse branches.
    if rec.direction is not None:
        breaks = np.flatnonzero(np.diff(rec.direction) != 0) + 1
    else:
        breaks = np.array([], dtype=int)
    passes = np.split(np.arange(x.size), breaks)
    for i, (name, dv) in enumerate(contrib.items()):
        style = "k--" if name == "all" else f"C{i % 10}-"
        for k, idx in enumerate(passes):
            ax2.plot(x[idx], 1e3 * dv[idx], style, lw=1, label=name if k == 0 else None)
    ax2.set_xlabel("displacement (mm)")
    ax2.set_ylabel("contribution (mV)")
    ax2.grid(alpha=0.3)
    if contrib:
        ax2.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    _save(fig, path)


def plot_fit(rec: Recordings, fit: FitResult, path: str | Path) -> None:
    """Recordings with the calibrated ideal model, excluded points marked; residuals."""
    x, y = rec.displacement_mm, rec.voltage_v
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True,
                                   gridspec_kw={"height_ratios": [3, 2]})
    xf = np.linspace(x.min(), x.max(), 600)
    ax1.plot(xf, ideal_output_v(fit.sensor, xf), "k-", lw=1, label="calibrated ideal model")
    ax1.plot(x[fit.used], y[fit.used], "C0o", ms=4, label="recordings (fitted)")
    if (~fit.used).any():
        ax1.plot(x[~fit.used], y[~fit.used], "rx", ms=9, mew=2, label="excluded outlier")
    ax1.set_ylabel("output (V)")
    ax1.set_title(f"calibration to {Path(rec.source).name}: rms {fit.rms_v * 1e3:.1f} mV")
    ax1.grid(alpha=0.3)
    ax1.legend(fontsize=8)
    ax2.plot(x[fit.used], 1e3 * fit.residual_v[fit.used], "C0o-", ms=4, lw=0.8)
    if (~fit.used).any():
        ax2.plot(x[~fit.used], 1e3 * fit.residual_v[~fit.used], "rx", ms=9, mew=2)
    ax2.axhline(0, color="k", lw=0.8)
    ax2.set_xlabel("displacement (mm)")
    ax2.set_ylabel("data - model (mV)")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    _save(fig, path)


def plot_anatomy(s: Sensor, path: str | Path) -> None:
    """Top: axial flux along the bore for a few core positions, windings shaded.
    Bottom: mutual inductances and the ideal output versus core position."""

    a1 = s.primary_length_mm / 2
    a2 = a1 + s.secondary_gap_mm
    a3 = a2 + s.secondary_length_mm
    half = a3 + s.core_length_mm / 2 + s.stroke_mm
    z = np.linspace(-half, half, 1201)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 7))
    for lo, hi, label, colour in ((-a1, a1, "primary", "0.85"), (a2, a3, "S1", "#cde"),
                                  (-a3, -a2, "S2", "#ecd")):
        ax1.axvspan(lo, hi, color=colour, zorder=0)
        ax1.text((lo + hi) / 2, 0.02, label, ha="center", transform=ax1.get_xaxis_transform(),
                 fontsize=8)
    for i, p in enumerate((0.0, 0.5 * s.stroke_mm, s.stroke_mm)):
        phi = np.abs(flux_profile(s, p, z)) * 1e6
        ax1.plot(z, phi, f"C{i}-", lw=1.2, label=f"core at {p:g} mm")
        ax1.axvspan(p - s.core_length_mm / 2, p + s.core_length_mm / 2, ymin=0.97 - 0.03 * i,
                    ymax=1.0 - 0.03 * i, color=f"C{i}", alpha=0.8)
    ax1.set_xlabel("z along the axis (mm); bars at the top: core extent")
    ax1.set_ylabel("|axial flux| (uWb per A)")
    ax1.set_title(f"{s.name}: flux along the bore (transmission-line model)")
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)
    t = coupling_table(s, half_range_mm=a3 + s.core_length_mm / 2, n=401)
    ax2.axvspan(-s.stroke_mm, s.stroke_mm, color="0.92", zorder=0)
    ax2.plot(t.position_mm, np.abs(t.m1_h) * 1e3, "C0-", label="|M1| (mH)")
    ax2.plot(t.position_mm, np.abs(t.m2_h) * 1e3, "C1-", label="|M2| (mH)")
    ax2.set_xlabel("core position (mm)")
    ax2.set_ylabel("mutual inductance (mH)")
    ax2.grid(alpha=0.3)
    ax3 = ax2.twinx()
    ax3.plot(t.position_mm, ideal_output_v(s, t.position_mm), "k--", lw=1, label="output (V)")
    ax3.set_ylabel("ideal output (V); shaded: rated stroke")
    lines = ax2.get_legend_handles_labels()
    more = ax3.get_legend_handles_labels()
    ax2.legend(lines[0] + more[0], lines[1] + more[1], fontsize=8, loc="upper left")
    fig.tight_layout()
    _save(fig, path)
