"""The certificate's error plot as inline SVG (drawn directly: a certificate costs milliseconds,
not the ~0.15-0.25 s of a matplotlib figure, which was a quarter of a sensor's budget).

Two panels sharing the displacement axis: the raw sensor's error (its least-squares line)
and the compensated error (the hardware twin) with the physical limit as +-dotted lines.
Every coordinate, tick and label is computed here; the template only places them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..textgen import template

TEMPLATE = "production/templates/error_plot.svg.j2"
WIDTH, PANEL_H = 720, 250          # px
LEFT, RIGHT, TOP, GAP, BOTTOM = 78, 16, 30, 48, 46
COLOURS = {"raw": "#c0392b", "hw": "#1f5fa8", "limit": "#222222", "tolerance": "#2e8b57"}


@dataclass(frozen=True)
class Series:
    points: str        # "x,y x,y ..." in px
    colour: str
    dash: str          # "" = solid
    width: float


@dataclass(frozen=True)
class Tick:
    pos: float         # px along its axis
    label: str


@dataclass(frozen=True)
class Panel:
    top: float
    height: float
    title: str
    ylabel: str
    series: tuple
    yticks: tuple
    zero: float | None  # px of y = 0 when inside the panel
    bands: tuple = ()   # shaded rectangles (x, y, width, height) in px: the tolerance band


@dataclass(frozen=True)
class Band:
    x: float
    y: float
    width: float
    height: float
    colour: str


def nice_ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    """About n round values covering [lo, hi] (1, 2, 5 x 10^k steps)."""
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        span = abs(lo) or 1.0
        lo, hi = lo - span / 2, hi + span / 2
    raw = (hi - lo) / max(1, n)
    mag = 10 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1, 2, 5, 10) if m * mag >= raw)
    first = math.floor(lo / step + 1e-9) * step
    ticks, t = [], first
    while t <= hi + step * 1e-6:
        ticks.append(round(t / step) * step)
        t += step
    if ticks[-1] < hi - step * 1e-6:
        ticks.append(ticks[-1] + step)
    return ticks


def _label(v: float, step: float) -> str:
    digits = max(0, -int(math.floor(math.log10(step))) if step > 0 else 0)
    return f"{v:.{digits}f}" if v != 0 else "0"


def _scale(lo: float, hi: float, p0: float, p1: float):
    k = (p1 - p0) / (hi - lo)
    return lambda v: p0 + (np.asarray(v, dtype=float) - lo) * k


# the data's extremes stay this share of the axis inside the frame: a last point at a tick's
# value drawn on the frame line is hidden by it (a certificate's worst error at its stroke's end)
PAD = 0.02


def _axis(lo: float, hi: float, p0: float, p1: float, n: int = 5):
    """(ticks, scale) of an axis over [lo, hi] drawn from px ``p0`` to ``p1``: round ticks, and
    the data kept PAD of the axis clear of the frame where a tick would put it on it."""
    ticks = nice_ticks(lo, hi, n)
    pad = PAD * (ticks[-1] - ticks[0])
    return ticks, _scale(min(ticks[0], lo - pad), max(ticks[-1], hi + pad), p0, p1)


def _points(px: np.ndarray, py: np.ndarray) -> str:
    return " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(px, py))


def _panel(top: float, title: str, ylabel: str, lines, sx, bands=()) -> Panel:
    """lines: (x, values, colour, dash, width); the y range covers them all (and 0); bands:
    (x_lo, x_hi, y_lo, y_hi, colour) in data units, shaded."""
    ys = np.concatenate([np.asarray(v, float) for _, v, *_ in lines] + [np.zeros(1)])
    yt, sy = _axis(float(np.min(ys)), float(np.max(ys)), top + PANEL_H, top)
    step = yt[1] - yt[0] if len(yt) > 1 else 1.0
    series = tuple(Series(_points(sx(x), sy(v)), c, d, w) for x, v, c, d, w in lines)
    z = float(sy(0.0))
    shaded = tuple(Band(float(sx(x0)), float(sy(y1)), float(sx(x1) - sx(x0)), float(sy(y0) - sy(y1)), c)
                   for x0, x1, y0, y1, c in bands)
    return Panel(top, PANEL_H, title, ylabel, series,
                 tuple(Tick(float(sy(t)), _label(t, step)) for t in yt),
                 z if yt[0] < 0 < yt[-1] else None, shaded)


def _tolerance(tolerance_mm, working_range_mm, xt, lines: list, legend: list) -> tuple:
    """The tolerance band over the working range (clipped to the axis): its edges appended to
    ``lines`` and its entry to ``legend``; returns the panel's shaded band (none without one)."""
    if tolerance_mm is None:
        return ()
    lo, hi = working_range_mm
    ends = np.array([max(lo, xt[0]), min(hi, xt[-1])])
    tol = np.full(2, float(tolerance_mm))
    lines += [(ends, tol, COLOURS["tolerance"], "8,3", 1.4), (ends, -tol, COLOURS["tolerance"], "8,3", 1.4)]
    legend.append((f"tolerance +-{tolerance_mm:.3g} mm ({lo:g}..{hi:g} mm)", COLOURS["tolerance"], "8,3"))
    return ((float(ends[0]), float(ends[1]), -tolerance_mm, tolerance_mm, COLOURS["tolerance"]),)


