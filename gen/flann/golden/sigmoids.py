"""The forward curve v(x) as a small sum of tanh units, averaged over their number.

The calibration positions are exact and the readings noisy, so the curve worth estimating is
v(x), not x(v).  A displacement sensor's v(x) is steep near its null and flattens toward the
ends of its stroke; a few saturating units carry that shape with few parameters, where a
generic smoother (polynomial, spline) needs many and is loose at the ends, which is where
the inverse's max error sits:

    v(x) = c [+ d x] + sum_k a_k tanh((x - b_k) / s_k),   k = 1..K

(a one-hidden-layer network in x; no sensor's formula).  The linear parameters (c, d, a_k)
are solved exactly for every trial of the others (variable projection), the units are grown
one at a time from the previous fit (up to six; more only while the closest member misses the
position means by more than the readings' repeat scatter allows), and every K with and
without the linear term (and the straight line, K = 0) is kept when its curve is monotone
over the stroke, together with the other local optima within 5 % of its residual: which of
near-equal optima the solver reaches turns on rounding, and they part at the ends.  Their
curves are averaged with Akaike weights: choosing one K by a held-out score is a noisy
choice (the score is set by the interior of the stroke, the max error by its ends),
averaging is not.

A differential sensor (an LVDT's two secondaries in opposition) is odd about its null, up
to a gain that differs between the two halves of the stroke (its datasheet's "symmetry").
So a second kind of member shares one centre h, the null, between its units and scales
each half by its own gain:

    v(x) = c + (1 + g sgn(x - h)) (d (x - h) + sum_k a_k tanh((x - h) / s_k))

Each end of the stroke is then tied to the other half's readings, not to its own few, which
is where the free units' variance sat.  A third kind, also odd about a null, has one width s
and the unit's derivatives in log s, (1 + g sgn z) u^j f^(j)(u), u = (x - h) / s, j = 0..J:
a spread of widths at one parameter a column, of tanh units or of algebraic ones,
f(u) = u / sqrt(1 + u^2), whose tail falls off as the axial field of a coil's end does, not
exponentially.  All kinds are averaged together: a sensor that is not odd about a null gives
its odd members little weight, one whose ends are not algebraic its algebraic ones.

:func:`fit_forward` returns a :class:`SigmoidForward`, a curve over its stroke that
:func:`flann.golden.inverse.fit_to_forward` inverts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .forward import aggregate, noise_floor_v, strictly_monotone

MAX_UNITS = 6
# Past MAX_UNITS units are grown one at a time, up to MORE_UNITS, only while the closest member
# misses the position means by more than the readings' own repeat scatter allows (an F test at
# MISFIT_P): a knee too sharp for six units (on four sweeps of a 16-bit sensor, 4.6 times the
# scatter, the inverse 7.3 times the oracle's error; 1.4 with eight).  Where six units reach the
# scatter, more only spread the average's weight over curves that follow noise.
MORE_UNITS = 10
MISFIT_P = 1e-4
MIN_POSITIONS = 6           # the smallest model (one unit and an offset) has 3 parameters
LOG_WIDTH = (np.log(0.02), np.log(5.0))     # unit widths, in halves of the stroke
CENTRE = (-1.5, 1.5)                        # unit centres, in halves of the stroke
NULL = (-0.95, 0.95)                        # an odd member's null, in halves of the stroke
GAIN_STEP = (-0.3, 0.3)                     # an odd member's gain step between the halves
GRID_CENTRES = np.linspace(-1.0, 1.0, 9)
GRID_WIDTHS = np.log([0.1, 0.4, 1.2])
RANDOM_STARTS = 6
REFINED = 6                 # starting points refined per K (the best by their first residual)
NEAR_BEST = 0.05            # local optima within 5 % of the best residual are members too
SPREAD_DERIVATIVES = 4      # an odd member with one width carries up to this many derivatives
# A fit stops once its residual has fallen by less than STALL_RTOL over the last STALL_EVALS
# evaluations.  The fits that crawl on are units narrower than the spacing of the positions, a
# step between two of them sharpening toward the narrowest width: the residual's slope in the
# width vanishes exponentially, and the solver gained mostly 1e-3 of the residual (at most a
# tenth) in a further 100-300 evaluations, half of all it did.  The rule also ends a few fits on
# a plateau a later step would have left (on 41 positions 11 of 932 fits more than 1 % above
# where the solver would have ended, 2 more than 5 %); the average's figures on the recordings
# tried stayed within 3 % or improved, but for a clipped sensor's (a quarter worse at its max).
STALL_EVALS = 5
STALL_RTOL = 1e-4
RANK_RTOL = 1e-10           # a basis whose QR diagonal spans more than this is near rank deficient
CHECK_POINTS = 20001        # monotonicity checked on this many points over the stroke
MAX_GROUPS = 1000           # a logger's continuous positions are averaged in this many bins of x
_CHECK = np.linspace(-1.0, 1.0, CHECK_POINTS)


def _jacobian(shape, nl, x, sw, linear, q, beta) -> np.ndarray:
    """d(weighted residual)/d(nonlinear parameters) by Kaufman's variable-projection
    approximation: each column of the shape's ``derivative`` (the curve's, at the linear
    parameters ``beta``), weighted, projected orthogonally to the weighted basis, whose
    orthonormal columns are ``q``."""
    d = shape.derivative(nl, x, linear, beta) * sw[:, None]
    return d - q @ (q.T @ d)


class _Free:
    """Units with their own centres: nl = (centre, log width) per unit."""

    name = "free"

    @staticmethod
    def units(nl: np.ndarray) -> int:
        return nl.size // 2

    @staticmethod
    def basis(nl: np.ndarray, x: np.ndarray, linear: bool) -> np.ndarray:
        cols = [np.ones_like(x)] + ([x] if linear else [])
        for b, ls in nl.reshape(-1, 2):
            cols.append(np.tanh((x - b) * np.exp(-ls)))
        return np.column_stack(cols)

    @staticmethod
    def bounds(k: int):
        return np.tile([CENTRE[0], LOG_WIDTH[0]], k), np.tile([CENTRE[1], LOG_WIDTH[1]], k)

    @staticmethod
    def derivative(nl, x, linear, beta):
        """d(curve)/d(centres, log widths)."""
        first = 2 if linear else 1
        cols = []
        for k, (b, ls) in enumerate(nl.reshape(-1, 2)):
            inv_w = np.exp(-ls)
            t = np.tanh((x - b) * inv_w)
            d = -(1.0 - t * t) * inv_w * beta[first + k]
            cols += [d, d * (x - b)]
        return np.column_stack(cols)


class _Odd:
    """Units sharing one centre, the null h, each half of the stroke scaled by its own gain:
    nl = (h, gain step g, log width per unit)."""

    name = "odd about a null"

    @staticmethod
    def units(nl: np.ndarray) -> int:
        return nl.size - 2

    @staticmethod
    def basis(nl: np.ndarray, x: np.ndarray, linear: bool) -> np.ndarray:
        z = x - nl[0]
        gain = 1.0 + nl[1] * np.sign(z)
        cols = [np.ones_like(x)] + ([z * gain] if linear else [])
        for ls in nl[2:]:
            cols.append(np.tanh(z * np.exp(-ls)) * gain)
        return np.column_stack(cols)

    @staticmethod
    def bounds(k: int):
        return (np.array([NULL[0], GAIN_STEP[0]] + [LOG_WIDTH[0]] * k),
                np.array([NULL[1], GAIN_STEP[1]] + [LOG_WIDTH[1]] * k))

    @staticmethod
    def derivative(nl, x, linear, beta):
        """d(curve)/d(null, gain step, log widths): the null and the gain step move every
        column but the offset."""
        z = x - nl[0]
        side = np.sign(z)
        gain = 1.0 + nl[1] * side
        d_null = np.zeros_like(x)
        d_gain = np.zeros_like(x)
        widths = []
        first = 1
        if linear:
            d_null -= gain * beta[1]
            d_gain += np.abs(z) * beta[1]
            first = 2
        for k, ls in enumerate(nl[2:]):
            inv_w = np.exp(-ls)
            t = np.tanh(z * inv_w)
            dt = (1.0 - t * t) * inv_w * gain * beta[first + k]
            d_null -= dt
            d_gain += t * side * beta[first + k]
            widths.append(-dt * z)
        return np.column_stack([d_null, d_gain] + widths)


def _polynomials(ps) -> list:
    """What calling each of ``ps`` (numpy Polynomials) at an array does, for :func:`_at`."""
    return [(*np.polynomial.polyutils.mapparms(p.domain, p.window), p.coef) for p in ps]


def _at(x: np.ndarray, poly) -> np.ndarray:
    """``Polynomial.__call__`` at an array, the same operations in the same order (map the
    domain to the window, then Horner as polyval) without its per-call checks: the fits
    call the units' polynomials some hundred thousand times."""
    off, scl, c = poly
    x = off + scl * x
    c0 = c[-1] + x * 0
    for i in range(2, len(c) + 1):
        c0 = c[-i] + c0 * x
    return c0


