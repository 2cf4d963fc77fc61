"""PASS or FAIL against a :class:`~flann.production.spec.ProductionSpec`, with the reasons,
and the expanded uncertainty of the figures the verdict rests on.  Without a specification
(no tolerance, no limit, no effect ruled out) a calibrated sensor is NOT JUDGED, never PASS:
its weights are written, and the certificate says nothing was judged.

Decision rule: simple acceptance (ILAC-G8 "shared risk"): a sensor passes when its measured
max error is within the tolerance; the expanded uncertainty U (k = 2) is stated beside it and
a result within U of the tolerance is flagged as marginal in the reasons.

Uncertainty of the max error (method stated on the certificate): one reading's noise sigma_v
(from the recording, :func:`noise_v`: the median absolute third difference along each pass
of the actuator in row order, median over the passes) becomes
sigma_x = sigma_v |dx/dv| in mm (median over the stroke); the fitted curve adds its own
uncertainty sigma_x sqrt(p / N) (p model terms, N positions); the output code adds
q / sqrt(12).  u = sqrt(sigma_x^2 (1 + p / N) + q^2 / 12), U = 2 u.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..diagnose.data import find_passes
from ..errors import FlannError
from ..golden.metrics import full_scale_of_span
from ..recordings.checks import MIN_REPEAT_PAIRS, estimate_noise_v, repeat_noise_v
from .spec import ProductionSpec

PASS, FAIL, NOT_JUDGED = "PASS", "FAIL", "NOT JUDGED"
NOT_JUDGED_WHY = "no specification given: nothing judged (give --spec or --tolerance-mm)"
COVERAGE = 2.0
# the working range must lie inside the recorded displacements to within this (mm)
RANGE_SLACK_MM = 1e-6
# third differences: they cancel the curve's slope and curvature, which at an LVDT's coarse
# steps (0.5 mm) put as much into a second difference as 2 mV of noise
NOISE_ORDER = 3
# The verdict judges the hardware's error at the recorded positions, i.e. where the weights
# were fitted.  With fewer positions than terms the least-squares weights follow the readings
# and that error says nothing about the stroke between them.  Measured on a 19-term family
# (two sweeps of a simulated LVDT, 2 mV, then a noise-free sweep every 0.1 mm): 11 positions
# judged 0.085 mm where the stroke had 5.7 mm, 16 judged 0.13 mm for 0.28 mm; from 21 (1.1 a
# term) on, the judged error was at or above the stroke's (0.15-0.23 mm).
POSITIONS_PER_TERM = 1.25
UNCERTAINTY_METHOD = (
    "U = 2 u (k = 2, about 95 %); u^2 = sigma_x^2 (1 + p/N) + q^2/12 with sigma_x the "
    "recording's noise per reading (median absolute third difference along each pass of "
    "the actuator in recorded order, one reading per position, / (0.6745 sqrt 20), in V, the "
    "median over the passes) times the median |dx/dv|, p the model terms, N the positions "
    "recorded, q the output LSB")


@dataclass(frozen=True)
class Uncertainty:
    noise_v: float
    sigma_x_mm: float
    positions: int
    terms: int
    expanded_mm: float          # U, k = 2
    method: str = UNCERTAINTY_METHOD


@dataclass(frozen=True)
class Verdict:
    verdict: str                         # PASS | FAIL | NOT JUDGED
    reasons: tuple[str, ...]
    tolerance: str                       # the spec as one cell
    max_error_mm: float | None           # over the working range
    max_error_pct_fs: float | None
    full_scale_mm: float | None
    range_text: str                      # "-8..8 mm" or "the recorded stroke -10..10 mm"
    rejected: bool = False               # not calibrated at all (bad input, outside the family)

    @property
    def passed(self) -> bool:
        return self.verdict == PASS

    @property
    def shipped(self) -> bool:
        """The sensor's weights are written: it passed, or was calibrated with nothing to judge."""
        return self.verdict in (PASS, NOT_JUDGED)


