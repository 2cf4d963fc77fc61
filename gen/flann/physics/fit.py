"""Calibrating the unknown construction of a sensor to recordings (ideal model, no effects).

Public API (stable):

* :data:`DEFAULT_FIT_PARAMS` -- what the seed paper does not give: primary length,
  secondary length, primary-secondary gap, demodulator gain.
* :func:`fit_sensor` (recordings, sensor=None, params=DEFAULT_FIT_PARAMS, bounds=None,
  outlier_sigma=8.0) -> :class:`FitResult`.

Method: a coarse grid over the geometric parameters (gain solved in closed form, it enters
linearly) picks starting points; :func:`scipy.optimize.least_squares` refines the best few
with a robust ``soft_l1`` loss; points whose residual exceeds ``outlier_sigma`` times a
robust (MAD) noise estimate are flagged and excluded (a single point far off a smooth curve
is a measurement glitch, not physics -- Table 1's +10 mm / 1.810 V); the inliers are refitted
with plain least squares, and parameter uncertainties come from the Jacobian at the
solution, ``cov = s^2 (J^T J)^-1`` with ``s^2 = SSR / (n - p)``.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ..errors import FlannError
from ..recordings import Recordings
from .lvdt import ideal_output_v
from .sensor import Sensor, default_sensor

DEFAULT_FIT_PARAMS = ("primary_length_mm", "secondary_length_mm", "secondary_gap_mm",
                      "demodulator_gain_ratio")

# Search ranges.  Lengths scale with the sensor being calibrated (a miniature LVDT is not
# searched in centimetres): (min(floor, 0.2 v), max(ceiling, 5 v)) around its current value v.
DEFAULT_BOUNDS: dict[str, tuple[float, float]] = {
    "primary_length_mm": (2.0, 150.0),
    "secondary_length_mm": (2.0, 150.0),
    "secondary_gap_mm": (0.0, 40.0),
    "core_permeability_ratio": (5.0, 1e4),
    "housing_inner_diameter_mm": (14.5, 200.0),
    "core_length_mm": (5.0, 300.0),
    "demodulator_gain_ratio": (-1e3, 1e3),
}
_SCALED = ("primary_length_mm", "secondary_length_mm", "secondary_gap_mm", "core_length_mm")
# Starting grid, as multiples of the sensor's current value (gain: solved in closed form).
_GRID: dict[str, tuple[float, ...]] = {
    "primary_length_mm": (0.3, 1.0, 3.0, 8.0),
    "secondary_length_mm": (0.5, 1.0, 2.0),
    "secondary_gap_mm": (0.2, 1.0, 3.0),
    "core_permeability_ratio": (0.2, 1.0, 5.0),
}


FINEST_WIRE_MM = 0.05   # AWG 44 magnet wire: the finest in practical use


def min_winding_length_mm(turns: float, sensor: Sensor) -> float:
    """Shortest winding that can hold ``turns`` in the radial build of the former, with the
    finest practical wire at 100 % fill: turns * d_w^2 / build."""
    build = (sensor.coil_outer_diameter_mm - sensor.coil_inner_diameter_mm) / 2
    return turns * FINEST_WIRE_MM ** 2 / build


def default_bounds(sensor: Sensor, name: str) -> tuple[float, float]:
    """Search range of a fittable field for this sensor (winding lengths: from the
    winding-space limit up to max(150 mm, 5 x the current value))."""
    lo, hi = DEFAULT_BOUNDS[name]
    if name in _SCALED:
        v = getattr(sensor, name)
        lo, hi = min(lo, 0.2 * v), max(hi, 5.0 * v)
    if name == "primary_length_mm":
        lo = min_winding_length_mm(sensor.primary_turns, sensor)
    if name == "secondary_length_mm":
        lo = min_winding_length_mm(sensor.secondary_turns, sensor)
    if name == "housing_inner_diameter_mm":
        lo = max(sensor.coil_outer_diameter_mm * 1.01, min(lo, sensor.housing_inner_diameter_mm))
    return lo, hi


@dataclass(frozen=True)
class FitResult:
    sensor: Sensor                       # the input sensor with the fitted values
    names: tuple[str, ...]
    values: dict[str, float]
    stderr: dict[str, float]             # 1-sigma, from the Jacobian (nan if singular)
    rms_v: float                         # over the points used
    residual_v: np.ndarray               # data - model, every point (excluded ones too)
    used: np.ndarray                     # bool mask of the points used
    excluded_rows: tuple[int, ...]       # 0-based data rows flagged as outliers
    noise_v: float                       # robust noise estimate of the first pass
    asymmetry_floor_v: float             # rms of the data's even part (nan: no mirrored pairs)
    bounds: dict[str, tuple[float, float]] = None  # search range of each fitted parameter

    def at_bound(self, name: str) -> bool:
        lo, hi = self.bounds[name]
        v = self.values[name]
        return abs(v - lo) <= 1e-6 * max(1.0, abs(lo)) or abs(v - hi) <= 1e-6 * max(1.0, abs(hi))

    def summary_lines(self) -> list[str]:
        lines = []
        for n in self.names:
            note = ""
            if self.bounds and self.at_bound(n):
                note = (f"  (at its search bound {self.bounds[n][0]:g}..{self.bounds[n][1]:g}: "
                        "the data push it there; the uncertainty is not meaningful)")
            lines.append(f"{n} = {self.values[n]:.4g} +- {self.stderr[n]:.2g}{note}")
        lines.append(f"rms residual = {self.rms_v * 1e3:.1f} mV over {int(self.used.sum())} points")
        if math.isfinite(self.asymmetry_floor_v):
            lines.append(f"even part of the data (y(x) + y(-x))/2: rms {self.asymmetry_floor_v * 1e3:.1f} mV "
                         "(asymmetry and noise: the floor for any symmetric sensor model)")
        return lines


def _model(base: Sensor, names, x):
    def f(theta):
        return ideal_output_v(base.replace(**dict(zip(names, map(float, theta)))), x)
    return f


def fit_sensor(rec: Recordings, sensor: Sensor | None = None,
               params: tuple[str, ...] = DEFAULT_FIT_PARAMS,
               bounds: dict[str, tuple[float, float]] | None = None,
               outlier_sigma: float = 8.0, starts: int = 4) -> FitResult:
    """Calibrate ``params`` of ``sensor`` (default: the paper's LVDT) to ``rec``."""
    base = (sensor or default_sensor()).without_effects()
    x = np.asarray(rec.displacement_mm, dtype=float)
    y = np.asarray(rec.voltage_v, dtype=float)
    names = tuple(params)
    unknown = [n for n in names if n not in DEFAULT_BOUNDS and (bounds is None or n not in bounds)]
    if unknown:
        raise FlannError(f"fit: no bounds known for {', '.join(unknown)} "
                         f"(fittable: {', '.join(DEFAULT_BOUNDS)})")
    if x.size < len(names) + 2:
        raise FlannError(f"{rec.source}: {x.size} points cannot calibrate {len(names)} parameters "
                         f"(need at least {len(names) + 2})")
    if np.ptp(x) == 0:
        raise FlannError(f"{rec.source}: no displacement variation")
    bnd = {n: default_bounds(base, n) for n in names if n in DEFAULT_BOUNDS}
    bnd.update(bounds or {})
    lo = np.array([bnd[n][0] for n in names])
    hi = np.array([bnd[n][1] for n in names])
    gain_i = names.index("demodulator_gain_ratio") if "demodulator_gain_ratio" in names else None

    starts_list = _starting_points(base, names, x, y, lo, hi, gain_i, starts)
    mask = np.ones(x.size, dtype=bool)
    best = _refine(base, names, x, y, mask, starts_list, lo, hi, loss="soft_l1",
                   f_scale=max(0.01 * float(np.ptp(y)), 1e-6))
    resid = y - _model(base, names, x)(best.x)
    noise = 1.4826 * float(np.median(np.abs(resid - np.median(resid))))
    noise = max(noise, 1e-6 * float(np.ptp(y)))
    mask = np.abs(resid) <= outlier_sigma * noise
    if mask.sum() < len(names) + 2:      # not a few outliers: keep everything
        mask[:] = True
    final = _refine(base, names, x, y, mask, [best.x], lo, hi, loss="linear", f_scale=1.0)
    theta = final.x
    fitted = base.replace(**dict(zip(names, map(float, theta))))
    resid = y - ideal_output_v(fitted, x)
    n_used = int(mask.sum())
    dof = max(n_used - len(names), 1)
    ssr = float(np.sum(resid[mask] ** 2))
    try:
        cov = np.linalg.inv(final.jac.T @ final.jac) * ssr / dof
        err = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        err = np.full(len(names), math.nan)
    return FitResult(
        sensor=fitted,
        names=names,
        values={n: float(v) for n, v in zip(names, theta)},
        stderr={n: float(e) for n, e in zip(names, err)},
        rms_v=math.sqrt(ssr / n_used),
        residual_v=resid,
        used=mask,
        excluded_rows=tuple(int(i) for i in np.flatnonzero(~mask)),
        noise_v=noise,
        asymmetry_floor_v=_even_part_rms(x, y, mask),
        bounds={n: (float(a), float(b)) for n, a, b in zip(names, lo, hi)},
    )


def _even_part_rms(x, y, mask) -> float:
    """rms over the used points of (y(x) + y(-x))/2, taking 0 for points without a used
    mirror point: the floor below which no odd (symmetric-sensor) model can go."""
    xu, yu = x[mask], y[mask]
    lookup = {}
    for xi, yi in zip(np.round(xu, 9), yu):
        lookup.setdefault(xi, []).append(yi)
    if not any(-xi in lookup and xi != 0 for xi in lookup):
        return math.nan
    even = np.zeros(xu.size)
    for i, (xi, yi) in enumerate(zip(np.round(xu, 9), yu)):
        mirror = lookup.get(-xi if xi != 0 else 0.0)
        if mirror is not None:
            even[i] = (yi + float(np.mean(mirror))) / 2 if xi != 0 else yi
    return float(np.sqrt(np.mean(even ** 2)))


def _starting_points(base, names, x, y, lo, hi, gain_i, keep):
    """Grid over the geometric parameters with the gain solved in closed form; the ``keep``
    best points (by median absolute residual, robust to outliers) start the refinement."""
    axes = []
    for i, n in enumerate(names):
        if i == gain_i:
            axes.append((None,))
        else:
            v0 = getattr(base, n)
            grid = tuple(f * v0 for f in _GRID.get(n, (1.0,))) if v0 > 0 else (lo[i], hi[i])
            axes.append(tuple(sorted({float(np.clip(v, lo[i], hi[i])) for v in grid})))
    scored = []
    for combo in itertools.product(*axes):
        theta = np.array([getattr(base, n) if v is None else v for n, v in zip(names, combo)],
                         dtype=float)
        if gain_i is not None:
            theta[gain_i] = 1.0
        try:
            f = _model(base, names, x)(theta)
        except FlannError:
            continue
        if gain_i is not None:
            denom = float(f @ f)
            if denom == 0:
                continue
            theta[gain_i] = float(np.clip((f @ y) / denom, lo[gain_i], hi[gain_i]))
            f = f * theta[gain_i]
        scored.append((float(np.median(np.abs(y - f))), theta))
    if not scored:
        raise FlannError("fit: no valid starting geometry inside the bounds")
    scored.sort(key=lambda t: t[0])
    return [t for _s, t in scored[:keep]]


def _refine(base, names, x, y, mask, starts, lo, hi, loss, f_scale):
    f = _model(base, names, x[mask])
    yy = y[mask]
    best = None
    for theta0 in starts:
        theta0 = np.clip(theta0, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
        try:
            r = least_squares(lambda th: f(th) - yy, theta0, bounds=(lo, hi), loss=loss,
                              f_scale=f_scale, x_scale="jac", max_nfev=400)
        except FlannError:
            continue
        if best is None or r.cost < best.cost:
            best = r
    if best is None:
        raise FlannError("fit: every start left the valid geometry")
    return best