class _TanhUnit:
    """tanh(u) and its derivatives, as polynomials in t = tanh(u): an exponential tail."""

    name = "tanh"

    def __init__(self, n: int):
        self._p = [np.polynomial.Polynomial([0.0, 1.0])]
        for _ in range(n):
            self._p.append(np.polynomial.Polynomial([1.0, 0.0, -1.0]) * self._p[-1].deriv())
        self._fast = _polynomials(self._p)

    def __call__(self, u: np.ndarray, n: int | None = None) -> list[np.ndarray]:
        """The unit and its first n derivatives at u (all it was made with by default)."""
        t = np.tanh(u)
        return [_at(t, f) for f in self._fast[:None if n is None else n + 1]]


class _AlgebraicUnit:
    """u / sqrt(1 + u^2) and its derivatives, P_j(u) r^(2j+1) with r = (1 + u^2)^(-1/2): an
    algebraic tail, the axial field of a coil's end (a disc's solid angle), where tanh's
    falls off exponentially."""

    name = "algebraic"

    def __init__(self, n: int):
        u = np.polynomial.Polynomial([0.0, 1.0])
        self._p = [u]
        for j in range(n):      # (P r^m)' = (P' (1 + u^2) - m u P) r^(m+2)
            self._p.append(self._p[-1].deriv() * (1 + u * u) - (2 * j + 1) * u * self._p[-1])
        self._fast = _polynomials(self._p)

    def __call__(self, u: np.ndarray, n: int | None = None) -> list[np.ndarray]:
        r = 1.0 / np.sqrt(1.0 + u * u)
        return [_at(u, f) * r ** (2 * j + 1) for j, f in enumerate(self._fast[:None if n is None else n + 1])]


