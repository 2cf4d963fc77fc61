"""Model-free look at recordings: checks, passes, noise, outliers, mismatch regions.

Nothing here knows the physics.  Functions take the displacement, voltage and (when
known) direction of every point and return plain numpy arrays or small dataclasses, so
the same code serves the ideal-simulation residuals and raw voltages alike.

Noise is estimated with the Gasser-Sargent-Buckley-Jennings pseudo-residuals: inside a
pass sorted by displacement, each point is compared with the straight line through its
two neighbours.  A smooth curve (the S-curve, or any physics left out of a model) has
almost no second difference, so what remains is the per-point scatter; a median
absolute deviation makes the estimate insensitive to the odd glitch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import RecordingsError
from ..recordings import OPTIONAL, REQUIRED, Recordings
from ..recordings.checks import row_directions, run_lengths

MIN_POINTS = 6
# |pseudo-residual| / sigma above which a lone point is a glitch (false alarm ~1e-6/point)
OUTLIER_Z = 5.0
# a running mean of w residuals is "off" when it exceeds REGION_Z * sigma / sqrt(w)
REGION_Z = 4.5
# flann diagnose takes means beyond this many readings: its time and memory grow faster than
# the points (900,000 took 4 GB and 3.5 minutes), and a few thousand already resolve every
# effect of the catalogue
MAX_POINTS = 5_000
# means a pass keeps when its readings alone are averaged, and positions a pass keeps when
# consecutive passes are averaged too (see reduce_points)
MIN_PASS_BINS = 20
PASS_POSITIONS = 200


@dataclass(frozen=True)
class Passes:
    """How the recording was taken: per-point direction (+1/-1, or None) and the runs.

    ``runs`` are index arrays in recording order, each a monotonic sweep of the core
    (one run holding everything, sorted by displacement, when the order carries no
    sweep information).  ``inferred`` says the direction came from the recording order.
    """

    direction: np.ndarray | None
    runs: tuple[np.ndarray, ...]
    inferred: bool
    ordered: bool


def check_inputs(x: np.ndarray, y: np.ndarray, direction: np.ndarray | None, source: str) -> None:
    """Refuse what cannot be diagnosed, in one line naming the problem."""
    n = x.size
    if n < MIN_POINTS:
        raise RecordingsError(f"{source}: {n} data rows; diagnose needs at least {MIN_POINTS}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise RecordingsError(f"{source}: displacement_mm/voltage_v contain non-finite values")
    x_flat = np.ptp(x) == 0
    y_flat = np.ptp(y) == 0
    if x_flat and y_flat:
        raise RecordingsError(
            f"{source}: all {n} points are identical (displacement {x[0]:g} mm, "
            f"voltage {y[0]:g} V): nothing to compare with a simulation")
    if x_flat:
        raise RecordingsError(
            f"{source}: column 'displacement_mm' does not vary (all {x[0]:g} mm): "
            "diagnose needs a sweep over the stroke")
    if y_flat:
        raise RecordingsError(
            f"{source}: column 'voltage_v' does not vary (all {y[0]:g} V) although the "
            "displacement does: no sensor signal recorded")
    if np.unique(x).size < 4:
        raise RecordingsError(
            f"{source}: only {np.unique(x).size} distinct displacements; diagnose needs "
            "at least 4 to calibrate a curve")
    if direction is not None:
        bad = ~np.isin(direction, (-1.0, 1.0))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise RecordingsError(
                f"{source}: row {i + 1}, column 'direction': {direction[i]:g} is not +1 or -1")


def find_passes(x: np.ndarray, direction: np.ndarray | None) -> Passes:
    """Split the recording (in row order) into monotonic sweeps.

    With a direction column the runs follow it.  Without one, the file order gives it
    (:func:`flann.recordings.checks.row_directions`); if that flips so often that runs are
    shorter than 4 points, the rows are taken as unordered (no direction information).
    """
    n = x.size
    if direction is not None:
        d = np.asarray(direction, dtype=float)
        cuts = np.flatnonzero(np.diff(d) != 0) + 1
        runs = tuple(np.split(np.arange(n), cuts))
        return Passes(direction=d, runs=runs, inferred=False, ordered=True)
    d = row_directions(x)
    if d is None:
        return Passes(None, (np.argsort(x, kind="stable"),), inferred=True, ordered=False)
    cuts = np.flatnonzero(np.diff(d) != 0) + 1
    runs = tuple(np.split(np.arange(n), cuts))
    if len(runs) > 1 and np.median(run_lengths(d)) < 4:
        return Passes(None, (np.argsort(x, kind="stable"),), inferred=True, ordered=False)
    return Passes(direction=d, runs=runs, inferred=True, ordered=True)


def reduce_points(rec: Recordings, max_points: int | None) -> tuple[Recordings, str]:
    """About ``max_points`` rows for the diagnosis, and one sentence saying how.

    Means over cells of (stretch of the recording, direction of travel, position).  While
    every pass keeps ``MIN_PASS_BINS`` means, a cell is ``k`` neighbouring positions of one
    pass (a mean never spans a turn: what ``flann calibrate`` does for its diagnosis).  With
    more passes than that (many repeated sweeps) a pass keeps up to ``PASS_POSITIONS``
    positions and a cell also takes the same positions of ``g`` consecutive passes of its
    direction: the curve keeps its shape and the recording its order in time (drift,
    temperature) in steps of ``g`` passes.  Rows in no order are sampled evenly instead.
    ``max_points`` None or 0, or no more rows: ``rec`` itself and "".
    """
    n = len(rec)
    if not max_points or n <= max_points:
        return rec, ""
    x = np.asarray(rec.displacement_mm, dtype=float)
    passes = find_passes(x, None if rec.direction is None else np.asarray(rec.direction, float))
    if not passes.ordered:
        idx = np.unique(np.linspace(0, n - 1, int(max_points)).round().astype(np.int64))
        return rec.subset(idx), (f"{idx.size} of the {n} readings, evenly sampled (the rows are "
                                 "in no order); row numbers below count those")
    factor = -(-n // int(max_points))
    run_id = np.empty(n, np.int64)
    for i, r in enumerate(passes.runs):
        run_id[r] = i
    length = int(np.median([r.size for r in passes.runs]))
    if len(passes.runs) * MIN_PASS_BINS <= max_points:
        k, g = factor, 1      # few passes: means of neighbouring readings of each
    else:
        # many short passes (repeated sweeps): the curve needs its positions more than the
        # time order needs every pass
        k = int(min(factor, max(1, length // PASS_POSITIONS)))
        g = -(-factor // k)
    dx = np.abs(np.diff(x))[run_id[1:] == run_id[:-1]]
    dx = dx[dx > 0]
    step = float(np.median(dx)) if dx.size else float(np.ptp(x)) / max(length, 1)
    direction = passes.direction
    dirs = np.unique(direction)
    # runs alternate direction: a block of g runs of each holds g passes each way
    block = run_id // (g * dirs.size)
    # positions on the actuator's grid fall in the middle of their bin (jitter stays in it)
    pos = np.floor(((x - x.min()) / step + 0.5) / k).astype(np.int64)
    side = (direction > 0).astype(np.int64)
    key = (block * 2 + side) * (int(pos.max()) + 1) + pos
    _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    count = np.bincount(inv)
    mean = {name: (None if getattr(rec, name) is None else
                   np.bincount(inv, weights=np.asarray(getattr(rec, name), float)) / count)
            for name in REQUIRED + OPTIONAL}
    # cells in recording order: block by block, each direction's pass in the order it came,
    # positions along it (so the passes read from the order are the recording's)
    d_cell = np.bincount(inv, weights=direction) / count
    b_cell = block[first]
    first_of_block = {}
    for b, i in zip(b_cell, first):
        first_of_block[b] = min(first_of_block.get(b, n), i)
    rank = np.array([0 if direction[first_of_block[b]] == d else 1
                     for b, d in zip(b_cell, d_cell)])
    order = np.lexsort((mean["displacement_mm"] * np.sign(d_cell), rank, b_cell))
    cols = {name: None if a is None else a[order] for name, a in mean.items()}
    small = Recordings(**cols, source=rec.source, sha256=rec.sha256, comments=rec.comments)
    cell = (f"up to {k} neighbouring positions of a pass, {k * step:.2g} mm" if k > 1
            else "each position of a pass")
    over = f" and of {g} consecutive passes of its direction" if g > 1 else ""
    return small, (f"{len(small)} means of the {n} readings ({cell}{over}): effects varying "
                   "over less than that are averaged out, noise figures are those of a mean "
                   "and row numbers below count the means")


def _sorted_groups(x: np.ndarray, passes: Passes, min_size: int = 3) -> list[np.ndarray]:
    groups = [r[np.argsort(x[r], kind="stable")] for r in passes.runs if r.size >= min_size]
    if not groups:
        groups = [np.argsort(x, kind="stable")]
    return groups


def pseudo_residuals(x: np.ndarray, r: np.ndarray, order: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Standardised GSJ pseudo-residuals along ``order`` (indices sorted by displacement).

    Returns (index, e/c): for each point, its residual minus the straight line through
    its two neighbours (one-sided extrapolation at the ends), divided by the factor that
    makes its variance equal to the per-point noise variance.
    """
    m = order.size
    if m < 3:
        return np.empty(0, dtype=int), np.empty(0)
    xs, rs = x[order], r[order]
    idx, val = [], []
    # interior: e_i = a r_{i-1} + b r_{i+1} - r_i
    x0, x1, x2 = xs[:-2], xs[1:-1], xs[2:]
    span = x2 - x0
    with np.errstate(invalid="ignore", divide="ignore"):
        a = np.where(span > 0, (x2 - x1) / span, 0.5)
        b = 1.0 - a
    e = a * rs[:-2] + b * rs[2:] - rs[1:-1]
    c = np.sqrt(a * a + b * b + 1.0)
    idx.append(order[1:-1])
    val.append(e / c)
    # ends: r_0 against the line through r_1, r_2 (extrapolated)
    for end, n1, n2 in ((0, 1, 2), (m - 1, m - 2, m - 3)):
        d12 = xs[n2] - xs[n1]
        t = (xs[end] - xs[n1]) / d12 if d12 != 0 else -1.0
        t = float(np.clip(t, -3.0, 3.0))
        pred = rs[n1] + t * (rs[n2] - rs[n1])
        cc = math.sqrt((1 - t) ** 2 + t ** 2 + 1.0)
        idx.append(np.array([order[end]]))
        val.append(np.array([(pred - rs[end]) / cc]))
    return np.concatenate(idx), np.concatenate(val)


