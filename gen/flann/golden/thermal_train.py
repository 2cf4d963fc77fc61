"""Training the two-input model x(v, T) (:mod:`.thermal`) on a calibration at several temperatures.

* :func:`fit_thermal` -- least squares (optionally ridge) for given expansion terms per
  temperature order, normalisation and ridge.
* :func:`fit_thermal_auto` -- the structure by cross-validation, over held-out *positions*
  (K folds of the distinct positions, every temperature of a position held out together)
  and held-out *temperatures* (each interior calibration temperature left out in turn; a
  fold fits the orders its remaining temperatures determine, so with 3 temperatures the
  quadratic order is judged on positions only).  Every candidate is judged on the same
  held-out points, so two candidates are compared point by point (the paired standard
  error of :mod:`.train`).  Every order uses the whole expansion: dropping cross terms
  that the held-out mean square cannot tell from noise cost accuracy and drift between the
  calibration temperatures, at the flat ends of the stroke, where the mean square does not
  look.  Of the candidates (normalisation, ridge, expansion size) whose held-out mean
  squared error is within ``AUTO_PAIRED_Z`` paired standard errors of the best, the one
  with the smallest sum of |coefficients| (the fixed-point terms' width, so the finest
  output LSB the hardware builds).  Candidates whose coefficients exceed ``WEIGHT_LIMIT``
  times the largest displacement, or sum to more than ``WEIGHT_SUM_LIMIT`` times, are not
  taken.  Position folds are ``POSITION_FOLDS``:
  with fewer, each fold's fit misses a larger share of the positions and the held-out
  error favours stiffer models than the full fit needs.

The temperature order is at most 2 (and at most the number of temperatures - 1): the
copper law makes the gain a ratio of functions linear in T, whose series in T is dominated
by its first two orders over a -20..80 degC range (docs/temperature.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import FlannError, RecordingsError
from .thermal import ThermalModel, corrected_voltage, temperature_groups, thermal_design
from .train import AUTO_MAX_CV_POINTS, AUTO_NORMS, AUTO_PAIRED_Z, normalisation, solve_lstsq

MAX_ORDER = 2
AUTO_TERMS = (0, 1, 3, 5, 7, 9, 11, 13, 15, 19, 25, 31, 41)
# A candidate whose coefficients exceed this many times the largest |displacement| is not
# taken: nearly collinear terms cancelling each other, which fixed point cannot carry (the
# one-input selection asks the fixed-point design itself; its weights stay within ~3x).
WEIGHT_LIMIT = 16.0
# ... nor one whose |coefficients| sum to more than this many times: the sum sets the width of
# the order datapaths' terms, and past it the finest output LSB that builds is coarser than the
# model's own error (a 2 mm sensor at 122x built at nothing finer than 180 ppm FS)
WEIGHT_SUM_LIMIT = 64.0
AUTO_RIDGES = (0.0, 1e-12, 1e-10, 1e-8, 1e-6)
POSITION_FOLDS = 10
MIN_TEMPERATURES = 2
MIN_POSITIONS = 4


def _temperature_norm(temperature_c) -> tuple[float, float]:
    t = np.asarray(temperature_c, dtype=float)
    lo, hi = float(t.min()), float(t.max())
    if not hi > lo:
        raise RecordingsError(f"temperature_c spans no range (all {lo:g} degC): a two-input model "
                              "needs a calibration at 2 or more temperatures")
    return (lo + hi) / 2.0, (hi - lo) / 2.0


def input_correction(voltage_v, t_n, displacement_mm, labels, groups) -> tuple[tuple, tuple]:
    """(input_gain_t, input_offset_t_v): the voltage at each calibration temperature of
    ``groups`` mapped by least squares (a gain and an offset, over the positions both
    hold) onto the temperature nearest the middle, and those gains and offsets fitted by a
    polynomial in t_n of degree min(2, len(groups) - 1), normalised to gain 1 at t_n = 0."""
    v = np.asarray(voltage_v, dtype=float)
    x = np.asarray(displacement_mm, dtype=float)
    curves, temps = [], []
    for g in groups:
        rows = labels == g
        pos, inv = np.unique(np.round(x[rows], 9), return_inverse=True)
        curves.append((pos, np.bincount(inv, weights=v[rows]) / np.bincount(inv)))
        temps.append(float(np.mean(t_n[rows])))
    degree = min(MAX_ORDER, len(groups) - 1)
    if degree < 1:
        return (), ()
    ref = int(np.argmin(np.abs(temps)))
    rp, rv = curves[ref]
    gains, offsets = [], []
    for pos, vk in curves:
        inside = (pos >= rp[0]) & (pos <= rp[-1])
        if inside.sum() < 2:
            raise RecordingsError("the calibration temperatures share too few positions to "
                                  "compare their gains")
        a = np.column_stack([vk[inside], np.ones(int(inside.sum()))])
        (g_k, o_k), *_ = np.linalg.lstsq(a, np.interp(pos[inside], rp, rv), rcond=None)
        gains.append(g_k)
        offsets.append(o_k)
    powers = np.asarray(temps)[:, None] ** np.arange(degree + 1)[None, :]
    gc, *_ = np.linalg.lstsq(powers, np.asarray(gains), rcond=None)
    oc, *_ = np.linalg.lstsq(powers, np.asarray(offsets), rcond=None)
    return (tuple(float(c / gc[0]) for c in gc[1:]), tuple(float(c / gc[0]) for c in oc[1:]))


def fit_thermal(voltage_v, temperature_c, displacement_mm, terms: tuple[int, ...], *,
                norm: str = "range", ridge: float = 0.0, correct_input: bool = True,
                temperature_norm: tuple[float, float] | None = None, training: dict | None = None) -> ThermalModel:
    """Least squares for ``terms`` (expansion terms per temperature order), after the
    input correction (:func:`input_correction`) unless ``correct_input`` is False;
    ``temperature_norm`` (offset, scale) degC, default the recording's own range."""
    v = np.asarray(voltage_v, dtype=float)
    t = np.asarray(temperature_c, dtype=float)
    x = np.asarray(displacement_mm, dtype=float)
    if not terms or any(n < 0 for n in terms):
        raise FlannError(f"terms per temperature order must be >= 0, got {list(terms)}")
    t_off, t_scale = temperature_norm or _temperature_norm(t)
    t_n = (t - t_off) / t_scale
    gain_t, offset_t = ((), ())
    if correct_input:
        levels, labels = temperature_groups(t)
        gain_t, offset_t = input_correction(v, t_n, x, labels, range(levels.size))
    v_c = corrected_voltage(v, t_n, gain_t, offset_t)
    offset, scale = normalisation(v_c, norm)
    a = thermal_design((v_c - offset) / scale, t_n, terms)
    coef = solve_lstsq(a, x, ridge)
    resid = x - a @ coef
    weights, bias, k = [], [], 0
    for n in terms:
        bias.append(float(coef[k]))
        weights.append(tuple(float(c) for c in coef[k + 1:k + 1 + n]))
        k += 1 + n
    info = {"method": "lstsq", "ridge": float(ridge), "normalisation": norm,
            "train_rms_error_mm": float(np.sqrt(np.mean(resid ** 2))), "points": int(v.size)}
    info.update(training or {})
    return ThermalModel(weights=tuple(weights), bias=tuple(bias), input_offset_v=float(offset),
                        input_scale_v=float(scale), temperature_offset_c=float(t_off),
                        temperature_scale_c=float(t_scale), input_gain_t=gain_t,
                        input_offset_t_v=offset_t,
                        voltage_range_v=(float(v.min()), float(v.max())),
                        temperature_range_c=(float(t.min()), float(t.max())),
                        displacement_range_mm=(float(x.min()), float(x.max())), training=info)