class _OddSpread:
    """Odd about a null like :class:`_Odd`, with one width s and the unit's derivatives in
    log s: nl = (h, gain step g, log s), columns (1 + g sgn z) u^j f^(j)(u), u = z / s,
    j = 0..J, f a :class:`_TanhUnit` or an :class:`_AlgebraicUnit`.  A spread of widths
    about s, one linear parameter per column where each width of :class:`_Odd` costs two:
    the odd members settle on that by themselves, as widths equal to three digits whose
    coefficients of 1e6-1e8 cancel, which is fragile."""

    def __init__(self, derivatives: int, unit=_TanhUnit):
        self.derivatives = derivatives
        self.unit = unit.name
        self.name = f"odd about a null, one width of {unit.name} units and {derivatives} derivative(s) in it"
        self._unit = unit(derivatives + 1)

    def units(self, nl: np.ndarray) -> int:
        return self.derivatives + 1

    def _columns(self, nl, x, derivatives: bool = True):
        """(z, gain, u, columns, their derivatives in u (None unless ``derivatives``))"""
        z = x - nl[0]
        gain = 1.0 + nl[1] * np.sign(z)
        u = z * np.exp(-nl[2])
        # the columns' derivatives take one derivative of the unit more than the columns
        p = self._unit(u, self.derivatives + (1 if derivatives else 0))
        powers = [u ** j for j in range(self.derivatives + 1)]    # each power once
        cols = [powers[j] * p[j] for j in range(self.derivatives + 1)]
        d_cols = None if not derivatives else [
            (j * powers[j - 1] * p[j] if j else 0.0) + powers[j] * p[j + 1]
            for j in range(self.derivatives + 1)]
        return z, gain, u, cols, d_cols

    def basis(self, nl: np.ndarray, x: np.ndarray, linear: bool) -> np.ndarray:
        z, gain, _u, cols, _d = self._columns(nl, x, derivatives=False)
        return np.column_stack([np.ones_like(x)] + ([z * gain] if linear else [])
                               + [c * gain for c in cols])

    def bounds(self, k: int):
        return (np.array([NULL[0], GAIN_STEP[0], LOG_WIDTH[0]]),
                np.array([NULL[1], GAIN_STEP[1], LOG_WIDTH[1]]))

    def derivative(self, nl, x, linear, beta):
        """d(curve)/d(null, gain step, log width)."""
        z, gain, u, cols, d_cols = self._columns(nl, x)
        side = np.sign(z)
        first = 2 if linear else 1
        shape = sum(b * c for b, c in zip(beta[first:], cols))
        slope = sum(b * d for b, d in zip(beta[first:], d_cols))
        d_null = -slope * gain * np.exp(-nl[2])
        d_gain = shape * side
        if linear:
            d_null = d_null - gain * beta[1]
            d_gain = d_gain + np.abs(z) * beta[1]
        return np.column_stack([d_null, d_gain, -slope * gain * u])