def _passes(x: np.ndarray, direction) -> list[np.ndarray]:
    """Row indices of each monotone pass of the actuator, in row order, one reading per
    position (the first of a dwell: a repeat at one position would put a step of the curve
    into every difference); [] when the rows are in no order."""
    passes = find_passes(x, direction)
    if not passes.ordered:
        return []
    out = []
    for run in passes.runs:
        run = run[np.concatenate([[True], np.diff(x[run]) != 0])]
        step = np.sign(np.diff(x[run]))
        trend = np.sign(step.sum())
        # a direction column may hold several passes one way (the return stroke not
        # recorded): cut where the travel goes back
        out += np.split(run, np.flatnonzero(step == -trend) + 1) if trend else [run]
    if not out or np.median([p.size for p in out]) < 4:
        return []
    return [p for p in out if p.size >= 4]


def noise_v(rec) -> float:
    """One reading's noise (V): the median of the estimates along each pass of the actuator,
    in row order.  Sorting all rows by displacement would interleave the readings of repeated
    sweeps at one position, and the differences would measure the curve's change between
    sweeps instead of the noise.  Rows in no order: the spread of readings repeated at one
    position, else the rows of each direction sorted by displacement (one sweep)."""
    v = np.asarray(rec.voltage_v, dtype=float)
    x = np.asarray(rec.displacement_mm, dtype=float)
    d = None if rec.direction is None else np.asarray(rec.direction, dtype=float)
    est = [estimate_noise_v(v[p], order=NOISE_ORDER) for p in _passes(x, d)]
    if est:
        return float(np.median(est))
    sigma, pairs = repeat_noise_v(x, v, d)
    if pairs >= MIN_REPEAT_PAIRS:
        return sigma
    groups = [np.flatnonzero(d == s) for s in (1.0, -1.0)] if d is not None else [np.arange(v.size)]
    est = [estimate_noise_v(v[g][np.argsort(x[g], kind="stable")], order=NOISE_ORDER)
           for g in groups if g.size >= 4]
    return float(np.median(est)) if est else 0.0


def uncertainty(rec, dxdv: np.ndarray, terms: int, output_lsb_mm: float) -> Uncertainty:
    nv = noise_v(rec)
    sx = nv * float(np.median(np.abs(dxdv)))
    n = int(np.unique(np.asarray(rec.displacement_mm, dtype=float)).size)
    u2 = sx ** 2 * (1.0 + terms / max(n, 1)) + output_lsb_mm ** 2 / 12.0
    return Uncertainty(noise_v=nv, sigma_x_mm=sx, positions=n, terms=int(terms),
                       expanded_mm=COVERAGE * math.sqrt(u2))


def require_positions(x_mm, terms: int, where: str = "") -> None:
    """Refuse a recording with too few distinct positions for ``terms`` weights (a
    :class:`FlannError`, i.e. a rejected sensor)."""
    n = int(np.unique(np.asarray(x_mm, dtype=float)).size)
    need = math.ceil(POSITIONS_PER_TERM * int(terms))
    if n < need:
        raise FlannError(f"{n} positions{where} for the design's {terms} terms: the weights would follow "
                         f"the readings and their error between the positions could not be judged; "
                         f"record at least {need} positions ({POSITIONS_PER_TERM:g} a term)")


