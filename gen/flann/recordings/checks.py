"""Checks before fitting an inverse model: the monotonic span, repeated displacements, noise."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace

import numpy as np

from ..errors import RecordingsError
from .csvio import Recordings

MIN_FIT_POINTS = 3
MIN_REPEAT_PAIRS = 8   # fewer repeats do not measure the noise
# repeats scattering more than this many times the point-to-point noise: the sweeps drifted apart
DRIFT_FACTOR = 2.0
# An LVDT conditioner's output (and any ADC input) is at most a few tens of volts: a larger
# number under a volts header is almost surely millivolts.
MAX_PLAUSIBLE_V = 60.0
# The fold-back threshold's floors: the noise estimate can come out low (readings on a
# converter grid whose noise is below a step: most differences are 0), so a fall must also
# exceed 0.2 % of the voltage span and three converter steps (noise below a step flips the
# reading by one code; the running median leaves less).  At 1 % of the span a 56 mV
# fold-back at the ends of an 11 V LVDT with 2 mV noise (26 sigma) was passed.
FOLDBACK_FLOOR = 0.002
STEPS_FLOOR = 3
# temperatures closer than this are one calibration temperature (a soak's sensor readings)
TEMPERATURE_RESOLUTION_C = 0.1


def temperature_groups(temperature_c) -> tuple[np.ndarray, np.ndarray]:
    """(distinct temperatures, label of each row): rows at the same temperature, to
    :data:`TEMPERATURE_RESOLUTION_C`."""
    t = np.round(np.asarray(temperature_c, dtype=float) / TEMPERATURE_RESOLUTION_C)
    levels, labels = np.unique(t, return_inverse=True)
    return levels * TEMPERATURE_RESOLUTION_C, labels


@dataclass(frozen=True)
class MonotonicSpan:
    """Result of :func:`monotonic_span`.

    ``mask`` selects (in file order) the rows of the monotonic span; it is all True when
    the voltage never folds back beyond the noise.  ``foldback`` tells whether it did,
    ``trimmable`` whether dropping rows at the ends removes it, ``message`` says where
    (empty when monotonic).  ``noise_v`` and ``threshold_v`` are the noise estimate and the
    fold-back threshold used.
    """

    mask: np.ndarray
    foldback: bool
    trimmable: bool
    message: str
    noise_v: float
    threshold_v: float


def estimate_noise_v(voltage_sorted: np.ndarray, order: int = 2) -> float:
    """Point-to-point noise (V, 1 sigma) of a curve sampled in displacement order.

    Robust: median absolute ``order``-th difference / (0.6745 * sqrt(C(2 order, order)));
    for white noise of standard deviation s the k-th difference has standard deviation
    s * sqrt(C(2k, k)) (6 for the second, 20 for the third).  A smooth curve sampled densely
    adds little; on coarse data (e.g. 13 points) the curvature inflates the second difference,
    which only makes the fold-back test more tolerant; the third cancels the curvature too
    (an LVDT at 0.5 mm steps puts as much into a second difference as 2 mV of noise).
    """
    v = np.asarray(voltage_sorted, dtype=float)
    if v.size < order + 1:
        return 0.0
    d = np.diff(v, order)
    return float(np.median(np.abs(d)) / (0.6745 * math.sqrt(math.comb(2 * order, order))))


def median_of_three(u: np.ndarray) -> np.ndarray:
    """Running median of three neighbours (Tukey's end rule: each end against the line through
    its two neighbours).  One isolated wrong reading cannot survive it; a curve that turns back
    over several readings does."""
    u = np.asarray(u, dtype=float)
    if u.size < 4:
        return u.copy()
    out = np.median(np.stack([u[:-2], u[1:-1], u[2:]]), axis=0)
    first = np.median([u[0], out[0], 3 * out[0] - 2 * out[1]])
    last = np.median([u[-1], out[-1], 3 * out[-1] - 2 * out[-2]])
    return np.concatenate([[first], out, [last]])


def _span_one(x: np.ndarray, v: np.ndarray, noise_v: float | None, k_sigma: float,
              floor_frac: float, step_v: float):
    """Fold-back test on one direction's readings sorted by displacement. Returns (keep per
    reading, kind, text, noise, thr).

    Judged on the mean reading of each position (repeated sweeps interleave their readings
    in displacement order, so differences of single readings would measure the slope as
    noise), and on their running median of three, so one glitch (the outlier screen's to
    find) is not taken for a curve without an inverse."""
    xu, inverse = np.unique(x, return_inverse=True)
    vu = np.bincount(inverse, weights=v) / np.bincount(inverse)
    keep, kind, text, noise, thr = _span_means(xu, vu, noise_v, k_sigma, floor_frac, step_v)
    return keep[inverse], kind, text, noise, thr


def _extreme_near(u: np.ndarray, i: int, sense: int) -> int:
    """The largest (``sense`` 1) or smallest (-1) of ``u[i - 1 : i + 2]``."""
    lo = max(i - 1, 0)
    window = sense * u[lo:i + 2]
    return lo + int(np.argmax(window))


def _span_means(x: np.ndarray, v: np.ndarray, noise_v: float | None, k_sigma: float,
                floor_frac: float, step_v: float):
    n = v.size
    slope = np.polyfit(x, v, 1)[0] if n >= 2 and np.ptp(x) > 0 else 1.0
    sign = 1.0 if slope >= 0 else -1.0
    # third differences where there are enough positions: a coarse sweep of a cubic curve puts
    # its curvature into the second (0.3x - 0.0004x^3 at 2 mm steps: a 0.36 V fall passed as noise)
    noise = (min(estimate_noise_v(v), estimate_noise_v(v, 3)) if n >= 8 else estimate_noise_v(v)) \
        if noise_v is None else float(noise_v)
    raw = sign * v
    u = median_of_three(raw)
    thr = max(k_sigma * noise, floor_frac * float(np.ptp(v)), STEPS_FLOOR * step_v)
    keep = np.ones(n, bool)
    if n < 3 or thr <= 0:
        return keep, None, "", noise, thr
    f_lo, f_hi = int(np.argmin(u)), int(np.argmax(u))
    if f_lo > f_hi:
        return keep, "interior", (f"voltage falls from {v[f_lo]:.6g} V at {x[f_lo]:g} mm back to "
                                  f"{v[f_hi]:.6g} V at {x[f_hi]:g} mm"), noise, thr
    inner = u[f_lo:f_hi + 1]
    drop = np.maximum.accumulate(inner) - inner
    if drop.max() > thr:
        j = int(np.argmax(drop)) + f_lo
        peak = int(np.argmax(u[f_lo:j + 1])) + f_lo
        return keep, "interior", (f"voltage turns back between {x[peak]:g} mm "
                                  f"({v[peak]:.6g} V) and {x[j]:g} mm ({v[j]:.6g} V)"), noise, thr
    # the median rounds a sharp turning point off by a reading: the readings beside it say where
    i_lo, i_hi = _extreme_near(raw, f_lo, -1), _extreme_near(raw, f_hi, 1)
    parts = []
    if f_hi < n - 1 and (u[f_hi] - u[f_hi + 1:].min()) > thr:
        j = int(np.argmin(u[f_hi + 1:])) + f_hi + 1
        parts.append(f"beyond {x[i_hi]:g} mm (turning point {v[i_hi]:.6g} V; {v[j]:.6g} V at {x[j]:g} mm)")
        keep[i_hi + 1:] = False
    if f_lo > 0 and (u[:f_lo].max() - u[f_lo]) > thr:
        j = int(np.argmax(u[:f_lo]))
        parts.append(f"below {x[i_lo]:g} mm (turning point {v[i_lo]:.6g} V; {v[j]:.6g} V at {x[j]:g} mm)")
        keep[:i_lo] = False
    if not parts:
        return np.ones(n, bool), None, "", noise, thr
    return keep, "ends", "voltage folds back " + " and ".join(parts), noise, thr


def monotonic_span(rec: Recordings, noise_v: float | None = None, k_sigma: float = 8.0,
                   floor_frac: float = FOLDBACK_FLOOR) -> MonotonicSpan:
    """Where the voltage folds back beyond the noise (no inverse exists), per direction.

    Within each direction (all rows when there is no ``direction`` column) the rows are
    ordered by displacement, the voltage is taken as the running median of three readings
    (:func:`median_of_three`) and oriented to rise.  A fold-back is a fall of more than
    ``threshold = max(k_sigma * noise, floor_frac * voltage span, 3 converter steps)`` below
    an earlier value; point-to-point wiggles smaller than that (noise on the flat ends) are
    not fold-backs.  A fold-back beyond the voltage extremes (the core leaving the coils)
    is *trimmable*: the span from the voltage minimum to its maximum is kept.  A fold-back
    inside that span is not.
    """
    groups = ([np.flatnonzero(rec.direction == d) for d in (1.0, -1.0)]
              if rec.direction is not None else [np.arange(len(rec))])
    mask = np.ones(len(rec), bool)
    step = converter_step(rec.voltage_v)
    messages, trimmable, noises, thrs = [], True, [], []
    for idx in groups:
        if idx.size == 0:
            continue
        order = idx[np.argsort(rec.displacement_mm[idx], kind="stable")]
        keep, kind, text, noise, thr = _span_one(rec.displacement_mm[order], rec.voltage_v[order],
                                                 noise_v, k_sigma, floor_frac, step)
        noises.append(noise)
        thrs.append(thr)
        if kind is None:
            continue
        where = "" if rec.direction is None else \
            f" (direction {int(rec.direction[idx[0]]):+d})"
        messages.append(f"{text}{where}")
        mask[order[~keep]] = False
        trimmable &= kind == "ends"
    noise = max(noises) if noises else 0.0
    thr = max(thrs) if thrs else 0.0
    msg = ""
    if messages:
        msg = (f"{rec.source}: {'; '.join(messages)}: no inverse exists there "
               f"(fold-back threshold {thr:.3g} V, noise estimate {noise:.3g} V)")
    if not trimmable:
        mask = np.ones(len(rec), bool)
    return MonotonicSpan(mask=mask, foldback=bool(messages), trimmable=bool(messages) and trimmable,
                         message=msg, noise_v=noise, threshold_v=thr)


def _pair(rec: Recordings, j: int, i: int) -> str:
    """'lines 3 and 4' (file lines) or 'rows 2 and 3' for recordings not read from a file."""
    a, b = rec.line_of(j), rec.line_of(i)
    return f"{a.split()[0]}s {a.split()[1]} and {b.split()[1]}"


def repeat_noise_v(displacement_mm, voltage_v, direction=None) -> tuple[float, int]:
    """(sigma V, pairs): the noise from readings repeated at one position and direction.

    Consecutive readings of one position (file order) differ by noise only: their difference
    has standard deviation sigma sqrt 2.  sigma is the RMS of the differences over sqrt 2,
    glitches (beyond 8 times the robust scale) left out; the robust scale alone (median |d|)
    is 0 on a converter's grid when most repeats read the same code.
    (0, pairs) with fewer than ``MIN_REPEAT_PAIRS`` pairs.
    """
    x = np.asarray(displacement_mm, float)
    v = np.asarray(voltage_v, float)
    d = np.zeros_like(x) if direction is None else np.asarray(direction, float)
    order = np.lexsort((np.arange(x.size), x, d))
    xs, ds, vs = x[order], d[order], v[order]
    same = (xs[1:] == xs[:-1]) & (ds[1:] == ds[:-1])
    diffs = (vs[1:] - vs[:-1])[same]
    if diffs.size < MIN_REPEAT_PAIRS:
        return 0.0, int(diffs.size)
    a = np.abs(diffs)
    nonzero = a[a > 0]
    scale = max(float(np.median(a)) / 0.6745, float(np.median(nonzero)) if nonzero.size else 0.0)
    kept = a[a <= 8.0 * scale]
    return float(np.sqrt(np.mean(kept ** 2) / 2.0)), int(diffs.size)


def check_duplicates(rec: Recordings, k_sigma: float = 8.0, floor_frac: float = 0.01,
                     inferred: bool = False, lone_glitches: bool = False) -> None:
    """Repeated readings (same position and direction: dwells, repeated sweeps) are data.

    A repeat is refused only when it differs from the median of the other readings there by
    more than ``max(k_sigma * noise, floor_frac * voltage span)``.  The noise comes from the
    repeats themselves (pairwise differences, robust) when there are at least
    ``MIN_REPEAT_PAIRS`` of them and they agree no worse than neighbouring positions do (the
    point-to-point estimate on the first reading of each position; sweeps further apart
    than that have drifted), else from that point-to-point estimate.  The message names the lines and the difference in noise units.

    ``lone_glitches``: the caller screens gross outliers (``flann train --terms auto``), so a
    repeat off by itself, where the other readings there agree with the neighbouring
    positions, is left to that screen (which names it and leaves it out) instead of refused.
    """
    direction = rec.direction if rec.direction is not None else np.zeros(len(rec))
    sigma, pairs = repeat_noise_v(rec.displacement_mm, rec.voltage_v, direction)
    keys = np.stack([direction, rec.displacement_mm], axis=1)
    first = np.sort(np.unique(keys, axis=0, return_index=True)[1])
    order = np.lexsort((rec.displacement_mm[first], direction[first]))
    p2p = estimate_noise_v(rec.voltage_v[first][order])
    if pairs >= MIN_REPEAT_PAIRS and sigma <= DRIFT_FACTOR * p2p:
        source = f"from {pairs} repeated readings"
    else:
        # sweeps that differ by more than the point-to-point noise drifted apart: that is not noise
        sigma, source = p2p, "point to point"
    tol = max(k_sigma * sigma, floor_frac * float(np.ptp(rec.voltage_v)))
    groups: dict[tuple[float, float], list[int]] = {}
    for i, (d, x) in enumerate(zip(direction, rec.displacement_mm)):
        groups.setdefault((float(d), float(x)), []).append(i)
    for (d, x), rows in groups.items():
        if len(rows) < 2:
            continue
        vv = rec.voltage_v[rows]
        if lone_glitches and _lone_glitches(rec, direction, d, x, vv, tol):
            continue
        for j, i in enumerate(rows):
            others = np.delete(np.arange(len(rows)), j)
            ref = float(np.median(vv[others]))
            if abs(vv[j] - ref) <= tol:
                continue
            # the reading named beside this one: the other reading there closest to their median
            other = rows[int(others[np.argmin(np.abs(vv[others] - ref))])]
            first_row, this_row = sorted((other, i))
            where = "" if rec.direction is None else f" in direction {int(d):+d}" + \
                (" (sweeps told apart by the row order)" if inferred else "")
            units = f"{abs(vv[j] - ref) / sigma:.3g} noise units" if sigma > 0 else "beyond the noise"
            which = (f"they are {units} apart" if len(rows) == 2 else
                     f"{rec.line_of(i)} is {units} from the other {len(rows) - 1} readings there")
            _several_temperatures(rec, first_row, this_row, x, which)
            raise RecordingsError(
                f"{rec.source}: {_pair(rec, first_row, this_row)}: displacement {x:g} mm appears twice"
                f"{where} with different voltages ({rec.voltage_v[first_row]:.6g} V, "
                f"{rec.voltage_v[this_row]:.6g} V): {which} (noise {sigma:.3g} V {source}; "
                f"repeats may differ by {tol:.3g} V): a glitch, or two files joined? "
                + ("give each sweep its direction (+1/-1)" if rec.direction is None or inferred else
                   "flann train --terms auto leaves an isolated glitch out; flann diagnose shows where"))


def _lone_glitches(rec: Recordings, direction: np.ndarray, d: float, x: float, vv: np.ndarray,
                   tol: float) -> bool:
    """The readings ``vv`` at position ``x`` (direction ``d``) disagree only through glitches:
    fewer than half of them (one of two) are off the line through the neighbouring positions'
    medians, and the rest agree with it."""
    same = direction == d
    xs, vs = rec.displacement_mm[same], rec.voltage_v[same]
    below, above = np.unique(xs[xs < x]), np.unique(xs[xs > x])
    if below.size == 0 or above.size == 0:
        return False   # at an end: no line through neighbours on both sides
    xl, xh = float(below[-1]), float(above[0])
    vl, vh = float(np.median(vs[xs == xl])), float(np.median(vs[xs == xh]))
    off = int(np.count_nonzero(np.abs(vv - (vl + (vh - vl) * (x - xl) / (xh - xl))) > tol))
    return off == 1 if vv.size == 2 else 0 < off < vv.size / 2


def _several_temperatures(rec: Recordings, a: int, b: int, x: float, which: str) -> None:
    """Refuses rows ``a`` and ``b`` (one position) as readings at two temperatures when they are:
    a temperature change moves the whole curve, which is no glitch and no joined file."""
    if rec.temperature_c is None:
        return
    levels, labels = temperature_groups(rec.temperature_c)
    if labels[a] == labels[b]:
        return
    t, v = rec.temperature_c, rec.voltage_v
    raise RecordingsError(
        f"{rec.source}: {_pair(rec, a, b)}: displacement {x:g} mm reads {v[a]:.6g} V at "
        f"{t[a]:g} degC and {v[b]:.6g} V at {t[b]:g} degC ({which}): the file holds readings at "
        f"{levels.size} temperatures ({', '.join(f'{c:g}' for c in levels[:8])}"
        f"{', ...' if levels.size > 8 else ''} degC), which one curve x(v) cannot fit; "
        "fit voltage and temperature together with flann train --temperature, "
        "or give the rows of one temperature")


def printed_resolution(values) -> float:
    """The last printed digit of the readings (V): the largest power of ten (100 at most) every
    reading is a whole multiple of ('%.6f' volts or '%.3f' millivolts: 1e-6), 0 when there is
    none that doubles resolve (readings of full precision, or to nine significant digits)."""
    u = np.abs(np.asarray(values, float))
    d = -2
    # a sample first: the whole needs at least its digits (one pass over a long recording)
    for part in (u[::max(1, u.size // 256)], u):
        while True:
            a = part * 10.0 ** d
            if a.max() > 1e14 or d > 15:   # beyond a double's 15 digits every number is "whole"
                return 0.0
            if np.all(np.abs(a - np.rint(a)) <= 1e-9 + 8e-16 * a):
                break
            d += 1
    return 10.0 ** -d


# A grid fitted to the readings is taken only where readings off any grid would all fall that
# close to one of the steps tried with less than this chance.
GRID_CHANCE = 1e-6


def _improbable(n: int, span: float, q: float, off: float) -> bool:
    """Whether ``n`` readings off any grid would fall within ``off`` of a grid of some step
    near ``q`` with less than :data:`GRID_CHANCE`: each does with chance 2 off / q, two are
    fitted, and steps ``2 off / span`` apart are told apart over the span."""
    p = 2.0 * off / q
    if not p < 1:
        return False
    return (n - 2) * math.log(p) + math.log(max(1.0, span / (2.0 * off))) <= math.log(GRID_CHANCE)


def converter_step(voltage_v, max_divisor: int = 64, tol: float = 0.02) -> float:
    """The converter's step (V) when every reading is a whole number of one step, else 0.

    The smallest gap between distinct readings is the step or a multiple of it; the largest
    step that puts every reading on the grid (within ``tol`` of a step, and the printing's
    rounding: :func:`printed_resolution`) is taken.  Readings with analogue noise or
    averaging are on no grid and give 0.
    """
    u = np.unique(np.asarray(voltage_v, float))
    if u.size < 8:
        return 0.0
    gaps = np.diff(u)
    g0 = float(gaps.min())
    if not g0 > 0:
        return 0.0
    res = printed_resolution(u)
    rel = u - u[0]
    span = float(rel[-1])
    for k in range(1, max_divisor + 1):
        # readings of nine digits and more: the gap's rounding is negligible over the span
        q = span / round(span * k / g0)
        frac = rel / q
        if np.max(np.abs(frac - np.round(frac))) <= tol:
            return q if _on_grid(rel, q, res, u) else 0.0
        q = _grid_step(u, gaps, k, res, tol)
        if q > 0:
            return q if _on_grid(rel, q, res, u) else 0.0
    return 0.0


def _on_grid(rel: np.ndarray, q: float, res: float, u: np.ndarray) -> bool:
    """Converter codes times a step are on the grid to the printing's rounding (a few of the
    printed digit; nine significant digits without one), not to a share of the step: readings
    of a straight sensor at evenly spaced positions are evenly spaced too, each off that grid
    by its noise (0.1 V/mm at 0.25 mm steps, 10 uV noise: a '6-bit, 25 mV converter').  Nine
    significant digits round a reading by up to 5e-9 of it, while the printed digit (``res``)
    is that of the smallest readings: the allowance is 2e-8 of the largest."""
    off = rel - q * np.round(rel / q)
    off -= np.median(off)
    return float(np.max(np.abs(off))) <= 2.0 * res + 2e-8 * float(np.max(np.abs(u)))


def _grid_step(u: np.ndarray, gaps: np.ndarray, k: int, res: float, tol: float) -> float:
    """The step of a grid that holds every reading (``u``, sorted; ``gaps`` between them)
    where the smallest gap is ``k`` steps, or 0.

    A step taken from one gap carries its two readings' rounding (half a µV each in a 0.61 mV
    step of a 14-bit converter printed '%.6f': 3 codes off over its span).  So the gaps are
    numbered in codes from the smallest up, the step refitted to those numbered so far, and a
    gap numbered only while six standard errors of the step over it, with its own rounding,
    stay below half a step; the readings' codes are then the sums of the gaps'.
    """
    q = float(gaps.min()) / k
    if q < 8 * res:
        # readings are whole multiples of the printed digit: steps of a few digits fit them
        # in patterns, not by chance (the direct check in converter_step covers these)
        return 0.0
    rel = u - u[0]
    size = float(rel[-1])
    half = 0.5 * res
    if not _improbable(rel.size, size, q, tol * q + half):
        half = 0.0
        if not _improbable(rel.size, size, q, tol * q):
            return 0.0
    eps = 1e-12 * size   # the doubles' own rounding
    # a reading's rounding: the printed digit's, or nine significant digits' ('%.9g')
    e = max(half, 1e-9 * max(abs(float(u[0])), abs(float(u[-1]))))
    sigma = e * math.sqrt(2.0 / 3.0)   # a gap's: two readings each uniform within +-e
    # gaps of this many codes are numbered without doubt (at first from the smallest alone)
    numbered = max(float(k), (0.45 * q - 2.0 * e) / (6.0 * sigma / k))
    while True:
        sel = gaps <= (numbered + 0.5) * q
        n = np.rint(gaps[sel] / q)
        if not n.min() >= 1:
            return 0.0   # two readings closer than half a step: not on this grid
        q = float(np.dot(n, gaps[sel]) / np.dot(n, n))
        if np.max(np.abs(gaps[sel] - n * q)) > 2.0 * (tol * q + half) + eps:
            return 0.0
        if sel.all():
            break
        wider = (0.45 * q - 2.0 * e) / (6.0 * sigma / math.sqrt(float(np.dot(n, n))))
        if wider <= 1.01 * numbered:
            return 0.0   # the rounding is too coarse to number longer gaps
        numbered = wider
    codes = np.concatenate([[0.0], np.cumsum(n)])
    common = int(np.gcd.reduce(n.astype(np.int64)))
    codes /= common   # codes all multiples of one number: that many steps is the grid's
    d = codes - codes.mean()
    q = float(np.dot(d, rel - rel.mean()) / np.dot(d, d))
    c = float(rel.mean() - q * codes.mean())
    if np.max(np.abs(rel - q * codes - c)) > tol * q + half + eps:
        return 0.0
    return q


# Above this many bits a grid at the printing's last digit is taken for the printing: a
# converter whose step is a power of ten volts is a 1 mV step of a 12-bit converter on a
# 2.048 V reference, not a 23-bit one of 1 µV (noisy readings of a long logger file printed
# '%.6f' fill every microvolt and look like that)
PRINTED_GRID_BITS = 16


def converter_of(voltage_v) -> tuple[int, float] | None:
    """(bits, volts per code) of the converter the readings were taken with, from their grid:
    the step, and the fewest two's-complement bits whose range holds every reading; None off-grid,
    or when the grid is the printing's last digit at more than :data:`PRINTED_GRID_BITS`."""
    step = converter_step(voltage_v)
    if not step > 0:
        return None
    vmax = float(np.max(np.abs(np.asarray(voltage_v, float))))
    bits = int(np.ceil(np.log2(max(vmax / step, 1.0) + 1.0))) + 1
    if bits > PRINTED_GRID_BITS and abs(step - printed_resolution(voltage_v)) < 1e-6 * step:
        return None
    return (bits, step) if 4 <= bits <= 32 else None