# no derivative: one tanh unit is an _Odd member already, one algebraic unit is not
SPREADS = (tuple(_OddSpread(j) for j in range(1, SPREAD_DERIVATIVES + 1))
           + tuple(_OddSpread(j, _AlgebraicUnit) for j in range(SPREAD_DERIVATIVES + 1)))


def _linear(nl, x, y, sw, linear, shape=_Free):
    """(weighted basis, linear parameters, residuals) for these units: the linear parameters
    by weighted least squares."""
    B = shape.basis(nl, x, linear) * sw[:, None]
    beta = np.linalg.lstsq(B, y * sw, rcond=None)[0]
    return B, beta, B @ beta - y * sw


def _projected(nl, x, y, sw, linear, shape):
    """(orthonormal columns of the weighted basis, linear parameters, residuals): one QR
    serves the linear parameters and the Jacobian's projection.  A basis near rank
    deficiency (units that coincide, or saturate to the offset) takes the least squares of
    :func:`_linear`, which drops the directions it cannot resolve."""
    B = shape.basis(nl, x, linear) * sw[:, None]
    q, r = np.linalg.qr(B)
    diag = np.abs(np.diag(r))
    if diag.min() <= RANK_RTOL * diag.max():
        beta = np.linalg.lstsq(B, y * sw, rcond=None)[0]
        return q, beta, B @ beta - y * sw
    qy = q.T @ (y * sw)
    return q, np.linalg.solve(r, qy), q @ qy - y * sw


@dataclass(frozen=True)
class Units:
    """One fitted member: K units of one shape (:class:`_Free`, :class:`_Odd` or an
    :class:`_OddSpread`), the linear term or not, and the linear parameters, all in
    normalised x (stroke to [-1, 1]) and v (range to [-1, 1])."""

    nl: np.ndarray
    beta: np.ndarray
    linear: bool
    sse: float
    shape: object = _Free      # _Free, _Odd or an _OddSpread

    @property
    def units(self) -> int:
        return self.shape.units(self.nl)

    @property
    def params(self) -> int:
        return self.nl.size + self.beta.size

    def __call__(self, xn: np.ndarray) -> np.ndarray:
        return self.shape.basis(self.nl, xn, self.linear) @ self.beta


class _Stalled(Exception):
    """The residual has stopped falling (:data:`STALL_EVALS`, :data:`STALL_RTOL`)."""


def _refine(nl0, x, y, sw, linear, shape=_Free) -> Units:
    lo, hi = shape.bounds(shape.units(nl0))
    nl0 = np.clip(nl0, lo + 1e-9, hi - 1e-9)
    last: dict = {}
    best = [np.inf, nl0]        # the lowest residual so far and where: the solver's iterate
    trail: list = []            # the lowest residual after each evaluation

    def solved(nl):     # the solver asks for the Jacobian where it just took the residuals
        key = nl.tobytes()
        if key not in last:
            last.clear()
            last[key] = _projected(nl, x, y, sw, linear, shape)
        return last[key]

    def residuals(nl):
        res = solved(nl)[2]
        sse = float(res @ res)
        if sse < best[0]:
            best[:] = sse, nl.copy()
        trail.append(best[0])
        if len(trail) > STALL_EVALS and trail[-STALL_EVALS - 1] - best[0] <= STALL_RTOL * best[0]:
            raise _Stalled
        return res

    from scipy.optimize import least_squares  # slow to import: only where fitted
    try:
        nl = least_squares(residuals, nl0, bounds=(lo, hi),
                           jac=lambda nl: _jacobian(shape, nl, x, sw, linear, *solved(nl)[:2]),
                           method="trf", max_nfev=300).x
    except _Stalled:
        nl = best[1]
    _q, beta, res = solved(nl)
    return Units(nl, beta, linear, float(res @ res), shape)