def estimate_noise(x: np.ndarray, r: np.ndarray, passes: Passes,
                   exclude: np.ndarray | None = None) -> float:
    """Per-point noise (V, one sigma) of residuals ``r``, robust to smooth structure."""
    keep = np.ones(x.size, bool) if exclude is None else ~exclude
    vals = []
    for g in _sorted_groups(x, passes):
        g = g[keep[g]]
        _, v = pseudo_residuals(x, r, g)
        vals.append(v)
    v = np.concatenate(vals) if vals else np.empty(0)
    if v.size < 5:
        g = np.argsort(x, kind="stable")
        _, v = pseudo_residuals(x, r, g[keep[g]])
    if v.size == 0:
        return float(np.std(r))
    return float(1.4826 * np.median(np.abs(v)))


def find_outliers(x: np.ndarray, r: np.ndarray, passes: Passes, sigma: float,
                  z: float = OUTLIER_Z) -> np.ndarray:
    """Boolean mask of isolated glitches: one point far off the line through its neighbours.

    A glitch of size g at point i gives pseudo-residual g at i and about -g/2 at its
    neighbours, so only the local maximum of |e| is flagged; a smooth excursion (physics)
    has no second difference and is never flagged.
    """
    mask = np.zeros(x.size, bool)
    if sigma <= 0:
        return mask
    n = x.size
    # at small n be stricter than the normal tail would need, never looser than z
    zz = max(z, float(_norm_isf(0.001 / max(n, 1))))
    for g in _sorted_groups(x, passes):
        idx, v = pseudo_residuals(x, r, g)
        if idx.size == 0:
            continue
        pos = {int(i): k for k, i in enumerate(idx)}
        score = np.zeros(g.size)
        for k, i in enumerate(g):
            score[k] = abs(v[pos[int(i)]]) if int(i) in pos else 0.0
        for k in range(g.size):
            if score[k] <= zz * sigma:
                continue
            left = score[k - 1] if k > 0 else 0.0
            right = score[k + 1] if k + 1 < g.size else 0.0
            if score[k] >= left and score[k] >= right:
                mask[g[k]] = True
    return mask


