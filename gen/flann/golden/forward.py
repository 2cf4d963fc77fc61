"""The forward curve v(x), fitted where the noise is, to find what does not belong to it.

A calibration steps the actuator to known positions (x exact) and reads the sensor (v
noisy).  A smooth model of v(x) chosen by cross-validation over held-out positions says
what each reading should have been; a reading far from it (in robust noise units) is a
glitch, not data.  ``flann train --terms auto`` leaves such readings out
(:func:`robust_forward`); the diagnosis has its own, physics-based, look at them.

* :func:`aggregate` -- readings at one position (repeats: any number of sweeps, either
  direction) become one weighted mean: for a least-squares fit that is exact.
* :class:`Smoother` -- two linear smoothers of v(x): a Chebyshev polynomial of degree d, and
  a penalised cubic spline (P-spline, third-difference penalty lambda).  Neither knows any
  sensor's formula; cross-validation picks the family member (the simplest as good as the
  best, by paired differences).
* :func:`robust_forward` -- the fit with gross outliers (held-out residual > ``OUTLIER_K``
  robust noise units, from the chosen fit and from the best fit of the other family: the end
  of the stroke, where one family's held-out prediction swings, is not a glitch) left out,
  and the noise: from repeated readings when there are
  enough (:func:`flann.recordings.checks.repeat_noise_v`), else from the residuals.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import RecordingsError
from ..recordings.checks import MIN_REPEAT_PAIRS, repeat_noise_v

FORWARD_FOLDS = 10
# a simpler forward fit is taken when its held-out error exceeds the best's by at most this
# many paired standard errors
FORWARD_PAIRED_Z = 1.0
MAX_POLY_DEGREE = 30
SPLINE_LAMBDAS = tuple(10.0 ** e for e in np.arange(-8.0, 8.01, 0.5))
MAX_SPLINE_SEGMENTS = 80
# a reading is a gross outlier when its held-out residual exceeds this many robust noise
# units: Gaussian noise reaches 5.5 sigma once in 2.5e7 readings
OUTLIER_K = 8.0
# more outliers than this share of the readings is not a glitch but a recording to look at
MAX_OUTLIER_SHARE = 0.05
MAX_OUTLIER_ROUNDS = 12


@dataclass(frozen=True)
class Positions:
    """Readings averaged per position: x (sorted, distinct), mean v, weight (count / sigma^2)."""

    x: np.ndarray
    v: np.ndarray
    w: np.ndarray
    count: np.ndarray
    index: np.ndarray  # position index of every reading


def aggregate(x, v, w=None) -> Positions:
    x = np.asarray(x, float)
    v = np.asarray(v, float)
    w = np.ones_like(v) if w is None else np.asarray(w, float)
    xu, idx = np.unique(x, return_inverse=True)
    idx = idx.ravel()
    sw = np.bincount(idx, weights=w, minlength=xu.size)
    vm = np.bincount(idx, weights=w * v, minlength=xu.size) / sw
    cnt = np.bincount(idx, minlength=xu.size)
    return Positions(xu, vm, sw, cnt, idx)


# -- the two smoothers ---------------------------------------------------------------------
@dataclass(frozen=True)
class Smoother:
    """One candidate forward model: ``kind`` 'poly' (``param`` = degree) or 'spline'
    (``param`` = lambda of the third-difference penalty, relative to the data's weight)."""

    kind: str
    param: float
    lo: float
    hi: float
    segments: int = 0

    def basis(self, x) -> np.ndarray:
        t = (2.0 * (np.asarray(x, float) - self.lo) / (self.hi - self.lo)) - 1.0
        t = np.clip(t, -1.0, 1.0)
        if self.kind == "poly":
            return np.polynomial.chebyshev.chebvander(t, int(self.param))
        knots = _knots(self.segments)
        from scipy.interpolate import BSpline  # slow to import: only where fitted
        return BSpline.design_matrix(t, knots, 3).toarray()

    def penalty(self) -> np.ndarray | None:
        if self.kind == "poly":
            return None
        return _penalty(self.segments + 3)[0]

    def solve(self, pos: Positions, keep=None, basis: np.ndarray | None = None) -> np.ndarray:
        """Coefficients fitted to the positions (``keep``: a mask of positions used;
        ``basis``: :meth:`basis` at those positions, when the caller has it)."""
        k = np.ones(pos.x.size, bool) if keep is None else keep
        B = self.basis(pos.x[k]) if basis is None else basis
        w = pos.w[k]
        sw = np.sqrt(w)
        A = B * sw[:, None]
        y = pos.v[k] * sw
        P = self.penalty()
        if P is not None:
            scale = float(np.sum(w)) / max(1, int(k.sum()))
            L = _penalty(self.segments + 3)[1]
            A = np.vstack([A, math.sqrt(self.param * scale) * L])
            y = np.concatenate([y, np.zeros(P.shape[0])])
        coef, *_ = np.linalg.lstsq(A, y, rcond=None)
        return coef

    def predict(self, coef, x) -> np.ndarray:
        return self.basis(x) @ coef

    def dof(self, pos: Positions) -> float:
        """Effective degrees of freedom (trace of the hat matrix) on these positions."""
        B = self.basis(pos.x)
        G = B.T @ (B * pos.w[:, None])
        P = self.penalty()
        if P is None:
            return float(B.shape[1])
        scale = float(np.sum(pos.w)) / pos.x.size
        M = G + self.param * scale * (P + 1e-12 * np.eye(P.shape[0]))
        return float(np.trace(np.linalg.solve(M, G)))


_PENALTIES: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def _penalty(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The third-difference penalty on n spline coefficients and its Cholesky factor
    (transposed, of the penalty plus 1e-12), made once per n: every fold's fit of every
    candidate uses them."""
    hit = _PENALTIES.get(n)
    if hit is None:
        D = np.diff(np.eye(n), 3, axis=0)
        P = D.T @ D
        L = np.linalg.cholesky(P + 1e-12 * np.eye(P.shape[0])).T
        P.setflags(write=False)
        L.setflags(write=False)
        hit = _PENALTIES[n] = (P, L)
    return hit


def _knots(segments: int) -> np.ndarray:
    inner = np.linspace(-1.0, 1.0, segments + 1)
    return np.concatenate([[-1.0] * 3, inner, [1.0] * 3])


def candidates(pos: Positions) -> list[Smoother]:
    lo, hi = float(pos.x[0]), float(pos.x[-1])
    n = pos.x.size
    out = [Smoother("poly", d, lo, hi) for d in range(1, min(MAX_POLY_DEGREE, n - 2) + 1)]
    seg = int(min(MAX_SPLINE_SEGMENTS, max(4, n - 1)))
    if n >= 6:
        out += [Smoother("spline", lam, lo, hi, seg) for lam in SPLINE_LAMBDAS]
    return out


def position_folds(n: int, k: int = FORWARD_FOLDS) -> list[np.ndarray]:
    """Interleaved folds over the inner positions (the two ends are never held out: the
    model is not used beyond the calibrated range)."""
    inner = np.arange(1, n - 1)
    k = min(k, inner.size)
    if k < 2:
        raise RecordingsError(f"{n} distinct positions: too few to cross-validate a forward fit (need 4)")
    return [inner[i::k] for i in range(k)]


def heldout_predictions(sm: Smoother, pos: Positions, folds) -> np.ndarray:
    """Each held-out position's prediction from the fit without its fold (NaN at the ends)."""
    pred = np.full(pos.x.size, np.nan)
    # a basis row depends on its own position alone: each fold's fit takes its rows of one
    # basis (least squares copies them as it needs them; the held-out product keeps predict's
    # own basis, whose memory order the product's rounding follows)
    B = sm.basis(pos.x)
    for held in folds:
        keep = np.ones(pos.x.size, bool)
        keep[held] = False
        pred[held] = _fold_prediction(sm, pos, keep, held, B)
    return pred


def _fold_prediction(sm: Smoother, pos: Positions, keep, held, B) -> np.ndarray:
    """``sm`` fitted to the kept positions (their rows of its basis ``B``), at the held ones."""
    return sm.predict(sm.solve(pos, keep, B[keep]), pos.x[held])


SPLINE_RANK_TOL = 1e-10    # R's smallest diagonal against its largest: below it, a fold is solved per candidate


def heldout_all(cands: list[Smoother], pos: Positions, folds) -> list[np.ndarray]:
    """:func:`heldout_predictions` of every candidate, one factorisation per fold and kind:
    a fold's weighted basis A (the widest candidate's: a polynomial's columns are the leading
    ones of every higher degree's, the splines share one) is reduced once to A = QR, and each
    candidate solves its small system on R (the leading block for a degree, with A's rcond;
    one SVD of the penalty over R for every lambda).  Q keeps the residual's norm, so this is
    the same least-squares solution as on A itself, to rounding."""
    preds: list = [None] * len(cands)
    by_kind: dict[str, list[int]] = {}
    for i, sm in enumerate(cands):
        by_kind.setdefault(sm.kind, []).append(i)
    held_max = max((h.size for h in folds), default=0)
    eps = np.finfo(float).eps
    for kind, idx in by_kind.items():
        widest = max((cands[i] for i in idx), key=lambda sm: sm.param if kind == "poly" else 0.0)
        B = widest.basis(pos.x)
        if pos.x.size - held_max < B.shape[1]:   # fewer rows than columns: no leading blocks
            for i in idx:
                preds[i] = heldout_predictions(cands[i], pos, folds)
            continue
        out = {i: np.full(pos.x.size, np.nan) for i in idx}
        sw = np.sqrt(pos.w)
        for held in folds:
            keep = np.ones(pos.x.size, bool)
            keep[held] = False
            n_keep = int(keep.sum())
            q, r = np.linalg.qr(B[keep] * sw[keep, None])
            qy = q.T @ (pos.v[keep] * sw[keep])
            Bh = B[held]
            diag = np.abs(np.diag(r))
            if kind == "spline" and diag.min() <= SPLINE_RANK_TOL * diag.max():
                # a B-spline with (nearly) no kept reading under it: R has no inverse, and the
                # penalty alone decides those coefficients, which each candidate's own solve does
                for i in idx:
                    out[i][held] = _fold_prediction(cands[i], pos, keep, held, B)
                continue
            if kind == "spline":
                # every lambda from one SVD (Demmler-Reinsch): with z = R c the penalised
                # problem is |z - Q'y|^2 + mu |L R^-1 z|^2, so z = V (1 + mu S^2)^-1 V' Q'y
                from scipy.linalg import solve_triangular
                L = _penalty(widest.segments + 3)[1]
                _u, sv, vt = np.linalg.svd(solve_triangular(r, L.T, trans="T").T, full_matrices=True)
                s2 = np.zeros(vt.shape[0])
                s2[:sv.size] = sv ** 2
                H = solve_triangular(r, vt.T, check_finite=False)   # R^-1 V
                H = Bh @ H
                g = vt @ qy
                scale = float(np.sum(pos.w[keep])) / max(1, n_keep)
            for i in idx:
                sm = cands[i]
                if kind == "poly":
                    m = int(sm.param) + 1
                    coef, *_ = np.linalg.lstsq(r[:m, :m], qy[:m], rcond=eps * max(n_keep, m))
                    out[i][held] = Bh[:, :m] @ coef
                else:
                    out[i][held] = H @ (g / (1.0 + sm.param * scale * s2))
        for i in idx:
            preds[i] = out[i]
    return preds


def strictly_monotone(y) -> bool:
    """Every step of ``y`` rises, or every step falls."""
    d = np.diff(y)
    return bool(np.all(d > 0) or np.all(d < 0))


def choose(pos: Positions, slope=None, folds=None, monotonic: bool = True,
           robust: bool = False, scored: list | None = None) -> tuple[Smoother, np.ndarray, float]:
    """The simplest candidate (fewest degrees of freedom) whose held-out error is as small
    as the best one's within ``FORWARD_PAIRED_Z`` paired standard errors; only candidates
    monotonic over the stroke (else there is no inverse).  The held-out error is in x units
    when ``slope`` (dv/dx at the positions) is given: an error in v costs most where the
    slope is low.  The held-out readings carry the noise, the same for every candidate, so
    the candidates are told apart by the paired difference, not by the scores' spread.
    ``robust``: the smallest median held-out error instead (a gross outlier, not yet found,
    must not decide the fit it is judged against).  ``scored``: :func:`_scored` of these
    arguments, when the caller has it.
    Returns the smoother, its held-out predictions and its score."""
    if scored is None:
        scored = _scored(pos, slope, folds, monotonic)
    if robust:
        sm, pred, e2 = scored[_robust_order(pos, scored)[0]]
        return sm, pred, float(np.median(e2))
    best = min(scored, key=lambda t: float(np.mean(t[2])))
    pool = []
    for sm, pred, e2 in scored:
        d = e2 - best[2]
        se = float(np.std(d, ddof=1) / math.sqrt(d.size)) if d.size > 1 else 0.0
        if float(np.mean(d)) <= FORWARD_PAIRED_Z * se + 1e-300:
            pool.append((sm.dof(pos), float(np.mean(e2)), sm, pred))
    dof, score, sm, pred = min(pool, key=lambda t: (t[0], t[1]))
    return sm, pred, score


def _scored(pos: Positions, slope, folds, monotonic: bool) -> list:
    """[(smoother, held-out predictions, held-out squared errors)] of every candidate
    (:func:`choose`)."""
    folds = position_folds(pos.x.size) if folds is None else folds
    held = np.concatenate(folds)
    s = np.ones(pos.x.size) if slope is None else np.abs(slope)
    cw = pos.count[held] / np.sum(pos.count[held])
    grid = np.linspace(pos.x[0], pos.x[-1], 1025)
    scored = []
    cands = [sm for sm in candidates(pos)
             # no inverse: not a calibration curve
             if not monotonic or strictly_monotone(sm.predict(sm.solve(pos), grid))]
    for sm, pred in zip(cands, heldout_all(cands, pos, folds)):
        e2 = cw * ((pos.v[held] - pred[held]) / s[held]) ** 2 * held.size
        if np.all(np.isfinite(e2)):
            scored.append((sm, pred, e2))
    if not scored:
        raise RecordingsError("no smooth forward fit is monotonic over the stroke: no inverse "
                              "exists (flann train --trim keeps the monotonic span)")
    return scored


def _robust_order(pos: Positions, scored: list) -> list[int]:
    """The indices of ``scored`` by median held-out error, then degrees of freedom, then
    place; a candidate's degrees of freedom (a solve each) only asked where medians tie."""
    med = [float(np.median(t[2])) for t in scored]
    order = sorted(range(len(scored)), key=med.__getitem__)
    out: list[int] = []
    for _m, tied in itertools.groupby(order, key=med.__getitem__):
        tied = list(tied)
        if len(tied) > 1:
            tied.sort(key=lambda i: (scored[i][0].dof(pos), i))
        out += tied
    return out


def robust_pair(pos: Positions, scored: list | None = None) -> tuple[Smoother, np.ndarray, np.ndarray | None]:
    """:func:`choose` ``robust`` (the smoother and its held-out predictions), and the held-out
    predictions of the best candidate of the other family (polynomial or spline; None when
    there is none), from one scoring.  Near the ends of the stroke a high-degree polynomial's
    held-out prediction swings where a spline's does not (and the reverse can happen): a
    reading both miss by far is a glitch, one only a single family misses is that family's.
    ``scored``: :func:`_scored` of ``pos`` (no slope, folds or monotonicity), when the caller has it."""
    if scored is None:
        scored = _scored(pos, None, None, False)
    keyed = [scored[i] for i in _robust_order(pos, scored)]
    sm, pred, _e2 = keyed[0]
    other = next((t[1] for t in keyed if t[0].kind != sm.kind), None)
    return sm, pred, other


# -- noise -----------------------------------------------------------------------------------
def noise_floor_v(v, step_v: float = 0.0) -> float:
    """The smallest noise worth stating: the converter's quantisation, or the numbers' digits."""
    v = np.asarray(v, float)
    return max(step_v / math.sqrt(12.0), 1e-7 * float(np.max(np.abs(v))), 1e-12)


# -- the robust forward fit ------------------------------------------------------------------
@dataclass
class ForwardFit:
    smoother: Smoother
    coef: np.ndarray
    positions: Positions
    noise_v: float
    noise_from: str
    outliers: list = field(default_factory=list)   # (row index, residual in noise units)
    keep: np.ndarray | None = None                  # readings used (file rows)
    heldout_score: float = math.nan

    def __call__(self, x) -> np.ndarray:
        return self.smoother.predict(self.coef, x)

    def slope(self, x) -> np.ndarray:
        return _slope(self.smoother, self.coef, np.asarray(x, float))


def _rows_by_position(keep, index) -> list[list[int]]:
    """The kept readings' rows, grouped by the position each was read at."""
    by_pos: dict[int, list[int]] = {}
    for i in np.flatnonzero(keep):
        by_pos.setdefault(int(index[i]), []).append(int(i))
    return list(by_pos.values())


def _reading_residuals(x, v, keep, pos: Positions, pred_pos, fitted_pos) -> np.ndarray:
    """Each reading's residual against what the other data say: the held-out prediction of
    its position, or (a position read several times) the median of its other readings."""
    r = np.full(x.size, np.nan)
    idx = pos.index
    ref = np.where(np.isfinite(pred_pos), pred_pos, fitted_pos)
    r[keep] = v[keep] - ref[idx[keep]]
    # several readings at one position: the others' median is the local reference
    for rows in _rows_by_position(keep, idx):
        if len(rows) >= 3:
            vv = v[rows]
            for j, i in enumerate(rows):
                r[i] = v[i] - np.median(np.delete(vv, j))
    return r


def _partners_agree(v, keep, pos: Positions, r) -> np.ndarray:
    """``r`` with each reading of a position read exactly twice judged against its partner
    where that is the smaller residual: two readings that agree are the curve, however far a
    held-out fit misses them (a sharp knee in quiet dwell means), while a glitch stays far from
    its partner too.  For judging only: the noise is the held-out residuals' (pairs of equal
    quantised readings would set it at zero)."""
    r = r.copy()
    for rows in _rows_by_position(keep, pos.index):
        if len(rows) == 2:
            a, b = rows
            d = v[a] - v[b]
            for i, di in ((a, d), (b, -d)):
                if abs(di) < abs(r[i]):
                    r[i] = di
    return r


def robust_forward(x, v, direction=None, step_v: float = 0.0,
                   max_share: float = MAX_OUTLIER_SHARE) -> ForwardFit:
    """The forward fit of v(x) chosen by cross-validation, gross outliers left out (the fit
    only says what each reading should have been: it need not be monotonic).

    Rounds: fit (choose by held-out error in v), residual of every reading against what the
    other data say, robust noise (repeats when there are enough, else the residuals' MAD),
    outliers beyond ``OUTLIER_K`` noise units out; until no new outlier.  The final choice
    is by held-out error in x (the slope of the fit converts).  Raises when more than
    ``max_share`` of the readings are outliers.
    """
    x = np.asarray(x, float)
    v = np.asarray(v, float)
    keep = np.ones(x.size, bool)
    floor = noise_floor_v(v, step_v)
    rep_sigma, pairs = repeat_noise_v(x, v, direction)
    outliers: dict[int, float] = {}
    scored = None   # the last round's scores, while its positions are still the readings kept
    for _ in range(MAX_OUTLIER_ROUNDS):
        pos = _positions(x, v, keep)
        scored = _scored(pos, None, None, False)
        sm, pred, other = robust_pair(pos, scored)
        coef = sm.solve(pos)
        fitted = sm.predict(coef, pos.x)
        indexed = _with_index(pos, x, keep)
        r = _reading_residuals(x, v, keep, indexed, pred, fitted)
        rk = r[keep]
        resid_sigma = float(1.4826 * np.median(np.abs(rk - np.median(rk))))
        if pairs >= MIN_REPEAT_PAIRS:
            sigma, source = max(rep_sigma, floor), f"{pairs} repeated readings"
            # held-out residuals also carry the fit's own error: never judge below their scale
            judge = max(sigma, resid_sigma)
        else:
            sigma, source = max(resid_sigma, floor), "held-out residuals (no repeats)"
            judge = sigma
        # the largest first: a gross outlier also pulls its neighbours' held-out predictions
        r = _partners_agree(v, keep, indexed, r)
        ar = np.abs(np.nan_to_num(r))
        limit = max(OUTLIER_K * judge, 0.5 * float(np.max(ar[keep])))
        if other is not None and np.any(keep & (ar > OUTLIER_K * judge)):
            # a candidate is confirmed by the other family's held-out fit too (the noise
            # stays the chosen fit's: the smaller of two residuals would understate it)
            r2 = _partners_agree(v, keep, indexed, _reading_residuals(x, v, keep, indexed, other, fitted))
            r = np.where(np.abs(np.nan_to_num(r2)) < ar, r2, r)
            ar = np.abs(np.nan_to_num(r))
        new = _largest_apart(x, keep & (ar > limit), ar)
        if not new.any():
            break
        for i in np.flatnonzero(new):
            outliers[int(i)] = float(abs(r[i]))   # volts; in noise units once the noise is known
        keep &= ~new
        scored = None
        if (~keep).sum() > max_share * x.size:
            break
    outliers = {i: r_v / sigma for i, r_v in outliers.items()}
    share = float((~keep).sum()) / x.size
    if share > max_share:
        worst = max(outliers, key=outliers.get)
        raise OutlierShareError(worst, outliers[worst], int((~keep).sum()), x.size, sigma)
    pos = _with_index(_positions(x, v, keep), x, keep)
    # without outliers found in the last round, the final choice scores what that round did
    sm, _pred, score = choose(pos, monotonic=False, scored=scored)
    coef = sm.solve(pos)
    return ForwardFit(sm, coef, pos, sigma, source, sorted(outliers.items()), keep, score)


NEIGHBOUR_CANDIDATES = 4


def _largest_apart(x, new, ar) -> np.ndarray:
    """Of the candidate outliers ``new``, those larger than every candidate at a neighbouring
    position: a gross outlier pulls its neighbours' held-out predictions by as much as half its
    own size, so they wait for the next round, judged without it."""
    if new.sum() > NEIGHBOUR_CANDIDATES:   # many at once: a bad stretch, not one reading's pull
        return new
    xs = np.unique(x)
    rank = np.searchsorted(xs, x)
    out = np.zeros_like(new)
    taken: set[int] = set()
    for i in sorted(np.flatnonzero(new), key=lambda i: -ar[i]):
        if taken & {int(rank[i]) - 1, int(rank[i]) + 1}:
            continue
        taken.add(int(rank[i]))
        out[i] = True
    return out


class OutlierShareError(RecordingsError):
    """More outliers than ``MAX_OUTLIER_SHARE``: ``row`` is the worst, ``units`` its size."""

    def __init__(self, row, units, n_out, n, sigma):
        self.row, self.units, self.n_out, self.n, self.sigma = row, units, n_out, n, sigma
        super().__init__(f"{n_out} of {n} readings are gross outliers")


def _slope(sm: Smoother, coef, x) -> np.ndarray:
    h = 1e-4 * (sm.hi - sm.lo)
    a, b = np.clip(x - h, sm.lo, sm.hi), np.clip(x + h, sm.lo, sm.hi)
    return (sm.predict(coef, b) - sm.predict(coef, a)) / (b - a)


def _positions(x, v, keep) -> Positions:
    return aggregate(x[keep], v[keep])


def _with_index(pos: Positions, x, keep) -> Positions:
    """``pos`` with ``index`` over every reading (rows left out map to their position too,
    or -1 when their position is gone)."""
    idx = np.searchsorted(pos.x, x)
    idx = np.clip(idx, 0, pos.x.size - 1)
    idx = np.where(pos.x[idx] == x, idx, -1)
    return Positions(pos.x, pos.v, pos.w, pos.count, idx)


@dataclass(frozen=True)
class Screen:
    """What :func:`screen_outliers` found: the readings kept, the outliers (row, noise units),
    the noise and where it came from, the positions used."""

    keep: np.ndarray
    outliers: tuple
    noise_v: float
    noise_from: str
    positions: int


MAX_SCREEN_POSITIONS = 5000   # a logger's continuous positions: the screen is skipped
# fewer positions than this: a smooth fit's held-out error near the ends is not noise, and a
# sound reading there would be called an outlier (13 positions of a sharp S-curve: 2 of 13)
MIN_SCREEN_POSITIONS = 20


def screens(x) -> bool:
    """Whether :func:`screen_outliers` judges a recording at positions ``x``: enough distinct
    positions for a smooth fit, not a logger's continuous ones."""
    npos = np.unique(np.asarray(x, float)).size
    return MIN_SCREEN_POSITIONS <= npos <= MAX_SCREEN_POSITIONS


def screen_outliers(x, v, direction=None, step_v: float = 0.0,
                    max_share: float = MAX_OUTLIER_SHARE) -> Screen | None:
    """Gross outliers against the cross-validated forward fit (:func:`robust_forward`);
    None when the recording has too few or too many distinct positions to judge them this way.
    Raises :class:`OutlierShareError` above ``max_share``."""
    if not screens(x):
        return None
    ff = robust_forward(x, v, direction, step_v, max_share)
    return Screen(ff.keep, tuple(ff.outliers), ff.noise_v, ff.noise_from, int(ff.positions.x.size))