def _near_best(fits: list[Units]) -> list[Units]:
    """The best fit, then the other local optima within :data:`NEAR_BEST` of its residual:
    which of several near-equal optima the solver reaches turns on rounding, and where they
    part is at the ends, so the average keeps them all rather than one by chance."""
    fits = sorted(fits, key=lambda u: u.sse)
    kept = [fits[0]]
    for u in fits[1:]:
        near = u.sse <= fits[0].sse * (1 + NEAR_BEST)
        if near and all(abs(u.sse - k.sse) > 1e-6 * fits[0].sse for k in kept):  # not a repeat
            kept.append(u)
    return kept


def _path(x, y, sw, ks: range, linear: bool, rng, prev=np.zeros(0)) -> list[Units]:
    """The best fits (:func:`_near_best`) with each K in ``ks`` units, each K grown from the
    best with one unit fewer (``prev``'s units before the first)."""
    out = []
    for k in ks:
        starts = [np.concatenate([prev, [b, ls]]) for b in GRID_CENTRES for ls in GRID_WIDTHS]
        starts += [np.column_stack([rng.uniform(-1, 1, k), rng.uniform(np.log(0.05), np.log(2.0), k)]).ravel()
                   for _ in range(RANDOM_STARTS)]
        lo, hi = _Free.bounds(k)

        def first(s):
            r = _linear(np.clip(s, lo, hi), x, y, sw, linear)[2]
            return float(r @ r)
        best_starts = sorted(starts, key=first)[:REFINED]
        kept = _near_best([_refine(s, x, y, sw, linear) for s in best_starts])
        out += kept
        prev = kept[0].nl
    return out


def _null_starts(null: float) -> list[np.ndarray]:
    """(null, gain step, log width) to start a member odd about a null from."""
    return [np.array([null, g, ls]) for g in (-0.03, 0.0, 0.03) for ls in GRID_WIDTHS]


def _odd_path(x, y, sw, ks: range, linear: bool, null: float, prev=None) -> list[Units]:
    """The best odd members (:func:`_near_best`) with each K in ``ks`` units about a null
    first placed at ``null``, each K grown from the best with one unit fewer (``prev``'s
    units before the first)."""
    out = []
    for k in ks:
        if prev is None:
            starts = _null_starts(null)
        else:
            starts = [np.concatenate([prev, [ls]]) for ls in GRID_WIDTHS]
        kept = _near_best([_refine(s, x, y, sw, linear, _Odd) for s in starts])
        out += kept
        prev = kept[0].nl
    return out


def _spread_members(x, y, sw, kmax: int, linear: bool, null: float) -> list[Units]:
    """The best :class:`_OddSpread` members (:func:`_near_best`) with at most kmax - 1
    derivatives (and :data:`SPREAD_DERIVATIVES`), their null first placed at ``null``."""
    starts = _null_starts(null)
    return [u for shape in SPREADS if shape.derivatives <= kmax - 1
            for u in _near_best([_refine(s, x, y, sw, linear, shape) for s in starts])]


@dataclass(frozen=True)
class SigmoidForward:
    """The Akaike-weighted average of the monotone members, in physical units."""

    members: tuple[Units, ...]
    weights: np.ndarray
    x_lo: float
    x_hi: float
    v_mid: float
    v_half: float
    # the straight line is the best member by the Bayesian criterion: no curvature shows
    # beyond the noise (Akaike's weights spread over units that fit noise, 5-45 % on a line)
    straight: bool = False

    def _xn(self, x):
        return (np.asarray(x, float) - 0.5 * (self.x_lo + self.x_hi)) / (0.5 * (self.x_hi - self.x_lo))

    def normalised(self, xn) -> np.ndarray:
        """The curve in normalised x and v (stroke and range to [-1, 1])."""
        return sum(w * m(xn) for w, m in zip(self.weights, self.members))

    def __call__(self, x) -> np.ndarray:
        return self.v_mid + self.v_half * self.normalised(self._xn(x))

    @property
    def stroke(self) -> tuple[float, float]:
        return self.x_lo, self.x_hi

    name = "an average of tanh-unit curves v(x)"

    def describe(self) -> dict:
        top = int(np.argmax(self.weights))
        out = {"kind": "tanh units, Akaike-weighted",
               "members": [{"units": m.units, "shape": m.shape.name, "linear_term": m.linear,
                            "weight": round(float(w), 4)}
                           for m, w in zip(self.members, self.weights) if w >= 1e-4],
               "heaviest_units": self.members[top].units,
               "largest_units": max(m.units for m in self.members)}
        odd = [k for k, m in enumerate(self.members) if m.shape is not _Free]
        if odd:
            h, g = self.members[max(odd, key=lambda k: self.weights[k])].nl[:2]
            # the heaviest odd member's null and the ratio of the slopes either side of it
            out["odd_about_null"] = {
                "weight": round(float(self.weights[odd].sum()), 4),
                "null_mm": float(0.5 * (self.x_lo + self.x_hi) + h * 0.5 * (self.x_hi - self.x_lo)),
                "slope_above_over_below": round(float((1 + g) / (1 - g)), 5)}
        return out


