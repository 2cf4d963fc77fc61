"""Accuracy metrics of a compensated (or raw) LVDT.

Definitions (docs/golden.md, "Metrics"):

* **Full scale (FS)**: half the displacement span, ``(max - min) / 2`` -- 30 mm for the
  paper's +-30 mm stroke.  "% FS" figures are ``100 * error_mm / FS``.
* **Errors**: ``e = output_mm - displacement_mm``; max is ``max |e|``, RMS is
  ``sqrt(mean e^2)``.
* **% of linearity range** (the paper's equation): ``100 * (points within +-tol of the ideal
  line) / (all points)``, ``tol = tol_pct_fs * FS / 100`` (default 2 % FS = 0.6 mm), a point
  on the boundary counting as linear.  The ideal line of the *raw* sensor is its own
  least-squares line ``x = a v + b`` (voltage -> displacement, errors in mm); the ideal
  line of the *compensated* output is ``y = x``.  Table 1 raw: 2 of 13 points, 15.38 %.
* **Fraction of the stroke within +-band % FS** (default 0.1 % FS): each point stands for
  the stretch of displacement nearer to it than to its neighbours (half the gap each side;
  the end points for half their one gap), so uneven sampling is weighted by stroke length;
  the fraction is the summed length of points within the band over the total span.  With
  a ``direction`` column each sweep is weighted on its own and the sweeps averaged.
"""

from __future__ import annotations

import numpy as np

from ..errors import FlannError

DEFAULT_TOL_PCT_FS = 2.0
DEFAULT_BAND_PCT_FS = 0.1


def full_scale_of_span(lo_mm: float, hi_mm: float) -> float:
    """Full scale of the span lo..hi (mm): half of it, the +-full-scale stroke of a sensor
    centred on it (a +-30 mm LVDT has a 30 mm full scale, as its data sheet states)."""
    return 0.5 * (float(hi_mm) - float(lo_mm))


def full_scale_mm(displacement_mm, source: str = "") -> float:
    """The full scale of the displacements' span (:func:`full_scale_of_span`); ``source`` names
    the recording in the refusal."""
    x = np.asarray(displacement_mm, dtype=float)
    fs = full_scale_of_span(np.min(x), np.max(x)) if x.size else 0.0
    if not fs > 0:
        where = f"{source}: " if source else ""
        raise FlannError(f"{where}displacement_mm spans no range (every reading at one position): full scale is "
                         "0, % FS is undefined: eval needs readings over a stroke")
    return fs


def raw_line(voltage_v, displacement_mm) -> tuple[float, float]:
    """Least-squares straight line x = a v + b of the raw sensor: (a mm/V, b mm)."""
    v = np.asarray(voltage_v, dtype=float)
    x = np.asarray(displacement_mm, dtype=float)
    A = np.column_stack([v, np.ones_like(v)])
    (a, b), *_ = np.linalg.lstsq(A, x, rcond=None)
    return float(a), float(b)


def raw_output_mm(voltage_v, displacement_mm) -> np.ndarray:
    """The raw sensor read through its own least-squares line (mm)."""
    a, b = raw_line(voltage_v, displacement_mm)
    return a * np.asarray(voltage_v, dtype=float) + b


def linearity_pct(output_mm, displacement_mm, tol_pct_fs: float = DEFAULT_TOL_PCT_FS,
                  fs_mm: float | None = None) -> float:
    """% of points whose ``|output - displacement| <= tol_pct_fs % of FS``."""
    if not tol_pct_fs >= 0:
        raise FlannError(f"tolerance must be >= 0 % FS, got {tol_pct_fs!r}")
    x = np.asarray(displacement_mm, dtype=float)
    e = np.asarray(output_mm, dtype=float) - x
    fs = full_scale_mm(x) if fs_mm is None else float(fs_mm)
    return 100.0 * float(np.count_nonzero(np.abs(e) <= tol_pct_fs / 100.0 * fs)) / e.size


def raw_linearity_pct(voltage_v, displacement_mm, tol_pct_fs: float = DEFAULT_TOL_PCT_FS,
                      fs_mm: float | None = None) -> float:
    """The raw sensor's % of linearity range, judged against its least-squares line."""
    return linearity_pct(raw_output_mm(voltage_v, displacement_mm), displacement_mm,
                         tol_pct_fs, fs_mm)


def stroke_weights(displacement_mm) -> np.ndarray:
    """Length of stroke (mm) each point stands for: its position stands for half the gap to
    each neighbouring position, shared equally by the readings at that position (so the
    weights do not depend on the rows' order, and a repeated position counts once)."""
    x = np.asarray(displacement_mm, dtype=float)
    xu, idx, count = np.unique(x, return_inverse=True, return_counts=True)
    gaps = np.diff(xu)
    per_position = np.zeros(xu.size)
    per_position[:-1] += gaps / 2.0
    per_position[1:] += gaps / 2.0
    idx = idx.ravel()
    return per_position[idx] / count[idx]


def stroke_fraction_within(output_mm, displacement_mm, band_pct_fs: float = DEFAULT_BAND_PCT_FS,
                           fs_mm: float | None = None, direction=None) -> float:
    """Fraction (0..1) of the stroke whose error is within +-band_pct_fs % FS."""
    x = np.asarray(displacement_mm, dtype=float)
    e = np.asarray(output_mm, dtype=float) - x
    fs = full_scale_mm(x) if fs_mm is None else float(fs_mm)
    ok = np.abs(e) <= band_pct_fs / 100.0 * fs
    groups = ([np.flatnonzero(np.asarray(direction) == d) for d in (1.0, -1.0)]
              if direction is not None else [np.arange(x.size)])
    fractions = []
    for idx in groups:
        if idx.size < 2 or np.ptp(x[idx]) == 0:
            continue
        w = stroke_weights(x[idx])
        fractions.append(float(np.sum(w[ok[idx]]) / np.sum(w)))
    if not fractions:
        raise FlannError("need at least 2 distinct displacements to measure a stroke fraction")
    return float(np.mean(fractions))


def error_report(output_mm, displacement_mm, tol_pct_fs: float = DEFAULT_TOL_PCT_FS,
                 band_pct_fs: float = DEFAULT_BAND_PCT_FS, fs_mm: float | None = None,
                 direction=None) -> dict:
    """All metrics of one output against the displacement (keys as in ``flann eval --json``)."""
    x = np.asarray(displacement_mm, dtype=float)
    e = np.asarray(output_mm, dtype=float) - x
    fs = full_scale_mm(x) if fs_mm is None else float(fs_mm)
    max_e = float(np.max(np.abs(e)))
    rms_e = float(np.sqrt(np.mean(e**2)))
    return {
        "max_error_mm": max_e,
        "rms_error_mm": rms_e,
        "max_error_pct_fs": 100.0 * max_e / fs,
        "rms_error_pct_fs": 100.0 * rms_e / fs,
        "linearity_pct": linearity_pct(output_mm, x, tol_pct_fs, fs),
        "stroke_fraction_within_band": stroke_fraction_within(output_mm, x, band_pct_fs, fs,
                                                              direction),
    }