def check_units(rec: Recordings) -> None:
    """Voltages no sensor conditioner gives are refused: millivolts under a volts header."""
    vmax = float(np.max(np.abs(rec.voltage_v)))
    if vmax > MAX_PLAUSIBLE_V:
        raise RecordingsError(
            f"{rec.source}: voltage_v reaches {vmax:.6g} V, more than any LVDT conditioner or ADC "
            f"gives (> {MAX_PLAUSIBLE_V:g} V): if these are millivolts, name the column voltage_mv "
            "or 'Voltage (mV)'")


def row_directions(displacement_mm) -> np.ndarray | None:
    """+1/-1 per row from the file order, or None when nothing moves.

    A row that repeats the previous displacement keeps the previous direction, except at a
    turn, where the repeat (the same position read again on the way back) starts the new sweep.
    """
    x = np.asarray(displacement_mm, dtype=float)
    step = np.sign(np.diff(x))
    moving = np.flatnonzero(step)
    if moving.size == 0:
        return None
    prev_dir = step[moving[np.maximum(np.searchsorted(moving, np.arange(step.size)) - 1, 0)]]
    nxt = np.searchsorted(moving, np.arange(step.size))
    next_dir = step[moving[np.minimum(nxt, moving.size - 1)]]
    zero = step == 0
    before = np.arange(step.size) < moving[0]
    step[zero] = np.where(before[zero] | (prev_dir[zero] != next_dir[zero]), next_dir[zero], prev_dir[zero])
    return np.concatenate([[step[0]], step])