def judge(spec: ProductionSpec, x_mm, err_mm, ratio_to_limit: float | None,
          named: tuple[str, ...], alternatives: tuple[tuple[str, ...], ...] = (),
          expanded_mm: float | None = None) -> Verdict:
    """The verdict of a calibrated sensor: its hardware error ``err_mm`` at the recorded
    displacements ``x_mm``, its ratio to the physical limit, and the effects its diagnosis
    named (and the sets it could not tell apart)."""
    x = np.asarray(x_mm, dtype=float)
    e = np.abs(np.asarray(err_mm, dtype=float))
    reasons: list[str] = []
    lo_x, hi_x = float(np.min(x)), float(np.max(x))
    if spec.working_range_mm is not None:
        lo, hi = spec.working_range_mm
        rng = f"{lo:.4g}..{hi:.4g} mm"
        if lo < lo_x - RANGE_SLACK_MM or hi > hi_x + RANGE_SLACK_MM:
            reasons.append(f"the recording covers {lo_x:.4g}..{hi_x:.4g} mm, not the whole working "
                           f"range {rng}")
        inside = (x >= lo) & (x <= hi)
    else:
        lo, hi = lo_x, hi_x
        rng = f"the recorded stroke {lo_x:.4g}..{hi_x:.4g} mm"
        inside = np.ones(x.size, bool)
    fs = full_scale_of_span(lo, hi)
    max_err = float(np.max(e[inside])) if inside.any() else None
    pct = 100.0 * max_err / fs if max_err is not None and fs > 0 else None
    if max_err is None:
        reasons.append(f"no recorded point inside the working range {rng}")
    u = expanded_mm or 0.0
    if spec.max_error_mm is not None and max_err is not None:
        if max_err > spec.max_error_mm:
            reasons.append(f"max error {max_err:.4g} mm > tolerance {spec.max_error_mm:g} mm "
                           f"over {rng}")
        elif max_err + u > spec.max_error_mm:
            reasons.append(f"marginal: max error {max_err:.4g} mm is within U = {u:.2g} mm of "
                           f"the tolerance {spec.max_error_mm:g} mm (passed by simple acceptance)")
    if spec.max_error_pct_fs is not None and pct is not None:
        u_pct = 100.0 * u / fs if fs > 0 else 0.0
        if pct > spec.max_error_pct_fs:
            reasons.append(f"max error {pct:.4g} % FS > tolerance {spec.max_error_pct_fs:g} % FS "
                           f"(FS {fs:.4g} mm, {rng})")
        elif pct + u_pct > spec.max_error_pct_fs:
            reasons.append(f"marginal: max error {pct:.4g} % FS is within U = {u_pct:.2g} % FS "
                           f"of the tolerance (passed by simple acceptance)")
    if spec.max_ratio_to_limit is not None and ratio_to_limit is not None \
            and ratio_to_limit > spec.max_ratio_to_limit:
        reasons.append(f"max error is {ratio_to_limit:.3g} x the physical limit > "
                       f"{spec.max_ratio_to_limit:g}")
    bad = [n for n in named if n in spec.fail_on_effects]
    if bad:
        reasons.append(f"the diagnosis names {', '.join(bad)}, which the spec does not allow")
    for group in alternatives:
        maybe = [n for n in group if n in spec.fail_on_effects and n not in named]
        if maybe:
            reasons.append(f"the diagnosis cannot rule out {', '.join(maybe)} (confounded with "
                           f"{', '.join(n for n in group if n not in maybe)}), which the spec "
                           "does not allow")
    failed = [r for r in reasons if not r.startswith("marginal")]
    if not failed and not spec.judges:
        return Verdict(verdict=NOT_JUDGED, reasons=(NOT_JUDGED_WHY,), tolerance=spec.tolerance_text(),
                       max_error_mm=max_err, max_error_pct_fs=pct, full_scale_mm=fs, range_text=rng)
    return Verdict(verdict=FAIL if failed else PASS, reasons=tuple(reasons),
                   tolerance=spec.tolerance_text(), max_error_mm=max_err, max_error_pct_fs=pct,
                   full_scale_mm=fs, range_text=rng)


def rejected(spec: ProductionSpec, reason: str) -> Verdict:
    """The verdict of a sensor that could not be calibrated (bad input, outside the family)."""
    return Verdict(verdict=FAIL, reasons=(f"rejected: {reason}",), tolerance=spec.tolerance_text(),
                   max_error_mm=None, max_error_pct_fs=None, full_scale_mm=None, range_text="",
                   rejected=True)


__all__ = ["PASS", "FAIL", "NOT_JUDGED", "NOT_JUDGED_WHY", "POSITIONS_PER_TERM", "Verdict", "Uncertainty", "judge", "rejected", "require_positions", "uncertainty",
           "noise_v", "UNCERTAINTY_METHOD"]
