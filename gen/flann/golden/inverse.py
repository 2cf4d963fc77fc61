"""The FLANN fitted to the inverse of a forward curve v(x), the noise where it is.

A calibration steps the actuator to exact positions and reads a noisy voltage.  Fitting
x(v) directly puts the noise in the regressor: least squares then pulls the fit flat where
the sensor's slope is low (the ends of the stroke, where the max error sits), and with a
handful of positions x(v) swings between them.  So ``flann train --terms auto`` fits the
forward curve v(x), inverts it densely, and fits the FLANN candidates to that noise-free
inverse (:func:`fit_to_forward`):

* the forward curve is a small sum of tanh units averaged over their number, free ones
  and ones odd about a fitted null (:mod:`flann.golden.sigmoids`); with fewer than
  :data:`SPARSE_POSITIONS` positions, a cubic spline through the position means
  (not-a-knot; monotone piecewise cubic when that one is not monotone): on 13 positions of
  the e2e family the tanh units' average, whose larger members then nearly interpolate,
  swung between the points (up to 24x the oracle where the spline had 6.8x);
* with :data:`SPARSE_POSITIONS` or more positions the direct fit's cross-validated choice
  is kept when the FLANN cannot follow the forward curve's inverse more closely than that
  choice's own held-out max error (a knee too sharp for any buildable candidate);
* with fewer, the error of the procedure at interior positions left out in turn is
  recorded, not used to choose: it is pessimistic (a left-out position doubles the spacing
  there) and blind to a direct fit that swings *between* the positions.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .forward import aggregate, strictly_monotone
from .model import FlannModel
from .sigmoids import SigmoidForward, fit_forward, refit
from .train import AUTO_NORMS, AUTO_RIDGES, AUTO_TERMS, CvResult, cv_folds, fit_auto, fit_lstsq

SPARSE_POSITIONS = 20      # the outlier screen's lower limit: below it, no smooth fit judges noise
MIN_POSITIONS = 5          # a cubic through fewer is no better than the direct fit's candidates
DENSE = 2001               # points of the inverse the FLANN is fitted to (uniform in x)
# candidates within this factor of the best buildable max deviation: through few positions
# the fewest terms near the best; on a dense curve the best buildable one (the roll-over of
# the paper's LVDT: 0.031 mm from the curve with 41 terms, 0.025 mm with 51)
TEACHER_TOL = 1.25
DENSE_TEACHER_TOL = 1.0
# members lighter than this in the full fit are not refitted per fold: on 8 e2e sensors the
# held-out RMS moved in its fifth digit at most, at half the time
REFIT_WEIGHT = 1e-3
TREND_UNITS = 2            # the few-positions trend: at most this many tanh units
# The noise-free inverse is followed as closely as the fixed-point bound allows: on the
# strong roll-offs of 16-bit sensors the candidates closest to it (61 terms, 'half', small
# ridge) have sin/cos weights too large for the datapath to stay within one output LSB.
# v_n in [-0.85, 0.85] (a gap of 0.3 in the terms' period for the curve to turn in) is
# better conditioned than 'half' and follows the ends far better than 'range'.
TEACHER_NORMS = (*AUTO_NORMS, "0.85")


@dataclass(frozen=True)
class Forward:
    """The interpolated forward curve: position means and the spline through them, on a
    smooth trend when there is one (the spline then interpolates only what the trend leaves,
    which is smaller and gentler, so it swings less between the positions)."""
    positions: np.ndarray
    mean_v: np.ndarray
    kind: str                 # "cubic" or "pchip"
    trend: SigmoidForward | None = None
    # the procedure's error at each interior position left out in turn (mm), once judged
    left_out_mm: np.ndarray | None = field(default=None, compare=False, repr=False)
    straight = False           # an interpolant says nothing of curvature beyond the noise

    def curve(self, positions=None, mean_v=None, trend=None):
        p = self.positions if positions is None else positions
        m = self.mean_v if mean_v is None else mean_v
        t = self.trend if positions is None else trend
        from scipy.interpolate import CubicSpline, PchipInterpolator  # slow to import: only where fitted
        base = CubicSpline if self.kind == "cubic" else PchipInterpolator
        if t is None:
            return base(p, m)
        rest = base(p, m - t(p))
        return lambda x: t(x) + rest(x)

    def __call__(self, x) -> np.ndarray:
        return self.curve()(x)

    @property
    def stroke(self) -> tuple[float, float]:
        return float(self.positions[0]), float(self.positions[-1])

    @property
    def name(self) -> str:
        spline = "a cubic spline" if self.kind == "cubic" else "a monotone cubic"
        on = " on a tanh-unit trend" if self.trend is not None else ""
        return f"{spline}{on} through their mean readings"

    def describe(self) -> dict:
        return {"kind": "cubic spline" if self.kind == "cubic" else "monotone cubic",
                "trend": None if self.trend is None else self.trend.describe()}


def _rms(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(e)))) if e.size else float("nan")


def _trend(displacement_mm, voltage_v) -> SigmoidForward | None:
    """The few-positions trend: at most :data:`TREND_UNITS` units, never grown, and no spread
    members: on 13 positions they weigh below 1e-6 in its average (the two free units carry
    it) and take nine tenths of its fit, which leaving each position out repeats."""
    return fit_forward(displacement_mm, voltage_v, max_units=TREND_UNITS, more_units=TREND_UNITS,
                       spreads=False)


def spline_curve(displacement_mm, voltage_v) -> Forward | None:
    """The spline v(x) through the position means, or None (too few positions, or no
    monotone curve through them: the readings fold back or sit within noise of each other).

    Two are tried, each the not-a-knot cubic or, when that is not monotone, the monotone
    one: on a trend of at most :data:`TREND_UNITS` tanh units, and plain.  When both are
    monotone the one with the smaller error at interior positions left out in turn is taken
    (ties: plain).  Both interpolate the same points, so what tells them apart is how they
    bend between them, which leaving a position out sees."""
    pos = aggregate(displacement_mm, voltage_v)
    if pos.x.size < MIN_POSITIONS or not strictly_monotone(pos.v):
        return None
    fine = np.linspace(pos.x[0], pos.x[-1], 8 * DENSE)

    def monotone(trend):
        return next((fw for kind in ("cubic", "pchip")
                     if strictly_monotone((fw := Forward(pos.x, pos.v, kind, trend))(fine))), None)

    def judged(fw):
        return replace(fw, left_out_mm=leave_one_out_mm(fw, displacement_mm, voltage_v))
    trend = _trend(displacement_mm, voltage_v)
    found = [judged(fw) for fw in (monotone(None), None if trend is None else monotone(trend))
             if fw is not None]
    # plain first: it keeps a tie
    return min(found, key=lambda fw: _rms(fw.left_out_mm), default=None)


def forward_curve(displacement_mm, voltage_v, step_v: float = 0.0) -> SigmoidForward | Forward | None:
    """With fewer than :data:`SPARSE_POSITIONS` positions the spline through the position
    means, else the tanh units' average (``step_v``: the converter's step, 0 off-grid); None
    when there is no monotone one."""
    if np.unique(np.asarray(displacement_mm, float)).size < SPARSE_POSITIONS:
        return spline_curve(displacement_mm, voltage_v)
    return fit_forward(displacement_mm, voltage_v, step_v=step_v)


def invert(curve, lo: float, hi: float, v: np.ndarray, points: int = 8 * DENSE) -> np.ndarray:
    """x where the monotone ``curve`` reads ``v``, on ``points`` uniform in x over lo..hi;
    readings past the curve's ends give the ends."""
    x = np.linspace(lo, hi, points)
    f = curve(x)
    order = np.argsort(f)
    return np.interp(v, f[order], x[order])