def run_lengths(direction: np.ndarray) -> np.ndarray:
    """Lengths of the runs of equal direction, in row order."""
    return np.diff(np.flatnonzero(np.diff(np.concatenate([[0.0], direction, [0.0]]))))


def sweep_direction(displacement_mm) -> np.ndarray | None:
    """+1/-1 per row from the file order (a forward then a reverse sweep, ...), or None when
    the rows are not in sweeps: a single sweep, no motion, or runs shorter than 4 points."""
    d = row_directions(displacement_mm)
    if d is None:
        return None
    runs = run_lengths(d)
    if runs.size < 2 or np.median(runs) < 4:
        return None
    return d


def prepare_for_fit(rec: Recordings, trim: bool = False, noise_v: float | None = None,
                    can_trim: bool = True, lone_glitches: bool = False) -> Recordings:
    """Validate recordings for fitting an inverse model; with ``trim`` keep the monotonic span
    (``can_trim``: the command has a ``--trim`` to advise; without, the span is named instead;
    ``lone_glitches``: the caller screens outliers, :func:`check_duplicates`).

    Without a direction column, sweeps are told apart by the file order (:func:`sweep_direction`)
    for the checks: the same position on the way up and on the way back is not a repeat.
    """
    if len(rec) < MIN_FIT_POINTS:
        raise RecordingsError(
            f"{rec.source}: {len(rec)} point(s); need at least {MIN_FIT_POINTS} to fit a model"
        )
    check_units(rec)
    inferred = rec.direction is None and (d := sweep_direction(rec.displacement_mm)) is not None
    if inferred:
        rec = replace(rec, direction=d)
    check_duplicates(rec, inferred=inferred, lone_glitches=lone_glitches)
    span = monotonic_span(rec, noise_v=noise_v)
    if span.foldback:
        if not span.trimmable:
            raise RecordingsError(span.message + "; the fold-back is inside the span, "
                                  "--trim cannot remove it")
        kept = rec.subset(span.mask)
        lo, hi = kept.displacement_mm.min(), kept.displacement_mm.max()
        if not trim:
            raise RecordingsError(span.message + ("; use --trim to keep the monotonic span" if can_trim else
                                                  f"; keep the recording to its monotonic span {lo:g} .. {hi:g} mm"))
        warnings.warn(f"{rec.source}: --trim kept {len(kept)} of {len(rec)} rows, "
                      f"the monotonic span {lo:g} .. {hi:g} mm", stacklevel=2)
        if len(kept) < MIN_FIT_POINTS:
            raise RecordingsError(
                f"{rec.source}: only {len(kept)} point(s) left after --trim; need at least "
                f"{MIN_FIT_POINTS}")
        return kept
    return rec