def _groups(x: np.ndarray, v: np.ndarray):
    """(x, mean v, count, group of each reading, positions): the readings averaged per
    position (exact for least squares), or per bin of x when a logger's file has more than
    :data:`MAX_GROUPS` distinct positions (the curve is straight within a bin)."""
    pos = aggregate(x, v)
    if pos.x.size <= MAX_GROUPS:
        return pos.x, pos.v, pos.w, pos.index, pos.x.size
    edges = np.linspace(pos.x[0], pos.x[-1], MAX_GROUPS + 1)
    index = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, MAX_GROUPS - 1)
    index = np.unique(index, return_inverse=True)[1]
    count = np.bincount(index).astype(float)
    return (np.bincount(index, weights=x) / count, np.bincount(index, weights=v) / count, count,
            index, pos.x.size)


@dataclass(frozen=True)
class _Scaled:
    """The readings averaged per position, in a curve's normalised x and v."""
    xn: np.ndarray
    y: np.ndarray
    sw: np.ndarray
    within: float       # scatter about the group means: the same for every member
    positions: int
    n: int


def _scaled(x: np.ndarray, v: np.ndarray, x_lo: float, x_hi: float, v_mid: float, v_half: float) -> _Scaled:
    gx, gv, count, index, positions = _groups(x, v)
    y = (gv - v_mid) / v_half
    return _Scaled((gx - 0.5 * (x_lo + x_hi)) / (0.5 * (x_hi - x_lo)), y, np.sqrt(count),
                   float(np.sum(((v - v_mid) / v_half - y[index]) ** 2)), positions, v.size)


def _line(d: _Scaled) -> Units:
    _B, beta, res = _linear(np.zeros(0), d.xn, d.y, d.sw, True)
    return Units(np.zeros(0), beta, True, float(res @ res))


def criterion_terms(members, d: _Scaled) -> tuple[np.ndarray, np.ndarray, int]:
    """(each member's fit term, its parameters, the sample size) of an information
    criterion, fit + penalty(parameters, sample size): Akaike's is fit + 2 parameters."""
    # the positions are the sample size: repeated readings at one position share its error
    # (backlash, hysteresis, drift between sweeps), so the evidence about the curve's shape
    # grows with the positions, not the readings
    m = min(d.positions, d.n)
    # residuals below 1e-12 of the range are rounding: noise-free readings tie every member
    fit = np.array([m * np.log(max((u.sse + d.within) / d.n, 1e-24)) for u in members])
    return fit, np.array([u.params for u in members]), m


def _averaged(fitted: list[Units], d: _Scaled, geometry: tuple) -> SigmoidForward | None:
    """The Akaike-weighted average of the monotone members, or None when none is."""
    members = [u for u in fitted if strictly_monotone(u(_CHECK))]
    if not members:
        return None
    fit, params, m = criterion_terms(members, d)
    aic = fit + 2 * params
    w = np.exp(-0.5 * (aic - aic.min()))
    straight = members[int(np.argmin(fit + np.log(m) * params))].units == 0
    return SigmoidForward(tuple(members), w / w.sum(), *geometry, bool(straight))


def _misfit_p(member: Units, d: _Scaled, floor: float) -> float | None:
    """The F test's p-value that ``member`` misses the position means by no more than the
    scatter of the readings about them allows, or None without repeated readings (no scatter
    to judge by) or without the positions to spare.  Repeats that read one code show no
    scatter, yet their mean is off by the converter's quantisation (``floor``, its standard
    deviation) as much as one reading is: the scatter is taken no smaller than the floor
    times the readings a position."""
    groups = d.xn.size
    dof = groups - member.params
    if d.n <= groups or dof <= 0:
        return None
    scatter = max(d.within / (d.n - groups), floor * floor * d.n / groups)
    from scipy.stats import f as f_distribution  # slow to import: only where tested
    return float(f_distribution.sf(member.sse / dof / scatter, dof, d.n - groups))