def _norm_isf(p: float) -> float:
    # scipy.stats.norm.isf is -ndtri(p); importing scipy.stats costs each process ~1 s
    from scipy.special import ndtri
    return float(-ndtri(p))


def running_mean(v: np.ndarray, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Centred running mean of ``v`` over ``w`` points (shrinking at the ends) and the count."""
    w = max(1, int(w))
    h = w // 2
    c = np.concatenate([[0.0], np.cumsum(v)])
    i = np.arange(v.size)
    lo = np.clip(i - h, 0, v.size)
    hi = np.clip(i + h + 1, 0, v.size)
    cnt = hi - lo
    return (c[hi] - c[lo]) / cnt, cnt


def window_size(m: int) -> int:
    """Points averaged when locating a mismatch: about 1/12 of a pass, 3..101."""
    return int(np.clip(m // 12, 3, 101)) | 1


@dataclass(frozen=True)
class Span:
    lo: int        # first and last position in the sorted group
    hi: int
    peak: float    # signed running-mean residual of largest magnitude


def significant_spans(v: np.ndarray, sigma: float, w: int, z: float = REGION_Z) -> list[Span]:
    """Spans of a sorted residual sequence whose running mean exceeds the noise."""
    if v.size == 0 or sigma <= 0:
        return []
    m, cnt = running_mean(v, w)
    # also flag single points far beyond the noise (large effects over a short stretch)
    sig = (np.abs(m) > z * sigma / np.sqrt(cnt))
    sig &= cnt >= min(w, v.size)  # ignore the shrunk end windows unless large
    sig |= (np.abs(m) > z * sigma / np.sqrt(np.maximum(cnt, 1))) & (np.abs(v) > 3 * sigma)
    spans = []
    k = 0
    while k < v.size:
        if not sig[k]:
            k += 1
            continue
        j = k
        while j + 1 < v.size and sig[j + 1]:
            j += 1
        seg = m[k:j + 1]
        spans.append(Span(k, j, float(seg[np.argmax(np.abs(seg))])))
        k = j + 1
    # merge spans separated by less than a window
    merged: list[Span] = []
    for s in spans:
        if merged and s.lo - merged[-1].hi <= w:
            p = merged[-1]
            peak = p.peak if abs(p.peak) >= abs(s.peak) else s.peak
            merged[-1] = Span(p.lo, s.hi, peak)
        else:
            merged.append(s)
    # a span must hold at least half a window (or be a large single excursion)
    return [s for s in merged if (s.hi - s.lo + 1) >= max(2, w // 2) or abs(s.peak) > 6 * sigma]


def locate_regions(x: np.ndarray, r: np.ndarray, passes: Passes, sigma: float,
                   exclude: np.ndarray | None = None) -> list[dict]:
    """Displacement spans (per direction of travel) where residuals exceed the noise.

    Returns dicts with the JSON keys (from_mm, to_mm, direction, peak_residual_v); a
    span seen in both directions of travel is reported once with direction "both".
    """
    keep = np.ones(x.size, bool) if exclude is None else ~exclude
    groups: dict[str, np.ndarray] = {}
    if passes.direction is not None and passes.ordered:
        for sign, label in ((1.0, "+"), (-1.0, "-")):
            idx = np.flatnonzero((passes.direction == sign) & keep)
            if idx.size >= 3:
                groups[label] = idx[np.argsort(x[idx], kind="stable")]
    if not groups:
        idx = np.flatnonzero(keep)
        groups["both"] = idx[np.argsort(x[idx], kind="stable")]
    found: dict[str, list[tuple[float, float, float]]] = {}
    for label, g in groups.items():
        w = window_size(g.size)
        spans = significant_spans(r[g], sigma, w)
        found[label] = [(float(x[g[s.lo]]), float(x[g[s.hi]]), s.peak) for s in spans]
    regions = []
    if set(found) == {"+", "-"}:
        plus, minus = list(found["+"]), list(found["-"])
        used = set()
        for a in plus:
            best = None
            for j, b in enumerate(minus):
                if j in used:
                    continue
                overlap = min(a[1], b[1]) - max(a[0], b[0])
                shorter = max(min(a[1] - a[0], b[1] - b[0]), 1e-12)
                if overlap / shorter > 0.5:
                    best = j
                    break
            if best is None:
                regions.append(_region(a, "+"))
            else:
                used.add(best)
                b = minus[best]
                peak = a[2] if abs(a[2]) >= abs(b[2]) else b[2]
                regions.append(_region((min(a[0], b[0]), max(a[1], b[1]), peak), "both"))
        regions += [_region(b, "-") for j, b in enumerate(minus) if j not in used]
    else:
        for label, spans in found.items():
            regions += [_region(s, label) for s in spans]
    regions.sort(key=lambda d: (d["from_mm"], d["direction"]))
    return regions


def _region(s: tuple[float, float, float], direction: str) -> dict:
    return {"from_mm": s[0], "to_mm": s[1], "direction": direction, "peak_residual_v": s[2]}


def locate_time_spans(t: np.ndarray, r: np.ndarray, sigma: float,
                      exclude: np.ndarray | None = None) -> list[tuple[float, float, float]]:
    """Spans of recording time (or row number) where the residual, taken in time order, is off."""
    keep = np.ones(t.size, bool) if exclude is None else ~exclude
    idx = np.flatnonzero(keep)
    idx = idx[np.argsort(t[idx], kind="stable")]
    w = window_size(idx.size)
    return [(float(t[idx[s.lo]]), float(t[idx[s.hi]]), s.peak)
            for s in significant_spans(r[idx], sigma, w)]


# --------------------------------------------------------------------------- shape checks

def _smooth_sorted(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    order = np.argsort(x, kind="stable")
    xs, ys = x[order], y[order]
    w = max(1, min(len(xs) // 15, 15)) | 1
    if w > 1:
        # running median: robust to glitches, keeps plateaus flat
        h = w // 2
        pad = np.pad(ys, h, mode="edge")
        win = np.lib.stride_tricks.sliding_window_view(pad, w)
        ys = np.median(win, axis=1)
    return xs, ys


def detect_v_shape(x: np.ndarray, y: np.ndarray, sigma_raw: float) -> float | None:
    """Displacement of the tip when the output is rectified (a V through the null), else None.

    A signed LVDT output crosses zero once and rises (or falls) through the stroke; an
    amplitude-demodulated one never changes sign: it falls to a minimum near zero at the
    null and rises again on both sides.  Flagged when the smoothed curve has an interior
    minimum within 15 % of the span from zero, both ends are at least 30 % of the span
    above it, and (almost) no point lies below it by more than the noise.
    """
    xs, ys = _smooth_sorted(x, y)
    rng = float(np.ptp(ys)) or float(np.ptp(y))
    tol = max(6.0 * sigma_raw, 0.03 * rng)
    for sgn in (1.0, -1.0):
        v = sgn * ys
        k = int(np.argmin(v))
        if 0 < k < len(v) - 1:
            rise_l, rise_r = v[0] - v[k], v[-1] - v[k]
            if (min(rise_l, rise_r) > 0.3 * rng and abs(v[k]) < 0.15 * rng
                    and np.mean(sgn * y >= -tol) > 0.97):
                return float(xs[k])
    return None


# --------------------------------------------------------------------------- local noise

NOISE_METHOD = ("robust (MAD) scale of leave-one-out residuals from a local quadratic through "
                "the 6 nearest points of the same pass, on the residual of the baseline "
                "(calibrated simulation + smooth shape term); points on a rail excluded")


def local_fit_residuals(x: np.ndarray, r: np.ndarray, order: np.ndarray,
                        h: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Standardised leave-one-out residuals of a local quadratic along ``order``.

    For each point, a quadratic through its 2h nearest neighbours in the sorted group
    (the point itself left out) predicts it; the difference divided by
    sqrt(1 + leverage) has the per-point noise variance.  Curvature of the curve does not
    enter (the quadratic takes it) and neither does a plateau (it is fitted exactly).
    """
    m = order.size
    w = 2 * h
    if m < w + 1:
        return np.empty(0, dtype=int), np.empty(0)
    xs, rs = x[order], r[order]
    i = np.arange(m)
    start = np.clip(i - h, 0, m - w - 1)
    win = start[:, None] + np.arange(w + 1)[None, :]           # includes the point itself
    nb = win[win != i[:, None]].reshape(m, w)
    dx = xs[nb] - xs[:, None]
    scale = np.maximum(np.max(np.abs(dx), axis=1, keepdims=True), 1e-300)
    t = dx / scale
    X = np.stack([np.ones_like(t), t, t * t], axis=2)           # (m, w, 3)
    A = np.einsum("mwi,mwj->mij", X, X) + 1e-12 * np.eye(3)
    try:
        Ainv = np.linalg.inv(A)
    except np.linalg.LinAlgError:
        return np.empty(0, dtype=int), np.empty(0)
    coef = np.einsum("mij,mwj,mw->mi", Ainv, X, rs[nb])
    lev = Ainv[:, 0, 0]
    e = (rs - coef[:, 0]) / np.sqrt(1.0 + np.clip(lev, 0, None))
    ok = np.isfinite(e)
    return order[ok], e[ok]


def estimate_noise_local(x: np.ndarray, r: np.ndarray, passes: Passes,
                         exclude: np.ndarray | None = None,
                         n_regions: int = 3) -> tuple[float, list[dict]]:
    """Per-point noise (V) of residuals ``r`` and its value per region of the stroke.

    Pooled MAD scale of :func:`local_fit_residuals` in every pass; per region (equal
    thirds of the recorded displacement) the same scale of that region's points.
    Falls back to the pseudo-residual estimate on passes too short for a local fit.
    """
    keep = np.ones(x.size, bool) if exclude is None else ~exclude
    idx_all, val_all = [], []
    for g in _sorted_groups(x, passes):
        g = g[keep[g]]
        i, v = local_fit_residuals(x, r, g)
        idx_all.append(i)
        val_all.append(v)
    idx = np.concatenate(idx_all) if idx_all else np.empty(0, int)
    val = np.concatenate(val_all) if val_all else np.empty(0)
    if val.size < 5:
        return estimate_noise(x, r, passes, exclude=exclude), []
    sigma = float(1.4826 * np.median(np.abs(val)))
    lo, hi = float(np.min(x[keep])), float(np.max(x[keep]))
    edges = np.linspace(lo, hi, n_regions + 1)
    regions = []
    for k in range(n_regions):
        sel = (x[idx] >= edges[k]) & (x[idx] <= edges[k + 1])
        if sel.sum() >= 5:
            regions.append({"from_mm": float(edges[k]), "to_mm": float(edges[k + 1]),
                            "noise_v": float(1.4826 * np.median(np.abs(val[sel]))),
                            "points": int(sel.sum())})
    return sigma, regions


# --------------------------------------------------------------------------- rails

MIN_RAIL_POINTS = 4


def find_rails(x: np.ndarray, y: np.ndarray, passes: Passes) -> list[dict]:
    """Flat rails read off the data: runs of equal or nearly equal readings at an extreme.

    A rail is at least ``MIN_RAIL_POINTS`` readings (at >= 3 distinct displacements)
    within a tolerance of the highest (or lowest) reading, holding every reading beyond
    them towards that end of the travel, whose tolerance is 5 % of the noise of the
    other points.  A smooth peak with noise never gives that: its top readings scatter
    by the noise and lie among lower ones.  Returns dicts (side, level_v, stderr_v, n, mask).
    """
    rails = []
    rng = float(np.ptp(y))
    if rng <= 0:
        return rails
    sigma, _ = estimate_noise_local(x, y, passes)
    tol = max(0.05 * sigma, 1e-9 * rng)
    for side, sgn in (("high", 1.0), ("low", -1.0)):
        v = sgn * y
        top = float(np.max(v))
        on = v >= top - tol
        if on.sum() < MIN_RAIL_POINTS or np.unique(x[on]).size < 3:
            continue
        # the plateau must hold the end of the travel it sits at
        xr = x[on]
        if np.median(xr) >= np.median(x):
            beyond = x >= np.min(xr)
        else:
            beyond = x <= np.max(xr)
        if np.any(beyond & ~on):
            continue
        others = ~on
        if others.sum() >= 8:
            sig_o, _ = estimate_noise_local(x, y, passes, exclude=on)
            spread = float(np.std(y[on]))
            if spread > 0.2 * sig_o and sig_o > 0:
                continue
        level = float(np.mean(y[on]))
        se = float(np.std(y[on], ddof=1) / math.sqrt(on.sum()))
        rails.append({"side": side, "level_v": level, "stderr_v": se, "n": int(on.sum()),
                      "mask": on})
    return rails


def shared_reading(rec: Recordings) -> tuple[Recordings, tuple[str, ...]]:
    """(the recording with the readings every command leaves out as gross outliers left out,
    the lines train says of the same reading: :func:`flann.golden.reading.read_usable`); rails
    and a fold-back stay in, they are physics the diagnosis names.  The caller says the lines
    once the diagnosis has run (a refused recording is one line).  A recording the shared
    reading refuses is diagnosed whole."""
    from ..errors import FlannError
    from ..golden.reading import read_usable

    try:
        reading = read_usable(rec)
    except FlannError:
        return rec, ()
    outliers = [i for i, lo in enumerate(reading.left_out) if lo.why == "outlier"]
    if not outliers or rec.lines is None:
        return rec, reading.said
    gone = {reading.left_out[i].line for i in outliers}
    keep = np.array([rec.line_of(k) not in gone for k in range(len(rec))])
    return rec.subset(keep), reading.said