# A rail (the output clipped at an amplifier's or converter's limit): at least this many
# readings, at this many distinct positions, at the extreme voltage
MIN_RAIL_READINGS = 4
MIN_RAIL_POSITIONS = 3
# readings within this share of the noise of the rail's level are on it: a smooth peak's top
# readings scatter by the whole noise, a clipped output's not at all
RAIL_NOISE_SHARE = 0.05


@dataclass(frozen=True)
class Rail:
    """Readings at a rail: ``side`` 'high' or 'low', its level, the rows on it (mask)."""

    side: str
    level_v: float
    mask: np.ndarray

    @property
    def n(self) -> int:
        return int(self.mask.sum())


def find_rails(rec: Recordings, noise_v: float | None = None) -> list[Rail]:
    """The rails the readings sit on: runs of readings equal to the highest (lowest) within
    :data:`RAIL_NOISE_SHARE` of the noise (and a converter step's rounding), holding every
    reading beyond them towards that end of the travel."""
    x, v = np.asarray(rec.displacement_mm, float), np.asarray(rec.voltage_v, float)
    rng = float(np.ptp(v))
    if v.size < 2 * MIN_RAIL_READINGS or not rng > 0:
        return []
    xu, inv = np.unique(x, return_inverse=True)
    vu = np.bincount(inv, weights=v) / np.bincount(inv)
    noise = estimate_noise_v(vu, 3) if noise_v is None else float(noise_v)
    tol = max(RAIL_NOISE_SHARE * noise, 0.5 * converter_step(v), 1e-9 * rng)
    rails = []
    for side, sgn in (("high", 1.0), ("low", -1.0)):
        u = sgn * v
        on = u >= float(u.max()) - tol
        if on.sum() < MIN_RAIL_READINGS or np.unique(x[on]).size < MIN_RAIL_POSITIONS:
            continue
        xr = x[on]
        beyond = x >= xr.min() if np.median(xr) >= np.median(x) else x <= xr.max()
        if np.any(beyond & ~on) or on.sum() > 0.5 * v.size:
            continue
        rails.append(Rail(side, float(np.mean(v[on])), on))
    return rails
