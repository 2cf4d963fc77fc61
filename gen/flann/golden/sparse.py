"""Few calibration positions: the FLANN fitted to the inverse of an interpolated forward curve.

With a handful of positions (the seed paper's 13) the inverse x(v) is sampled far too coarsely
where the sensor's curve flattens: its slope there is steep and a fit of x on v swings
between the points.  The forward curve v(x) is the gentle one, and its positions are exact:
a cubic spline through the positions' mean readings (not-a-knot; monotone piecewise cubic
when that one is not monotone) is inverted densely over the recorded stroke, and the FLANN
candidates are fitted to that noise-free inverse.

:func:`sparse_fit` is used by ``flann train --terms auto`` instead of the direct fit when the
recording holds fewer than :data:`SPARSE_POSITIONS` distinct positions.  The error of each
procedure at interior positions left out in turn is recorded, not used to choose: it is
pessimistic (a left-out position doubles the spacing there) and blind to a direct fit that
swings *between* the positions, which is where the direct fit of few points fails.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline, PchipInterpolator

from .forward import aggregate
from .model import FlannModel
from .train import AUTO_NORMS, AUTO_RIDGES, AUTO_TERMS, fit_lstsq

SPARSE_POSITIONS = 20      # the outlier screen's lower limit: below it, no smooth fit judges noise
MIN_POSITIONS = 5          # a cubic through fewer is no better than the direct fit's candidates
DENSE = 2001               # points of the inverse the FLANN is fitted to (uniform in x)
TEACHER_TOL = 1.25         # candidates within this factor of the best buildable max deviation


@dataclass(frozen=True)
class Forward:
    """The interpolated forward curve: position means and the spline through them."""
    positions: np.ndarray
    mean_v: np.ndarray
    kind: str                 # "cubic" or "pchip"

    def curve(self, positions=None, mean_v=None):
        p = self.positions if positions is None else positions
        m = self.mean_v if mean_v is None else mean_v
        return (CubicSpline(p, m) if self.kind == "cubic" else PchipInterpolator(p, m))

    def inverse(self, n: int = DENSE) -> tuple[np.ndarray, np.ndarray]:
        """(v, x) on n points uniform in x over the recorded stroke."""
        x = np.linspace(self.positions[0], self.positions[-1], n)
        return self.curve()(x), x


def _monotone(v: np.ndarray) -> bool:
    d = np.diff(v)
    return bool(np.all(d > 0) or np.all(d < 0))


def forward_curve(displacement_mm, voltage_v) -> Forward | None:
    """The spline v(x) through the position means, or None (too few positions, or no
    monotone curve through them: the readings fold back or sit within noise of each other)."""
    pos = aggregate(displacement_mm, voltage_v)
    if pos.x.size < MIN_POSITIONS or not _monotone(pos.v):
        return None
    fine = np.linspace(pos.x[0], pos.x[-1], 8 * DENSE)
    for kind in ("cubic", "pchip"):
        fw = Forward(pos.x, pos.v, kind)
        if _monotone(fw.curve()(fine)):
            return fw
    return None


def _invert(curve, lo: float, hi: float, v: np.ndarray) -> np.ndarray:
    x = np.linspace(lo, hi, 8 * DENSE)
    f = curve(x)
    order = np.argsort(f)
    return np.interp(v, f[order], x[order])


def leave_one_out_mm(fw: Forward) -> np.ndarray:
    """Error (mm) at each interior position of the procedure refitted without it: the
    spline through the other positions, inverted at the position's mean reading."""
    errs = []
    for i in range(1, fw.positions.size - 1):
        keep = np.arange(fw.positions.size) != i
        curve = fw.curve(fw.positions[keep], fw.mean_v[keep])
        errs.append(_invert(curve, fw.positions[0], fw.positions[-1], fw.mean_v[i:i + 1])[0]
                    - fw.positions[i])
    return np.asarray(errs)