@dataclass(frozen=True)
class ThermalCv:
    terms: tuple[int, ...]
    norm: str
    ridge: float
    sq_errors: np.ndarray       # held-out squared error of every judged point, fixed order
    max_coefficient: float      # largest |coefficient| fitted on all the judged points
    weight_sum: float           # sum of |coefficient| fitted on all the judged points
    at_positions: int = 0       # how many of sq_errors (the first) are the position folds'

    @property
    def mse(self) -> float:
        return float(np.mean(self.sq_errors))

    @property
    def rms_mm(self) -> float:
        return float(np.sqrt(self.mse))

    @property
    def max_mm(self) -> float:
        return float(np.sqrt(np.max(self.sq_errors)))

    @property
    def position_rms_mm(self) -> float:
        """Held-out RMS over the position folds alone: how well the terms follow the curve at
        the calibrated temperatures (a held-out temperature's error is the temperature
        orders', much the same at any term count)."""
        return float(np.sqrt(np.mean(self.sq_errors[:self.at_positions]))) if self.at_positions else self.rms_mm

    @property
    def coefficients(self) -> int:
        return sum(self.terms) + len(self.terms)


@dataclass(frozen=True)
class _Folds:
    """Held-out index sets: position folds first, then each interior temperature."""
    position: list[np.ndarray]
    temperature: list[np.ndarray]
    n_temperatures: int