def _sampled(fw, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(v, x) of the forward curve on n points uniform in x over its stroke."""
    x = np.linspace(*fw.stroke, n)
    return fw(x), x


def _left_out_mm(displacement_mm, voltage_v, predict) -> np.ndarray:
    """Error (mm) at each interior position of a procedure refitted without it and asked at
    the position's mean reading: ``predict(keep, mean_v) -> x``, ``keep`` a reading mask."""
    x = np.asarray(displacement_mm, dtype=float)
    pos = aggregate(x, voltage_v)
    return np.asarray([predict(x != pos.x[i], pos.v[i]) - pos.x[i] for i in range(1, pos.x.size - 1)])


def leave_one_out_mm(fw: Forward, displacement_mm, voltage_v) -> np.ndarray:
    """The spline through the other positions (on its trend refitted without the left-out
    position), inverted at the left-out position's reading."""
    x = np.asarray(displacement_mm, dtype=float)
    v = np.asarray(voltage_v, dtype=float)

    def predict(keep, mean_v):
        pos = aggregate(x[keep], v[keep])
        trend = None if fw.trend is None else _trend(x[keep], v[keep])
        return invert(fw.curve(pos.x, pos.v, trend), x.min(), x.max(), np.array([mean_v]))[0]
    return _left_out_mm(x, v, predict)


def forward_heldout(fw: SigmoidForward, displacement_mm, voltage_v) -> dict | None:
    """The averaged curve's held-out error, on the direct fit's folds (whole positions, the
    ends never held out): per fold the members refitted without it (:func:`refit`; those
    below :data:`REFIT_WEIGHT` left out) and inverted at each held-out reading.  Like the
    direct fit's, the figure includes the readings' noise; on the same readings the two
    compare point for point.  None when a fold leaves no monotone member."""
    x = np.asarray(displacement_mm, dtype=float)
    v = np.asarray(voltage_v, dtype=float)
    folds = cv_folds(v, groups=x)
    err = np.full(x.size, np.nan)
    for held in folds:
        keep = np.ones(x.size, bool)
        keep[held] = False
        curve = refit(fw, x[keep], v[keep], min_weight=REFIT_WEIGHT)
        if curve is None:
            return None
        err[held] = invert(curve, *fw.stroke, v[held]) - x[held]
    e = err[np.sort(np.concatenate(folds))]
    return {"folds": len(folds), "points": int(e.size),
            "refit": "the members' units refined from the full fit's, not grown again",
            "rms_error_mm": _rms(e), "max_error_mm": float(np.max(np.abs(e)))}


def direct_leave_one_out_mm(displacement_mm, voltage_v, terms: int, norm: str,
                            ridge: float) -> np.ndarray:
    """The same interior positions left out of the direct fit of x(v) (one candidate)."""
    x = np.asarray(displacement_mm, dtype=float)
    v = np.asarray(voltage_v, dtype=float)

    def predict(keep, mean_v):
        m = fit_lstsq(v[keep], x[keep], terms, norm=norm, ridge=ridge)
        lo, hi = sorted(m.voltage_range_v)
        return float(m.predict(np.clip([mean_v], lo, hi))[0])
    return _left_out_mm(x, v, predict)


def fit_to_forward(fw, cost, training: dict, tol: float = TEACHER_TOL) -> tuple[FlannModel, dict] | None:
    """The FLANN candidate with the fewest terms (then the cheapest) whose largest deviation
    from the inverted forward curve, between the points it was fitted to, is within
    ``tol`` times the best buildable candidate's; None when none builds."""
    v, x = _sampled(fw, DENSE)
    v_mid, x_mid = _sampled(fw, 2 * DENSE - 1)
    v_mid, x_mid = v_mid[1::2], x_mid[1::2]     # between the fitted points
    scored = []
    for norm in TEACHER_NORMS:
        for ridge in AUTO_RIDGES:
            for terms in AUTO_TERMS:
                m = fit_lstsq(v, x, terms, norm=norm, ridge=ridge, training=training)
                scored.append((float(np.max(np.abs(m.predict(v_mid) - x_mid))), terms, norm, ridge, m))
    scored.sort(key=lambda s: (s[0], s[1]))
    costs = {}

    def costed(s):
        if id(s[4]) not in costs:
            costs[id(s[4])] = cost(s[4])
        return costs[id(s[4])]

    best = next((s for s in scored if costed(s)["buildable"]), None)
    if best is None:
        return None
    near = sorted((s for s in scored if s[0] <= tol * best[0]), key=lambda s: (s[1], s[0]))
    choice = next(s for s in near if costed(s)["buildable"])
    c = costed(choice)
    return choice[4], {"teacher_max_deviation_mm": choice[0], "terms": choice[1],
                       "normalisation": choice[2], "ridge": choice[3],
                       "fixed_point": {k: c[k] for k in ("cost", "luts", "brams", "weight_bits",
                                                         "term_bits", "output_lsb_mm")}}


def inverse_fit(displacement_mm, voltage_v, direct, cost, training: dict,
                step_v: float = 0.0) -> FlannModel | None:
    """The model fitted to the inverted forward curve, or None: no forward curve, a straight
    one (without curvature there is no flattening at the ends to undo, and the FLANN would
    spend 61 terms following the curved members' 1e-4 mm wiggles where the direct fit takes
    1), no candidate that builds, or (:data:`SPARSE_POSITIONS` or more positions) none that follows
    the curve more closely than the direct fit's held-out max error.  ``direct`` is the
    direct fit's :class:`~flann.golden.train.CvResult`; ``training`` the record to extend
    (with many positions, the direct fit's own, whose held-out figures it keeps); ``step_v``
    the recording's converter step (0 off-grid)."""
    x = np.asarray(displacement_mm, dtype=float)
    positions = int(np.unique(x).size)
    fw = forward_curve(x, voltage_v, step_v)
    if fw is None or fw.straight:
        return None
    record = {k: val for k, val in training.items()
              if k not in ("traded", "best_heldout", "chosen", "fixed_point", "as_good_candidates",
                           "candidates_costed", "hardware_why")}
    record["forward_model"] = fw.describe()
    record["selected_by"] = f"{positions} positions: the FLANN fitted to the inverse of {fw.name} (x exact)"
    record["direct"] = {"terms": direct.terms, "normalisation": direct.norm, "ridge": direct.ridge,
                        "cv_heldout_rms_error_mm": direct.rms_mm,
                        "cv_heldout_max_error_mm": direct.max_mm}
    spline = isinstance(fw, Forward)    # few positions: judged by leaving each out, no fallback
    if spline:
        record["forward_spline"] = fw.kind
        mine = fw.left_out_mm
        theirs = direct_leave_one_out_mm(x, voltage_v, direct.terms, direct.norm, direct.ridge)
        record.update({
            "cv_heldout_rms_error_mm": _rms(mine),
            "cv_heldout_max_error_mm": float(np.max(np.abs(mine))) if mine.size else float("nan"),
            "leave_one_out": {"positions": int(mine.size), "rms_error_mm": _rms(mine),
                              "direct_rms_error_mm": _rms(theirs)},
        })
    fitted = fit_to_forward(fw, cost, record, TEACHER_TOL if spline else DENSE_TEACHER_TOL)
    if fitted is None:      # no candidate builds at this converter: the direct fit says why
        return None
    model, info = fitted
    if not spline and info["teacher_max_deviation_mm"] > direct.max_mm:
        return None
    model.training.update(info)
    if not spline:
        model.training["forward_model"] = {**fw.describe(), "heldout": forward_heldout(fw, x, voltage_v)}
    return model


def fit_default(displacement_mm, voltage_v, cost, training: dict | None = None,
                step_v: float = 0.0, stage=lambda text: None) -> tuple[FlannModel, CvResult, bool]:
    """What ``flann train --terms auto`` fits: the direct fit x(v) chosen by cross-validation,
    then the FLANN fitted to the forward curve's inverse where it follows the curve more
    closely (:func:`inverse_fit`).  (model, the direct fit's choice, whether the model is the
    inverse's); ``stage(text)`` is told as each of the two begins."""
    stage("the direct fit x(v): terms, normalisation and ridge by cross-validation")
    direct, choice = fit_auto(voltage_v, displacement_mm, training=training, cost=cost)
    stage("the forward curve v(x), and the FLANN fitted to its inverse")
    inverse = inverse_fit(displacement_mm, voltage_v, choice, cost, direct.training, step_v)
    return (direct, choice, False) if inverse is None else (inverse, choice, True)


__all__ = ["DENSE", "Forward", "MIN_POSITIONS", "SPARSE_POSITIONS", "direct_leave_one_out_mm",
           "fit_default", "fit_to_forward", "forward_curve", "forward_heldout", "inverse_fit", "leave_one_out_mm", "spline_curve"]