def direct_leave_one_out_mm(fw: Forward, displacement_mm, voltage_v, terms: int, norm: str,
                            ridge: float) -> np.ndarray:
    """The same interior positions left out of the direct fit of x(v) (one candidate)."""
    x = np.asarray(displacement_mm, dtype=float)
    v = np.asarray(voltage_v, dtype=float)
    errs = []
    for i in range(1, fw.positions.size - 1):
        keep = x != fw.positions[i]
        m = fit_lstsq(v[keep], x[keep], terms, norm=norm, ridge=ridge)
        lo, hi = sorted(m.voltage_range_v)
        errs.append(float(m.predict(np.clip([fw.mean_v[i]], lo, hi))[0]) - fw.positions[i])
    return np.asarray(errs)


def _rms(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(e))))


def fit_to_forward(fw: Forward, cost, training: dict) -> tuple[FlannModel, dict] | None:
    """The FLANN candidate with the fewest terms (then the cheapest) whose largest deviation
    from the inverted spline, between the points it was fitted to, is within
    ``TEACHER_TOL`` of the best buildable candidate's; None when none builds."""
    v, x = fw.inverse()
    v_mid, x_mid = fw.inverse(2 * DENSE - 1)
    v_mid, x_mid = v_mid[1::2], x_mid[1::2]     # between the fitted points
    scored = []
    for norm in AUTO_NORMS:
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
    near = sorted((s for s in scored if s[0] <= TEACHER_TOL * best[0]), key=lambda s: (s[1], s[0]))
    choice = next(s for s in near if costed(s)["buildable"])
    c = costed(choice)
    return choice[4], {"teacher_max_deviation_mm": choice[0], "terms": choice[1],
                       "normalisation": choice[2], "ridge": choice[3],
                       "fixed_point": {k: c[k] for k in ("cost", "luts", "brams", "weight_bits",
                                                         "term_bits", "output_lsb_mm")}}


def sparse_fit(displacement_mm, voltage_v, direct, cost, training: dict) -> FlannModel | None:
    """The model fitted to the inverted forward spline, or None when the recording has
    :data:`SPARSE_POSITIONS` or more positions, no monotone spline through them, or no
    candidate that builds.  The record gives the left-out error of the procedure and of the
    direct fit's candidate ``direct`` (a :class:`~flann.golden.train.CvResult`), each
    interior position left out in turn (mm)."""
    x = np.asarray(displacement_mm, dtype=float)
    if np.unique(x).size >= SPARSE_POSITIONS:
        return None
    fw = forward_curve(x, voltage_v)
    if fw is None:
        return None
    mine = leave_one_out_mm(fw)
    theirs = direct_leave_one_out_mm(fw, x, voltage_v, direct.terms, direct.norm, direct.ridge)
    record = dict(training)
    record.update({
        "selected_by": f"{fw.positions.size} positions: the FLANN fitted to the inverse of a "
                       f"{'cubic spline' if fw.kind == 'cubic' else 'monotone cubic'} through their "
                       "mean readings (x exact)",
        "cv_heldout_rms_error_mm": _rms(mine),
        "cv_heldout_max_error_mm": float(np.max(np.abs(mine))),
        "forward_spline": fw.kind,
        "leave_one_out": {"positions": int(mine.size), "rms_error_mm": _rms(mine),
                          "direct_rms_error_mm": _rms(theirs),
                          "direct": {"terms": direct.terms, "normalisation": direct.norm,
                                     "ridge": direct.ridge}},
    })
    fitted = fit_to_forward(fw, cost, record)
    if fitted is None:      # no candidate builds at this converter: the direct fit says why
        return None
    model, info = fitted
    model.training.update(info)
    return model


__all__ = ["DENSE", "Forward", "MIN_POSITIONS", "SPARSE_POSITIONS", "direct_leave_one_out_mm",
           "fit_to_forward", "forward_curve", "leave_one_out_mm", "sparse_fit"]