def _folds(x: np.ndarray, labels: np.ndarray, n_groups: int) -> _Folds:
    positions, pos_label = np.unique(np.round(x, 9), return_inverse=True)
    k = min(POSITION_FOLDS, positions.size)
    position = [np.flatnonzero(pos_label % k == f) for f in range(k)]
    temperature = [np.flatnonzero(labels == g) for g in range(1, n_groups - 1)]
    return _Folds(position, temperature, n_groups)


@dataclass(frozen=True)
class _Inputs:
    """Normalised inputs of every fold: ``v_n`` with the input correction from every
    temperature (position folds), ``v_n_without[k]`` from the temperatures but the k-th
    held-out one (that fold's own calibration)."""
    v_n: np.ndarray
    t_n: np.ndarray
    v_n_without: list[np.ndarray]


def _inputs(v, t_n, x, labels, n_groups, folds: _Folds, norm: str, correct_input: bool = True) -> _Inputs:
    def correction(groups):
        return input_correction(v, t_n, x, labels, groups) if correct_input else ((), ())

    gain_t, offset_t = correction(range(n_groups))
    v_c = corrected_voltage(v, t_n, gain_t, offset_t)
    offset, scale = normalisation(v_c, norm)
    without = []
    for g in range(1, n_groups - 1):
        gk, ok = correction([k for k in range(n_groups) if k != g])
        without.append((corrected_voltage(v, t_n, gk, ok) - offset) / scale)
    return _Inputs((v_c - offset) / scale, t_n, without)


def _cv(x, folds: _Folds, inputs: _Inputs, terms, norm, ridge) -> ThermalCv:
    """Held-out squared errors of a candidate (normalisations fixed from all the data, so
    every fold expands the same way)."""
    v_n, t_n = inputs.v_n, inputs.t_n
    full = thermal_design(v_n, t_n, terms)
    errs = []
    for held in folds.position:
        train = np.ones(v_n.size, bool)
        train[held] = False
        coef = solve_lstsq(full[train], x[train], ridge)
        errs.append((full[held] @ coef - x[held]) ** 2)
    at_positions = sum(e.size for e in errs)
    usable = terms[:folds.n_temperatures - 1]   # orders the remaining temperatures determine
    for held, v_fold in zip(folds.temperature, inputs.v_n_without):
        part = thermal_design(v_fold, t_n, usable)
        train = np.ones(v_n.size, bool)
        train[held] = False
        coef = solve_lstsq(part[train], x[train], ridge)
        errs.append((part[held] @ coef - x[held]) ** 2)
    coef = solve_lstsq(full, x, ridge)
    return ThermalCv(tuple(terms), norm, ridge, np.concatenate(errs), float(np.max(np.abs(coef))),
                     float(np.sum(np.abs(coef))), at_positions)


def _paired_se(r: ThermalCv, ref: ThermalCv) -> float:
    d = r.sq_errors - ref.sq_errors
    return float(np.std(d, ddof=1) / np.sqrt(d.size)) if d.size > 1 else 0.0


def cv_subset(n: int, limit: int = AUTO_MAX_CV_POINTS) -> np.ndarray:
    return np.arange(n) if n <= limit else np.unique(np.linspace(0, n - 1, limit).round().astype(int))


@dataclass(frozen=True)
class ThermalCvRun:
    """Every candidate of one cross-validation and the folds it used."""
    results: list[ThermalCv]
    position_folds: int
    temperature_folds: int
    points: int
    temperatures_c: tuple[float, ...]