def error_plot_svg(chk: dict, sensor: str, tolerance_mm: float | None = None,
                   working_range_mm: tuple[float, float] | None = None) -> str:
    """Raw and compensated error vs displacement (mm), with the physical limit and, given a
    tolerance, the tolerance band (over the working range), as an <svg>."""
    x = np.asarray(chk["rec"].displacement_mm, dtype=float)
    o = np.argsort(x, kind="stable")
    x = x[o]
    xt, sx = _axis(float(x[0]), float(x[-1]), LEFT, WIDTH - RIGHT, 8)
    lim = np.asarray(chk["limit_mm"], float)[o]
    raw = _panel(TOP, f"{sensor}: raw sensor (error from its least-squares line)", "raw error (mm)",
                 [(x, chk["raw_err_mm"][o], COLOURS["raw"], "", 1.0)], sx)
    lines = [(x, chk["hw_err_mm"][o], COLOURS["hw"], "", 1.0), (x, lim, COLOURS["limit"], "3,3", 1.2),
             (x, -lim, COLOURS["limit"], "3,3", 1.2)]
    legend = [("compensated (hardware twin)", COLOURS["hw"], ""),
              ("physical limit (half an input LSB / slope)", COLOURS["limit"], "3,3")]
    bands = _tolerance(tolerance_mm, working_range_mm or (float(x[0]), float(x[-1])), xt, lines, legend)
    hw = _panel(TOP + PANEL_H + GAP, "compensated by the FPGA design (bit-true twin)", "compensated error (mm)",
                lines, sx, bands)
    xstep = xt[1] - xt[0] if len(xt) > 1 else 1.0
    height = TOP + 2 * PANEL_H + GAP + BOTTOM
    return template(TEMPLATE).render(
        width=WIDTH, height=height, left=LEFT, right=WIDTH - RIGHT, panels=(raw, hw),
        xticks=[Tick(float(sx(t)), _label(t, xstep)) for t in xt], xlabel="displacement (mm)",
        legend=legend,
        legend_y=TOP + PANEL_H + GAP + 14,
    )


# one colour per calibration temperature, cold to hot
TEMPERATURE_COLOURS = ("#1f5fa8", "#17becf", "#2ca02c", "#bcbd22", "#ff7f0e", "#d62728", "#8c564b")


def temperature_colour(k: int, n: int) -> str:
    """Cold blue to hot red over n temperatures."""
    if n <= 1:
        return TEMPERATURE_COLOURS[0]
    return TEMPERATURE_COLOURS[round(k * (len(TEMPERATURE_COLOURS) - 1) / (n - 1))]


def error_plot_temperatures_svg(chk: dict, sensor: str, tolerance_mm: float | None = None,
                                working_range_mm: tuple[float, float] | None = None) -> str:
    """Raw and compensated error vs displacement, one curve per calibration temperature (the
    legend names them), the tolerance band given one, as an <svg>."""
    x_all = np.asarray(chk["rec"].displacement_mm, dtype=float)
    labels, temps = chk["labels"], chk["temperatures_c"]
    xt, sx = _axis(float(np.min(x_all)), float(np.max(x_all)), LEFT, WIDTH - RIGHT, 8)
    raw_lines, hw_lines, legend = [], [], []
    for g, temp in enumerate(temps):
        rows = np.flatnonzero(labels == g)
        o = rows[np.argsort(x_all[rows], kind="stable")]
        colour = temperature_colour(g, len(temps))
        raw_lines.append((x_all[o], chk["raw_err_mm"][o], colour, "", 1.0))
        hw_lines.append((x_all[o], chk["hw_err_mm"][o], colour, "", 1.2))
        legend.append((f"{temp:g} degC", colour, ""))
    bands = _tolerance(tolerance_mm, working_range_mm or (float(np.min(x_all)), float(np.max(x_all))), xt,
                       hw_lines, legend)
    raw = _panel(TOP, f"{sensor}: raw sensor at each temperature (error from one least-squares line)",
                 "raw error (mm)", raw_lines, sx)
    hw = _panel(TOP + PANEL_H + GAP, "compensated by the FPGA design at each temperature (bit-true twin)",
                "compensated error (mm)", hw_lines, sx, bands)
    xstep = xt[1] - xt[0] if len(xt) > 1 else 1.0
    return template(TEMPLATE).render(
        width=WIDTH, height=TOP + 2 * PANEL_H + GAP + BOTTOM, left=LEFT, right=WIDTH - RIGHT, panels=(raw, hw),
        xticks=[Tick(float(sx(t)), _label(t, xstep)) for t in xt], xlabel="displacement (mm)",
        legend=legend, legend_y=TOP + PANEL_H + GAP + 14,
    )


__all__ = ["error_plot_svg", "error_plot_temperatures_svg", "nice_ticks", "temperature_colour"]
