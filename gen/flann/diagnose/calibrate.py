"""Calibrating the ideal simulation (no effects) to recordings: gain, origin and geometry.

* gain (``demodulator_gain_ratio``, its sign the output's sign convention) and origin (the
  displacement at which the core is centred) are cheap: the magnetics table is reused;
* the geometry (primary and secondary length, their gap, core length) changes the shape of
  the S-curve and costs a new magnetics table (~0.1 s) per trial, so it is fitted by a
  damped Gauss-Newton loop with forward-difference derivatives, gain and origin solved
  exactly for every geometry (variable projection), residuals Huber-weighted so a glitch
  does not bend the curve.  A handful of iterations (~5 tables each) converge from the
  paper's geometry for sensors of quite different construction.

The derivatives at the solution are returned as shape modes (see
:class:`flann.diagnose.model.ShapeModes`) for the effect fits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ..errors import FlannError, SensorError
from ..physics.lvdt import ideal_output_v
from .model import ShapeModes

GEOMETRY_FIELDS = ("primary_length_mm", "secondary_length_mm", "secondary_gap_mm",
                   "core_length_mm")
_STEP = {"primary_length_mm": 0.03, "secondary_length_mm": 0.03, "secondary_gap_mm": 0.03,
         "core_length_mm": 0.03}  # relative forward-difference steps
_BOUNDS = {"primary_length_mm": (1.0, 300.0), "secondary_length_mm": (1.0, 300.0),
           "secondary_gap_mm": (0.05, 100.0), "core_length_mm": (2.0, 600.0)}
MAX_ITER = 12


@dataclass
class Calibration:
    sensor: object               # geometry and gain calibrated, no effects
    gain: float
    origin_mm: float
    geometry: dict[str, float]   # fitted geometry fields (empty when known)
    geometry_stderr: dict[str, float]
    shape: ShapeModes | None
    resid: np.ndarray            # y - ideal (every point)
    tables: int                  # magnetics tables built (cost)
    scale: float = 1.0           # sensor mm per recorded displacement unit


def _huber_weights(r: np.ndarray, c: float = 2.5) -> np.ndarray:
    s = 1.4826 * float(np.median(np.abs(r - np.median(r))))
    if s <= 0:
        return np.ones_like(r)
    a = np.abs(r) / (c * s)
    return np.where(a <= 1, 1.0, 1.0 / np.maximum(a, 1e-12))


def _solve_gain_origin(sensor, x, y, w, gain0, origin0, origin_free, origin_range):
    """Weighted LS for gain and origin at fixed geometry (cheap: the table is cached)."""
    s1 = sensor.replace(demodulator_gain_ratio=1.0)
    sw = np.sqrt(w)

    def f(th):
        g = th[0]
        o = th[1] if origin_free else origin0
        return sw * (g * ideal_output_v(s1, x - o) - y)

    th0 = np.array([gain0, origin0] if origin_free else [gain0], dtype=float)
    r = least_squares(f, th0, method="lm", x_scale="jac", xtol=1e-12, ftol=1e-12,
                      max_nfev=200)
    if origin_free and not origin_range[0] <= r.x[1] <= origin_range[1]:
        r.x[1] = float(np.clip(r.x[1], *origin_range))
    g = float(r.x[0])
    o = float(r.x[1]) if origin_free else origin0
    return g, o, float(np.sum(r.fun ** 2))


def initial_origin(x: np.ndarray, y: np.ndarray, v_tip: float | None) -> float:
    """Null position guess: the V's tip, else where a line through the middle crosses zero."""
    if v_tip is not None:
        return v_tip
    order = np.argsort(x, kind="stable")
    xs, ys = x[order], y[order]
    sign = np.sign(ys)
    cross = np.flatnonzero(sign[:-1] * sign[1:] < 0)
    if cross.size:
        k = cross[np.argmin(np.abs(cross - xs.size / 2))]
        x0, x1, y0, y1 = xs[k], xs[k + 1], ys[k], ys[k + 1]
        return float(x0 - y0 * (x1 - x0) / (y1 - y0))
    # one side of the null only: extrapolate a line through the quarter nearest zero
    k = np.argsort(np.abs(ys))[:max(3, ys.size // 4)]
    if np.ptp(xs[k]) > 0:
        slope, icpt = np.polyfit(xs[k], ys[k], 1)
        if slope != 0:
            guess = -icpt / slope
            span = float(np.ptp(xs))
            return float(np.clip(guess, xs[0] - span, xs[-1] + span))
    return float(np.median(xs))


def calibrate(sensor, x: np.ndarray, y: np.ndarray, origin_known: bool, geometry_known: bool,
              origin0: float, progress=None) -> Calibration:
    """Fit gain, origin (unless known) and geometry (unless known) of the ideal output."""
    span = float(np.ptp(x))
    origin_range = (float(np.min(x)) - span, float(np.max(x)) + span)
    origin_free = not origin_known
    if origin_known:
        origin0 = 0.0
    s = sensor.replace(effects={})
    w = np.ones_like(y)
    f1 = ideal_output_v(s.replace(demodulator_gain_ratio=1.0), x - origin0)
    gain0 = float(f1 @ y / (f1 @ f1)) if f1 @ f1 > 0 else s.demodulator_gain_ratio
    gain, origin, _ = _solve_gain_origin(s, x, y, w, gain0, origin0, origin_free, origin_range)
    for _ in range(2):  # robust weights from the first fits
        r = y - ideal_output_v(s.replace(demodulator_gain_ratio=gain), x - origin)
        w = _huber_weights(r)
        gain, origin, cost = _solve_gain_origin(s, x, y, w, gain, origin, origin_free,
                                                origin_range)
    tables = 1
    scale = 1.0
    geometry: dict[str, float] = {}
    geo_err: dict[str, float] = {}
    shape = None
    if not geometry_known:
        fields = GEOMETRY_FIELDS
        g0 = np.array([getattr(s, f) for f in fields], dtype=float)
        solutions = []
        # Each start is (k, geometry): k = sensor mm per recorded unit (1 for mm; the grid
        # also tries the scales that map the recorded span onto the rated stroke, which
        # covers recordings in inches or other units).  Everything below works in the
        # scaled coordinate x * k; the origin is converted back at the end.
        for k, g_start in _grid_starts(s, x, y, origin, fields):
            trial = _with_geometry(s, fields, g_start)
            if trial is None:
                continue
            xk = x * k
            rng_k = (origin_range[0] * k, origin_range[1] * k)
            gn, on, _ = _solve_gain_origin(trial, xk, y, np.ones_like(y), gain, origin * k,
                                           origin_free, rng_k)
            out = _gauss_newton(trial, fields, xk, y, gn, on, origin_free, rng_k, progress)
            tables += out[4]
            solutions.append((k, out))
        k_best, best = _reproducible(solutions, x, y, g0)
        s, g, gain, origin_k, _tables, _cost = best
        scale = k_best
        origin = origin_k / scale
        # derivatives at the solution -> shape modes and geometry uncertainty
        base = s.replace(demodulator_gain_ratio=gain)
        u = (x - origin) * scale
        r = y - ideal_output_v(base, u)
        w = _huber_weights(r)
        lo_core, hi_core = float(np.min(u)) - 0.1 * span - 2, float(np.max(u)) + 0.1 * span + 2
        grid = np.linspace(lo_core, hi_core, 1201)
        f_grid = ideal_output_v(base, grid) / gain
        d_grid = []
        for j, name in enumerate(fields):
            d = _STEP[name] * g[j]
            trial = _with_geometry(base, fields, g + d * np.eye(len(fields))[j])
            tables += 1
            d_grid.append(np.zeros_like(grid) if trial is None
                          else (ideal_output_v(trial, grid) / gain - f_grid) / d)
        D = np.stack(d_grid)                       # (fields, grid) per unit gain
        dfdx = np.gradient(f_grid, grid)
        shape, J_geo = _modes(grid, f_grid, dfdx, D, u, origin_free, fields)
        geometry = {f: float(v) for f, v in zip(fields, g)}
        geo_err = _geometry_stderr(J_geo, gain, f_grid, dfdx, grid, u, r, w, origin_free, fields)
    resid = y - ideal_output_v(s.replace(demodulator_gain_ratio=gain), (x - origin) * scale)
    return Calibration(sensor=s.replace(demodulator_gain_ratio=gain), gain=gain,
                       origin_mm=origin, geometry=geometry, geometry_stderr=geo_err,
                       shape=shape, resid=resid, tables=tables, scale=scale)


# two geometries fit alike when another recording of the same sensor may reverse which fits
# better: their squared-residual sums differ by less than this many standard errors of that
# difference over noise draws (one-sided 99 %, sqrt 2 for two recordings)
SAME_FIT_Z = 2.33 * math.sqrt(2.0)


def _noise_sd(x: np.ndarray, y: np.ndarray) -> float:
    """The readings' noise from second differences along the displacement (the curve's slope
    and bend cancel; the fit's misfit, which can be far larger, does not enter)."""
    order = np.argsort(x, kind="stable")
    dd = np.diff(y[order], 2)
    return math.sqrt(float(np.median(dd * dd)) / (6.0 * 0.455)) if dd.size else 0.0


def _reproducible(solutions, x, y, g0):
    """The (scale, Gauss-Newton result) to keep: the lowest cost, or, among the solutions that
    fit as well as it on another recording of the same sensor, the one nearest the sensor's
    own geometry.  Two geometries far apart can draw the same curve (a short primary with a
    wide gap and a long one with a narrow gap); left to the noise, identical sensors landed
    on either, and an imbalance fitted on top moved by twice its stated uncertainty.

    The difference of two fits' squared-residual sums moves between recordings by
    2 sigma |f_a - f_b| (sigma the readings' noise, f the fitted curves): the misfit both
    share is the same on every recording (a sensor whose halves differ in gain by 1 % is
    misfit by 50 mV with 0.5 mV noise: its geometries are told apart)."""
    if not solutions:
        raise FlannError("calibration: no geometry could be simulated")
    best = min(solutions, key=lambda t: t[1][-1])
    resid = {}
    for k, out in solutions:
        s, _g, gain, origin_k, _t, _c = out
        resid[id(out)] = y - ideal_output_v(s.replace(demodulator_gain_ratio=gain), x * k - origin_k)
    r0 = resid[id(best[1])]
    sigma = _noise_sd(x, y)
    alike = []
    for k, out in solutions:
        r = resid[id(out)]
        se = 2.0 * sigma * float(np.linalg.norm(r - r0))
        if out is best[1] or float(r @ r - r0 @ r0) <= SAME_FIT_Z * se:
            alike.append((k, out))

    def distance(t):
        k, out = t
        return float(np.sum(np.log(out[1] / g0) ** 2) + math.log(k) ** 2)

    return min(alike, key=distance)


def _grid_starts(s, x, y, origin, fields, keep: int = 2):
    """Coarse grid over the geometry (each length varied around the sensor's, all of them
    or the displacement scaled when the recorded span is far from the rated stroke), gain
    solved in closed form on <= 200 points; the ``keep`` best (k, geometry) start the
    Gauss-Newton refinement, together with the sensor's own geometry at k = 1."""
    order = np.argsort(x, kind="stable")
    sub = order[np.unique(np.linspace(0, x.size - 1, min(x.size, 200)).astype(int))]
    xs, ys = x[sub] - origin, y[sub]
    g0 = np.array([getattr(s, f) for f in fields], dtype=float)
    half = max(float(np.max(np.abs(xs))), 1e-12)
    k_span = max(s.stroke_mm, 1e-3) / half     # maps the recorded half-span onto the stroke
    factors = {"primary_length_mm": (0.5, 1.0, 3.0, 8.0), "secondary_length_mm": (0.6, 1.0, 1.6),
               "secondary_gap_mm": (0.3, 1.0, 2.5), "core_length_mm": (0.8, 1.0, 1.25)}
    scored = []
    s1 = s.replace(demodulator_gain_ratio=1.0)
    # (k, length factor): the recorded span is either a sensor of another size in mm
    # (lengths scaled) or the paper-sized sensor recorded in other units (x scaled)
    options = [(1.0, f / k_span) for f in (0.7, 1.0, 1.5)]
    if not 0.5 < k_span < 2.0:
        options += [(k_span * f, 1.0) for f in (0.7, 1.0, 1.5)]
    for k, lf in options:
        for fp in factors["primary_length_mm"]:
            for fs in factors["secondary_length_mm"]:
                for fg in factors["secondary_gap_mm"]:
                    for fc in factors["core_length_mm"]:
                        g = g0 * lf * np.array([fp, fs, fg, fc])
                        trial = _with_geometry(s1, fields, g)
                        if trial is None:
                            continue
                        f = ideal_output_v(trial, xs * k)
                        den = float(f @ f)
                        if den <= 0:
                            continue
                        r = ys - f * float(f @ ys) / den
                        scored.append((float(r @ r), k, tuple(g)))
    scored.sort(key=lambda t: t[0])
    starts = [(k, np.array(g)) for _c, k, g in scored[:keep]]
    return [(1.0, g0)] + starts


def _gauss_newton(s, fields, x, y, gain, origin, origin_free, origin_range, progress):
    """Damped Gauss-Newton over the geometry fields (gain, origin solved at each trial)."""
    g = np.array([getattr(s, f) for f in fields], dtype=float)
    lam = 1e-2
    tables = 0
    rel = 1.0
    cost = math.inf
    for it in range(MAX_ITER):
        base = s.replace(demodulator_gain_ratio=gain)
        u = x - origin
        f0 = ideal_output_v(base, u)
        r = y - f0
        w = _huber_weights(r)
        cost = float(np.sum(w * r * r))
        h = 0.01
        dfdx = (ideal_output_v(base, u + h) - ideal_output_v(base, u - h)) / (2 * h)
        cols = [f0 / gain, -dfdx] if origin_free else [f0 / gain]
        steps = []
        for j, name in enumerate(fields):
            d = _STEP[name] * g[j]
            trial = _with_geometry(base, fields, g + d * np.eye(len(fields))[j])
            tables += 1
            if trial is None:
                cols.append(np.zeros_like(f0))
            else:
                cols.append((ideal_output_v(trial, u) - f0) / d)
            steps.append(d)
        J = np.stack(cols, 1)
        sw = np.sqrt(w)
        Jw, rw = J * sw[:, None], r * sw
        A = Jw.T @ Jw
        b = Jw.T @ rw
        improved = False
        for _attempt in range(4):
            M = A + lam * np.diag(np.diag(A) + 1e-30)
            try:
                delta = np.linalg.solve(M, b)
            except np.linalg.LinAlgError:
                lam *= 10
                continue
            dg = delta[-len(fields):]
            # keep each geometry step within 30 % of the current value
            scale = min(1.0, float(np.min(0.3 * g / np.maximum(np.abs(dg), 1e-30))))
            g_new = np.clip(g + scale * dg, [_BOUNDS[f][0] for f in fields],
                            [_BOUNDS[f][1] for f in fields])
            trial = _with_geometry(s, fields, g_new)
            if trial is None:
                lam *= 10
                continue
            tables += 1
            gn, on, _ = _solve_gain_origin(trial, x, y, w, gain, origin, origin_free,
                                           origin_range)
            rn = y - ideal_output_v(trial.replace(demodulator_gain_ratio=gn), x - on)
            cost_new = float(np.sum(w * rn * rn))
            if cost_new < cost:
                rel = (cost - cost_new) / max(cost, 1e-300)
                s, g, gain, origin = trial, g_new, gn, on
                lam = max(lam / 5, 1e-6)
                improved = True
                break
            lam *= 8
        if progress:
            progress(f"calibrating geometry: iteration {it + 1}, "
                     f"rms {math.sqrt(np.mean(r * r)) * 1e3:.3g} mV")
        if not improved or rel < 1e-5:
            break
    base = s.replace(demodulator_gain_ratio=gain)
    r = y - ideal_output_v(base, x - origin)
    return s, g, gain, origin, tables, float(np.sum(_huber_weights(r) * r * r))


def _with_geometry(s, fields, values):
    try:
        return s.replace(**{f: float(v) for f, v in zip(fields, values)})
    except (SensorError, FlannError):
        return None


def _modes(grid, f_grid, dfdx, D, u, origin_free, fields):
    """Geometry derivatives made orthogonal (over the data's core positions) to gain and
    origin, reduced to their significant singular directions."""
    at = lambda arr: np.interp(u, grid, arr)  # noqa: E731
    B = np.stack([at(f_grid)] + ([at(dfdx)] if origin_free else []), 1)
    Dd = np.stack([at(row) for row in D], 1)
    Q, _ = np.linalg.qr(B)
    Dd_perp = Dd - Q @ (Q.T @ Dd)
    U, sv, Vt = np.linalg.svd(Dd_perp, full_matrices=False)
    if sv.size == 0 or sv[0] <= 0:
        return None, Dd
    keep = sv > 1e-4 * sv[0]
    # few points cannot carry many free shapes: at most one mode per 8 points beyond 10
    keep &= np.arange(sv.size) < max(0, min(sv.size, (u.size - 10) // 8))
    if not keep.any():
        return None, Dd
    # modes on the grid: the same combinations of the raw derivatives, orthogonalised
    # against gain/origin with the data-point projection coefficients
    coef_B = np.linalg.lstsq(B, Dd, rcond=None)[0]           # (nb, fields)
    Bg = np.stack([f_grid] + ([dfdx] if origin_free else []), 0)  # (nb, grid)
    D_perp_grid = D - coef_B.T @ Bg                            # (fields, grid)
    V = Vt[keep].T / sv[keep]                                  # unit-norm modes on the data
    modes = (D_perp_grid.T @ V).T * math.sqrt(u.size)          # rms 1 over the data
    return ShapeModes(grid, modes, tuple(fields), dfdx), Dd


def _geometry_stderr(J_geo, gain, f_grid, dfdx, grid, u, r, w, origin_free, fields):
    at = lambda arr: np.interp(u, grid, arr)  # noqa: E731
    cols = [at(f_grid)] + ([-gain * at(dfdx)] if origin_free else []) + \
        [gain * J_geo[:, j] for j in range(J_geo.shape[1])]
    J = np.stack(cols, 1)
    n, k = J.shape
    if n <= k:
        return {f: math.nan for f in fields}
    s2 = float(np.sum(w * r * r) / max(np.sum(w) - k, 1))
    cov = np.linalg.pinv((J * w[:, None]).T @ J) * s2
    err = np.sqrt(np.clip(np.diag(cov), 0, None))[-len(fields):]
    return {f: float(e) for f, e in zip(fields, err)}