def cross_validate_thermal(voltage_v, temperature_c, displacement_mm, *, orders: int | None = None,
                           terms=AUTO_TERMS[1:], norms=AUTO_NORMS, ridges=AUTO_RIDGES,
                           temperature_norm: tuple[float, float] | None = None, correct_input: bool = True,
                           source: str = "recordings") -> ThermalCvRun:
    """Held-out errors (module docstring) of every candidate: ``terms`` per order (every order
    the same), ``orders`` temperature orders (default: what the temperatures determine, at most
    ``MAX_ORDER`` + 1), ``temperature_norm`` (offset, scale) degC (default: the recording's own
    range) and with or without the input correction."""
    v = np.asarray(voltage_v, dtype=float)
    t = np.asarray(temperature_c, dtype=float)
    x = np.asarray(displacement_mm, dtype=float)
    levels, labels = temperature_groups(t)
    if levels.size < MIN_TEMPERATURES:
        raise RecordingsError(f"{source}: temperature_c takes {levels.size} value(s); a two-input "
                              f"model needs a calibration at {MIN_TEMPERATURES} or more temperatures")
    if np.unique(np.round(x, 9)).size < MIN_POSITIONS:
        raise RecordingsError(f"{source}: fewer than {MIN_POSITIONS} distinct positions: too few "
                              "to cross-validate a two-input model")
    sub = cv_subset(v.size)
    vs, ts, xs = v[sub], t[sub], x[sub]
    _, sub_labels = temperature_groups(ts)
    folds = _folds(xs, sub_labels, levels.size)
    t_off, t_scale = temperature_norm or _temperature_norm(t)
    if orders is None:
        orders = min(MAX_ORDER + 1, levels.size)
    inputs = {norm: _inputs(vs, (ts - t_off) / t_scale, xs, sub_labels, levels.size, folds, norm, correct_input)
              for norm in norms}
    results: list[ThermalCv] = []
    for norm in norms:
        for ridge in ridges:
            for n in terms:
                if (n + 1) * orders >= xs.size:
                    continue
                results.append(_cv(xs, folds, inputs[norm], (n,) * orders, norm, ridge))
    if not results:
        raise RecordingsError(f"{source}: {v.size} points are too few for a two-input model")
    return ThermalCvRun(results, len(folds.position), len(folds.temperature), int(sub.size),
                        tuple(float(round(a, 3)) for a in levels))


def select_thermal(results: list[ThermalCv], displacement_mm) -> tuple[ThermalCv, ThermalCv, int]:
    """(choice, best, how many as good): of the buildable candidates (``WEIGHT_LIMIT``,
    ``WEIGHT_SUM_LIMIT``) within ``AUTO_PAIRED_Z`` paired standard errors of the best held-out
    error, the smallest sum of |coefficients|."""
    scale = float(np.max(np.abs(displacement_mm)))
    limit, sum_limit = WEIGHT_LIMIT * scale, WEIGHT_SUM_LIMIT * scale
    buildable = [r for r in results if r.max_coefficient <= limit and r.weight_sum <= sum_limit] or results
    best = min(buildable, key=lambda r: r.mse)
    good = [r for r in buildable
            if r is best or r.mse - best.mse <= AUTO_PAIRED_Z * _paired_se(r, best)]
    return min(good, key=lambda r: (r.weight_sum, r.mse)), best, len(good)


def fit_thermal_auto(voltage_v, temperature_c, displacement_mm, *, training: dict | None = None,
                     source: str = "recordings", terms=None) -> tuple[ThermalModel, ThermalCv]:
    """Structure by cross-validation (module docstring); the choice fitted on every row.
    ``terms``: the expansion sizes to choose among (default ``AUTO_TERMS``)."""
    run = cross_validate_thermal(voltage_v, temperature_c, displacement_mm, source=source,
                                 terms=AUTO_TERMS[1:] if terms is None else tuple(terms))
    choice, best, n_good = select_thermal(run.results, displacement_mm)
    info = {
        "selected_by": "cross-validation over held-out positions and temperatures; every "
                       "order with the whole expansion; of the candidates within "
                       f"{AUTO_PAIRED_Z:g} paired standard errors of the best held-out error, "
                       "the smallest sum of |coefficients|",
        "cv_position_folds": run.position_folds,
        "cv_temperature_folds": run.temperature_folds,
        "cv_points": run.points,
        "cv_rms_error_mm": choice.rms_mm,
        "cv_max_error_mm": choice.max_mm,
        "calibration_temperatures_c": list(run.temperatures_c),
        "as_good_candidates": n_good,
        "best_structure": {"terms": list(best.terms), "cv_rms_error_mm": best.rms_mm,
                           "coefficients": best.coefficients},
    }
    info.update(training or {})
    model = fit_thermal(voltage_v, temperature_c, displacement_mm, choice.terms, norm=choice.norm,
                        ridge=choice.ridge, training=info)
    return model, choice


def compensable(temperature_c, min_rows: int = MIN_POSITIONS) -> tuple[float, ...]:
    """The temperatures a recording holds with at least ``min_rows`` rows each."""
    if temperature_c is None:
        return ()
    levels, labels = temperature_groups(temperature_c)
    counts = np.bincount(labels, minlength=levels.size)
    return tuple(float(t) for t, c in zip(levels, counts) if c >= min_rows)


__all__ = ["AUTO_TERMS", "MAX_ORDER", "ThermalCv", "ThermalCvRun", "compensable", "cross_validate_thermal",
           "fit_thermal", "fit_thermal_auto", "select_thermal"]