def _misfit(fitted: list[Units], d: _Scaled, floor: float) -> bool:
    """Whether the closest member misses the position means by more than the readings'
    scatter allows (:func:`_misfit_p` below :data:`MISFIT_P`)."""
    p = _misfit_p(min(fitted, key=lambda u: u.sse), d, floor)
    return p is not None and p < MISFIT_P


def _closest(fitted: list[Units], shape, linear: bool, units: int) -> np.ndarray:
    """The nonlinear parameters of the closest member of this kind and size."""
    return min((u for u in fitted if u.shape is shape and u.linear == linear and u.units == units),
               key=lambda u: u.sse).nl


def fit_forward(displacement_mm, voltage_v, max_units: int = MAX_UNITS, more_units: int = MORE_UNITS,
                step_v: float = 0.0, spreads: bool = True) -> SigmoidForward | None:
    """The averaged forward curve, or None with fewer than :data:`MIN_POSITIONS` positions or
    no monotone member.  Units past ``max_units``, up to ``more_units``, are grown while the
    members miss the readings (:func:`_misfit`; ``step_v`` the converter's step, 0 off-grid).
    ``spreads``: whether the :data:`SPREADS` members are among them."""
    x = np.asarray(displacement_mm, float)
    v = np.asarray(voltage_v, float)
    v_mid, v_half = 0.5 * (v.max() + v.min()), 0.5 * (v.max() - v.min())
    if v_half <= 0:
        return None
    geometry = (float(x.min()), float(x.max()), v_mid, v_half)
    d = _scaled(x, v, *geometry)
    if d.xn.size < MIN_POSITIONS:
        return None
    most = max(1, (d.xn.size - 3) // 3)      # three positions a unit
    kmax = min(max_units, most)
    rng = np.random.default_rng(0)
    fitted = [_line(d)]     # no unit: a straight sensor
    fitted += [u for linear in (False, True) for u in _path(d.xn, d.y, d.sw, range(1, kmax + 1), linear, rng)]
    free = _averaged(fitted, d, geometry)
    if free is None:
        return None
    # the odd members' null starts where the free units' curve is steepest
    null = float(np.clip(_CHECK[np.argmax(np.abs(np.gradient(free.normalised(_CHECK))))], *NULL))
    fitted += [u for linear in (False, True) for u in _odd_path(d.xn, d.y, d.sw, range(1, kmax + 1), linear, null)]
    if spreads:
        fitted += [u for linear in (False, True)
                   for u in _spread_members(d.xn, d.y, d.sw, kmax, linear, null)]
    floor = noise_floor_v(v, step_v) / v_half
    for k in range(kmax + 1, min(more_units, most) + 1):
        if not _misfit(fitted, d, floor):
            break
        fitted += [u for linear in (False, True) for u in
                   _path(d.xn, d.y, d.sw, range(k, k + 1), linear, rng, _closest(fitted, _Free, linear, k - 1))
                   + _odd_path(d.xn, d.y, d.sw, range(k, k + 1), linear, null, _closest(fitted, _Odd, linear, k - 1))]
    return _averaged(fitted, d, geometry)


def refit(fw: SigmoidForward, displacement_mm, voltage_v, min_weight: float = 0.0) -> SigmoidForward | None:
    """``fw``'s members refined on other readings of the same stroke, starting from their
    fitted units, and weighted again: the procedure for its cross-validation, without
    growing the units from the grid again (ten times the cost).  Members lighter than
    ``min_weight`` in ``fw`` are left out."""
    x = np.asarray(displacement_mm, float)
    v = np.asarray(voltage_v, float)
    geometry = (fw.x_lo, fw.x_hi, fw.v_mid, fw.v_half)
    d = _scaled(x, v, *geometry)
    fitted = [_line(d) if u.units == 0 else _refine(u.nl, d.xn, d.y, d.sw, u.linear, u.shape)
              for u, w in zip(fw.members, fw.weights) if w >= min_weight]
    return _averaged(fitted, d, geometry)


__all__ = ["MAX_UNITS", "MIN_POSITIONS", "MORE_UNITS", "SigmoidForward", "Units", "criterion_terms", "fit_forward",
           "refit"]
