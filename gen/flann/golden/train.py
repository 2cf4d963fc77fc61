"""Training the FLANN inverse model: the paper's LMS, closed-form least squares, and ``auto``.

All three return a :class:`flann.golden.model.FlannModel` whose output is
``y_mm = bias + sum_i w_i phi_i(v_n)`` with ``v_n = (v - input_offset_v) / input_scale_v``.

* :func:`fit_lms` -- the paper's rule, sample by sample in file order (computed epoch-wise
  as an affine map, see :func:`lms_epochs`; :func:`lms_sequential` is the literal loop):
  ``w(k+1) = w(k) + eta * e(k) * s(k)``, ``e(k) = d(k) - y(k)``, every weight (and the bias,
  whose input is the constant 1, the paper's phi_1 = 1) starting at 1.  The mean of e(k)^2
  over each epoch (the a-priori errors seen while updating) is recorded as the epoch's MSE.
* :func:`fit_lstsq` -- minimum-norm least squares (``numpy.linalg.lstsq``), optionally with a
  ridge penalty: minimise ``mean(e^2) + ridge * |w|^2`` (the bias is not penalised).  With
  more terms than points the problem is under-determined and the minimum-norm interpolant
  is returned (the paper fits 51 and 61 terms to 13 points).
* :func:`fit_auto` -- chooses terms, normalisation and ridge by K-fold cross-validation and
  reports the held-out error (never the training error).  Of the candidates whose held-out
  mean squared error is within its uncertainty of the best buildable one's, it takes the
  cheapest by a cost the caller gives (``flann train``: the fixed-point design's cost, so the
  model is buildable and its weights small); the record says what was traded.  The
  uncertainty is that of the *difference*, point by point on the same held-out points
  (:func:`paired_se`): both candidates see the same noise, so the fold-to-fold spread of the
  MSE itself (the textbook one-standard-error rule) is far wider than what tells them apart,
  and gave a quarter to a third of the accuracy away for a cheaper datapath on the e2e
  sensor family.

Normalisation: ``"range"`` maps the data's voltage range to [-1, 1] (offset = midpoint,
scale = half span); ``"half"`` maps it to [-0.5, 0.5] (scale = span: the trigonometric terms,
periodic over 2 units of v_n, then need not join the two ends of the curve, which avoids the
Gibbs-like error near the ends); a number f in (0, 1] maps it to [-f, f] (scale = span / 2f);
``"none"`` uses raw volts (offset 0, scale 1) as the paper.
Everything here is deterministic: no random numbers, a fixed order of operations.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..errors import FlannError, RecordingsError
from .model import FlannModel, expand

PAPER_TERMS = (11, 25, 51, 61)
# v_n's half range under each named normalisation; a number f in (0, 1] is one too (the range
# -> [-f, f]) and 'none' is raw volts
HALF_RANGES = {"range": 1.0, "half": 0.5}
NORMALISATIONS = (*HALF_RANGES, "none")
MIN_POINTS = 3  # a line and one curvature point: fewer cannot be fitted at all
AUTO_TERMS = (1, 3, 5, 7, 9, 11, 13, 15, 19, 25, 31, 41, 51, 61)
# 'range' puts one full period of the fundamental over the recorded range (the linear term
# carries the trend): a well-conditioned, near-orthogonal expansion.  'half' fits the ends
# more freely but its terms are nearly collinear; its candidates compete on held-out error
# and fixed-point cost.  Raw volts ('none') alias many periods over the range: never chosen.
AUTO_NORMS = ("range", "half")
AUTO_RIDGES = (0.0, 1e-14, 1e-12, 1e-10, 1e-8, 1e-6, 1e-4, 1e-2, 1e-1, 1.0)
AUTO_MAX_FOLDS = 10
# Cross-validation keeps a held-out error per point for every candidate (280 of them): on a
# logger's million rows that is gigabytes and minutes.  The choice of terms and ridge is
# settled by far fewer points, so auto chooses on this many, evenly spread in voltage (the
# extremes included, so the normalisation is the same), then fits the choice on every row.
AUTO_MAX_CV_POINTS = 20000
# Above this many rows the least-squares problem is first reduced block by block to its
# triangular factor (exact in exact arithmetic): the full design matrix is never held.
LSTSQ_BLOCK_ROWS = 50000
# a candidate is as good as the best when its held-out MSE exceeds the best's by less than
# this many standard errors of the paired difference (0.5: measured on the e2e sensor family,
# between 1 -- cheaper, less accurate -- and 0 -- the best held-out candidate, 1.5-2x the cost)
AUTO_PAIRED_Z = 0.5


# -- normalisation -----------------------------------------------------------------------
def half_range(kind: str) -> float | None:
    """v_n's half range under normalisation ``kind`` (None: 'none', raw volts)."""
    if kind == "none":
        return None
    if kind in HALF_RANGES:
        return HALF_RANGES[kind]
    try:
        f = float(kind)
    except ValueError:
        f = math.nan
    if not 0 < f <= 1:
        raise FlannError(f"normalisation must be one of {', '.join(NORMALISATIONS)} or a number "
                         f"in (0, 1] (the range -> [-f, f]), got {kind!r}")
    return f


def normalisation_kind(kind: str) -> str:
    """``kind`` as the training record writes it: a name, or the fraction (``%g``)."""
    return kind if kind in NORMALISATIONS else f"{half_range(kind):g}"


def normalisation(voltage_v, kind: str = "range") -> tuple[float, float]:
    """(input_offset_v, input_scale_v) for ``kind`` (:func:`half_range`)."""
    f = half_range(kind)
    if f is None:
        return 0.0, 1.0
    v = np.asarray(voltage_v, dtype=float)
    lo, hi = float(v.min()), float(v.max())
    if not hi > lo:
        raise RecordingsError(
            f"voltage_v spans no range (all {lo:g} V): cannot normalise or fit"
        )
    return (lo + hi) / 2.0, (hi - lo) / (2.0 * f)


def design_matrix(v_n: np.ndarray, terms: int) -> np.ndarray:
    """[1, phi_0 .. phi_{terms-1}]: the bias column first."""
    return np.hstack([np.ones((v_n.size, 1)), expand(v_n, terms)])


def check_fit_input(voltage_v, displacement_mm, terms: int, source: str = "recordings") -> None:
    """Refuse what cannot be fitted at all; warn (as the paper did it) about terms > points."""
    n = int(np.asarray(voltage_v).size)
    if terms < 1:
        raise FlannError(f"--terms must be >= 1, got {terms}")
    distinct = np.unique(np.asarray(voltage_v, dtype=float)).size
    if n < MIN_POINTS or distinct < 2:
        raise RecordingsError(
            f"{source}: {n} point(s) with {distinct} distinct voltage(s); need at least "
            f"{MIN_POINTS} points with 2 distinct voltages to fit a model"
        )
    if terms + 1 > n:
        warnings.warn(
            f"{source}: {terms} terms + bias from {n} points: under-determined, the fit "
            "interpolates the points (as in the paper); check between-point behaviour with "
            "'flann eval' on denser data",
            stacklevel=2,
        )


def _ranges(voltage_v, displacement_mm):
    v = np.asarray(voltage_v, dtype=float)
    x = np.asarray(displacement_mm, dtype=float)
    return (float(v.min()), float(v.max())), (float(x.min()), float(x.max()))


# -- least squares -----------------------------------------------------------------------
def solve_lstsq(design: np.ndarray, y: np.ndarray, ridge: float = 0.0,
                samples: int | None = None) -> np.ndarray:
    """Coefficients c (bias first) minimising mean((design c - y)^2) + ridge |c[1:]|^2.

    ridge = 0: minimum-norm least squares.  ridge > 0: the augmented system
    [design; sqrt(n ridge) [0 | I]] c = [y; 0], solved by the same routine.  ``samples``
    is n when ``design`` is a QR-reduced stand-in for an n-row system (cross-validation).
    """
    if ridge < 0 or not math.isfinite(ridge):
        raise FlannError(f"--ridge must be a finite number >= 0, got {ridge!r}")
    if ridge > 0:
        n, p = design.shape
        n = n if samples is None else samples
        reg = np.zeros((p - 1, p))
        reg[:, 1:] = np.sqrt(n * ridge) * np.eye(p - 1)
        design = np.vstack([design, reg])
        y = np.concatenate([y, np.zeros(p - 1)])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    return coef


def _blocks(n: int):
    return (slice(i, min(i + LSTSQ_BLOCK_ROWS, n)) for i in range(0, n, LSTSQ_BLOCK_ROWS))


def _reduced(v_n: np.ndarray, x: np.ndarray, terms: int) -> tuple[np.ndarray, np.ndarray]:
    """(R, Q^T x) of the design [1, phi(v_n)] without forming it whole (tall-skinny QR):
    each block's [A_b | x_b] is reduced to its triangle, the stacked triangles once more."""
    tri = [np.linalg.qr(np.column_stack([design_matrix(v_n[b], terms), x[b]]), mode="r")
           for b in _blocks(v_n.size)]
    r = np.linalg.qr(np.vstack(tri), mode="r")
    p = terms + 1
    return r[:p, :p], r[:p, p]


def fit_lstsq(voltage_v, displacement_mm, terms: int, *, norm: str = "range",
              offset_scale: tuple[float, float] | None = None, ridge: float = 0.0,
              training: dict | None = None) -> FlannModel:
    """Closed-form least-squares model (see module docstring)."""
    v = np.asarray(voltage_v, dtype=float)
    x = np.asarray(displacement_mm, dtype=float)
    offset, scale = offset_scale if offset_scale is not None else normalisation(v, norm)
    v_n = (v - offset) / scale
    if v.size > LSTSQ_BLOCK_ROWS:
        r, z = _reduced(v_n, x, terms)
        coef = solve_lstsq(r, z, ridge, samples=v.size)
        resid = np.concatenate([x[b] - design_matrix(v_n[b], terms) @ coef
                                for b in _blocks(v.size)])
    else:
        coef = solve_lstsq(design_matrix(v_n, terms), x, ridge)
        resid = x - (design_matrix(v_n, terms) @ coef)
    vr, xr = _ranges(v, x)
    info = {"method": "lstsq", "ridge": float(ridge),
            "normalisation": norm if offset_scale is None else "explicit",
            "train_rms_error_mm": float(np.sqrt(np.mean(resid**2))), "points": int(v.size)}
    info.update(training or {})
    return FlannModel(weights=tuple(float(c) for c in coef[1:]), bias=float(coef[0]),
                      input_offset_v=float(offset), input_scale_v=float(scale),
                      voltage_range_v=vr, displacement_range_mm=xr, training=info)


# -- LMS -----------------------------------------------------------------------------------
MAX_EPOCHS = 100_000     # the paper's fits settle within a few thousand; one float per epoch is kept


def _check_lms(eta: float, epochs: int) -> None:
    if not (eta > 0 and math.isfinite(eta)):
        raise FlannError(f"--eta must be a finite number > 0, got {eta!r}")
    if not 1 <= epochs <= MAX_EPOCHS:
        raise FlannError(f"--epochs must be 1..{MAX_EPOCHS}, got {epochs}")


def _diverged(S: np.ndarray, eta: float, where: str) -> FlannError:
    bound = 2 / float(np.max(np.sum(S**2, 1)))
    return FlannError(f"LMS diverged {where} with eta={eta:g}: use a smaller --eta "
                      f"(stability needs roughly eta < 2/|s|^2 = {bound:.3g})")


def lms_sequential(S: np.ndarray, d: np.ndarray, eta: float, epochs: int,
                   w0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The paper's LMS written literally, one sample at a time (the reference).

    ``S`` has one row per sample (bias column included); samples are visited in row order
    every epoch: e = d_k - s_k.w, w += eta e s_k.  Returns (weights, mse_per_epoch) with the
    epoch's MSE the mean of the a-priori e^2.
    """
    _check_lms(eta, epochs)
    w = np.ones(S.shape[1]) if w0 is None else np.array(w0, dtype=float)
    mse = np.empty(epochs)
    with np.errstate(over="ignore", invalid="ignore"):
        for ep in range(epochs):
            acc = 0.0
            for s, dk in zip(S, d):
                e = dk - float(s @ w)
                w += eta * e * s
                acc += e * e
            mse[ep] = acc / S.shape[0]
            if not math.isfinite(mse[ep]):
                raise _diverged(S, eta, f"in epoch {ep + 1}")
    return w, mse


def _epoch_map(S: np.ndarray, d: np.ndarray, eta: float, skip: int | None = None):
    """One LMS epoch as an affine map: w_after = A w + c; a-priori errors e = f - E w.

    Step k is w <- (I - eta s_k s_k^T) w + eta d_k s_k; composing the steps in row order
    (``skip`` leaves one row out) gives A, c; E, f give each step's a-priori error.
    """
    p = S.shape[1]
    A, c = np.eye(p), np.zeros(p)
    E, f = np.zeros_like(S), np.zeros(S.shape[0])
    for k, (s, dk) in enumerate(zip(S, d)):
        if k == skip:
            continue
        sA = s @ A
        E[k], f[k] = sA, dk - s @ c
        A = A - eta * np.outer(s, sA)
        c = c + (eta * (dk - s @ c)) * s
    return A, c, E, f


def lms_epochs(S: np.ndarray, d: np.ndarray, eta: float, epochs: int,
               w0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The paper's LMS, same result as :func:`lms_sequential` (to rounding), much faster.

    The sample-by-sample rule is linear in w, so one epoch is an affine map computed once
    (:func:`_epoch_map`); the epochs then cost one small matrix-vector product each.
    """
    _check_lms(eta, epochs)
    w = np.ones(S.shape[1]) if w0 is None else np.array(w0, dtype=float)
    mse = np.empty(epochs)
    with np.errstate(over="ignore", invalid="ignore"):
        A, c, E, f = _epoch_map(S, d, eta)
        for ep in range(epochs):
            e = f - E @ w
            mse[ep] = float(e @ e) / S.shape[0]
            if not math.isfinite(mse[ep]):
                raise _diverged(S, eta, f"in epoch {ep + 1}")
            w = A @ w + c
    return w, mse


def lms_leave_one_out(S: np.ndarray, d: np.ndarray, eta: float, epochs: int) -> np.ndarray:
    """Held-out predictions of LMS trained without each row in turn.

    Fold i visits every row except row i, in row order, ``epochs`` times, starting from
    weights of 1 -- :func:`lms_epochs` on the other rows; returns S[i] @ w_i.
    """
    _check_lms(eta, epochs)
    n, p = S.shape
    maps = [_epoch_map(S, d, eta, skip=i) for i in range(n)]
    A = np.stack([m[0] for m in maps])
    C = np.stack([m[1] for m in maps])
    W = np.ones((n, p))
    with np.errstate(over="ignore", invalid="ignore"):
        for _ in range(epochs):
            W = np.einsum("ipq,iq->ip", A, W) + C
    pred = np.einsum("ij,ij->i", W, S)
    if not np.all(np.isfinite(pred)):
        raise _diverged(S, eta, "in leave-one-out")
    return pred


def fit_lms(voltage_v, displacement_mm, terms: int, *, eta: float, epochs: int,
            norm: str = "range", offset_scale: tuple[float, float] | None = None,
            training: dict | None = None) -> FlannModel:
    """The paper's LMS (see module docstring).  MSE per epoch goes to training['mse_per_epoch']."""
    v = np.asarray(voltage_v, dtype=float)
    x = np.asarray(displacement_mm, dtype=float)
    offset, scale = offset_scale if offset_scale is not None else normalisation(v, norm)
    S = design_matrix((v - offset) / scale, terms)
    w, mse = lms_epochs(S, x, eta, epochs)
    resid = x - S @ w
    vr, xr = _ranges(v, x)
    info = {"method": "lms", "eta": float(eta), "epochs": int(epochs), "weights_start": 1.0,
            "normalisation": norm if offset_scale is None else "explicit",
            "train_rms_error_mm": float(np.sqrt(np.mean(resid**2))), "points": int(v.size),
            "mse_per_epoch": [float(f"{m:.6g}") for m in mse]}
    info.update(training or {})
    return FlannModel(weights=tuple(float(c) for c in w[1:]), bias=float(w[0]),
                      input_offset_v=float(offset), input_scale_v=float(scale),
                      voltage_range_v=vr, displacement_range_mm=xr, training=info)


# -- auto: cross-validation ---------------------------------------------------------------
@dataclass(frozen=True)
class CvResult:
    terms: int
    norm: str
    ridge: float
    rms_mm: float
    max_mm: float
    # held-out error at every held-out point (mm), same order for every candidate
    errors: np.ndarray | None = field(default=None, compare=False, hash=False, repr=False)

    @property
    def mse(self) -> float:
        return self.rms_mm ** 2


def cv_subset(voltage_v, limit: int | None = None) -> np.ndarray:
    """Indices of at most ``limit`` points evenly spread over the voltage order (both
    extremes kept); all points, in file order, when there are no more than that."""
    v = np.asarray(voltage_v, dtype=float)
    limit = AUTO_MAX_CV_POINTS if limit is None else limit
    if v.size <= limit:
        return np.arange(v.size)
    order = np.argsort(v, kind="stable")
    return np.sort(order[np.unique(np.linspace(0, v.size - 1, limit).round().astype(np.int64))])


def cv_folds(voltage_v, k: int | None = None, groups=None) -> list[np.ndarray]:
    """Interleaved held-out folds over the points sorted by voltage.

    The lowest- and highest-voltage points are never held out: cross-validation measures
    error *inside* the calibrated voltage range (the model is not used beyond it).
    ``groups`` (the displacement of each row): rows of one group are held out together, so
    a position read again on another sweep cannot stand in for itself -- with repeated
    sweeps (identical after the ADC) every held-out row would otherwise have its twin in the
    training set and the held-out error would be that of an interpolation through it.
    """
    v = np.asarray(voltage_v, dtype=float)
    if groups is None:
        gid = np.arange(v.size)
    else:
        gid = np.unique(np.asarray(groups, dtype=float), return_inverse=True)[1].ravel()
    n_groups = int(gid.max()) + 1 if gid.size else 0
    mean_v = np.bincount(gid, weights=v, minlength=n_groups) / np.bincount(gid, minlength=n_groups)
    ends = {int(gid[np.argmin(v)]), int(gid[np.argmax(v)])} if v.size else set()
    order = [g for g in np.argsort(mean_v, kind="stable") if int(g) not in ends]
    inner = np.asarray(order, dtype=np.int64)
    k = min(AUTO_MAX_FOLDS if k is None else k, inner.size)
    if k < 2:
        raise RecordingsError(
            f"{v.size} points ({n_groups} distinct positions): too few for cross-validation "
            "(auto needs at least 4 distinct positions); give --terms N explicitly"
        )
    return [np.flatnonzero(np.isin(gid, inner[i::k])) for i in range(k)]


def cross_validate(voltage_v, displacement_mm, terms_list=AUTO_TERMS, norms=AUTO_NORMS,
                   ridges=AUTO_RIDGES, k: int | None = None) -> list[CvResult]:
    """Held-out RMS and max error (mm) for every (terms, norm, ridge) candidate.

    Per fold one QR factorisation of the largest design, A = Q R; the first k columns of A
    are Q R[:, :k], so every smaller candidate is the small problem R[:, :k] c = Q^T y
    (same minimiser, same minimum-norm solution, ridge included) -- exact, and fast.
    """
    v = np.asarray(voltage_v, dtype=float)
    x = np.asarray(displacement_mm, dtype=float)
    folds = cv_folds(v, k, groups=x)
    held_all = np.sort(np.concatenate(folds))
    results = []
    for norm in norms:
        offset, scale = normalisation(v, norm)
        full = design_matrix((v - offset) / scale, max(terms_list))
        errs = {(t, r): np.full(v.size, np.nan) for t in terms_list for r in ridges}
        for held in folds:
            train = np.ones(v.size, bool)
            train[held] = False
            Q, R = np.linalg.qr(full[train])
            z = Q.T @ x[train]
            n_train = int(train.sum())
            for t in terms_list:
                B = full[held, : t + 1]
                for r in ridges:
                    coef = solve_lstsq(R[:, : t + 1], z, r, samples=n_train)
                    errs[(t, r)][held] = B @ coef - x[held]
        for (t, r), e in errs.items():
            e = e[held_all]
            if not np.all(np.isfinite(e)):   # numerically broken candidate: never chosen
                results.append(CvResult(t, norm, r, math.inf, math.inf))
                continue
            results.append(CvResult(t, norm, r, float(np.sqrt(np.mean(e**2))), float(np.max(np.abs(e))), e))
    return results


def pick(results: list[CvResult]) -> CvResult:
    """Without a cost: smallest held-out RMS; within 2 % of it, fewer terms, then larger ridge."""
    best = min(r.rms_mm for r in results)
    ok = [r for r in results if r.rms_mm <= best * 1.02 + 1e-12]
    return min(ok, key=lambda r: (r.terms, -r.ridge, NORMALISATIONS.index(r.norm)))


def paired_se(r: CvResult, ref: CvResult) -> tuple[float, float]:
    """(mean, standard error) of r's squared held-out error minus ref's, point by point (mm^2)."""
    d = r.errors ** 2 - ref.errors ** 2
    return float(np.mean(d)), float(np.std(d, ddof=1) / math.sqrt(d.size)) if d.size > 1 else 0.0


def as_good(results: list[CvResult], ref: CvResult, z: float = AUTO_PAIRED_Z) -> list[CvResult]:
    """Candidates whose held-out MSE exceeds ref's by at most z paired standard errors."""
    out = []
    for r in results:
        if not math.isfinite(r.rms_mm):
            continue
        mean, se = paired_se(r, ref)
        if mean <= z * se + 1e-300:
            out.append(r)
    return out


def _key(r: CvResult) -> dict:
    return {"terms": r.terms, "normalisation": r.norm, "ridge": r.ridge,
            "heldout_rms_error_mm": r.rms_mm, "heldout_max_error_mm": r.max_mm}


def fit_auto(voltage_v, displacement_mm, *, terms_list=AUTO_TERMS, norms=AUTO_NORMS,
             ridges=AUTO_RIDGES, training: dict | None = None,
             cost=None) -> tuple[FlannModel, CvResult]:
    """Choose (terms, norm, ridge) by cross-validation, then fit on all points.

    ``cost(model) -> {"buildable": bool, "cost": float, "why": str, ...}`` (lower is
    cheaper): with it, the cheapest buildable model as good as the best buildable one
    (:func:`as_good`); when none builds, the best-scoring candidate (the record says why).
    Without it, :func:`pick` (fewest terms within 2 % of the best RMS).
    """
    v = np.asarray(voltage_v, dtype=float)
    x = np.asarray(displacement_mm, dtype=float)
    if v.size < 4:
        raise RecordingsError(
            f"{v.size} points: too few for cross-validation (auto needs at least 4); "
            "give --terms N explicitly"
        )
    sub = cv_subset(v)
    vs, xs = v[sub], x[sub]
    results = cross_validate(vs, xs, terms_list, norms, ridges)
    info = {"selected_by": "cross-validation",
            "cv_folds": len(cv_folds(vs, groups=xs)),
            "cv_candidates": len(results)}
    if sub.size < v.size:
        info["cv_points"] = int(sub.size)
    if cost is None:
        choice = pick(results)
    else:
        choice, _model, info_hw = _cheapest(vs, xs, results, cost)
        info.update(info_hw)
    info.update({"cv_heldout_rms_error_mm": choice.rms_mm,
                 "cv_heldout_max_error_mm": choice.max_mm})
    info.update(training or {})
    model = fit_lstsq(v, x, choice.terms, norm=choice.norm, ridge=choice.ridge, training=info)
    return model, choice


def _cheapest(v, x, results: list[CvResult], cost) -> tuple[CvResult, FlannModel, dict]:
    """The cheapest buildable candidate as good as the best buildable one (:func:`as_good`).

    Candidates are visited in order of held-out MSE until one builds (normally the best);
    every candidate as good as that one is then costed and the cheapest buildable taken
    (ties: lower held-out error).
    """
    order = sorted((r for r in results if math.isfinite(r.rms_mm)), key=lambda r: (r.mse, r.terms))
    best = order[0]

    def fit(r):   # as it will be written: its held-out error sets the default output LSB
        return fit_lstsq(v, x, r.terms, norm=r.norm, ridge=r.ridge,
                         training={"cv_heldout_rms_error_mm": r.rms_mm})

    costs: dict[CvResult, tuple[FlannModel, dict]] = {}

    def costed(r):
        if r not in costs:
            m = fit(r)
            costs[r] = (m, cost(m))
        return costs[r]

    anchor = next((r for r in order if costed(r)[1]["buildable"]), None)
    if anchor is None:
        m, c = costed(best)
        return best, m, {"selected_by": "cross-validation (no candidate builds in fixed point)",
                         "hardware_why": c["why"]}
    pool = as_good(order, anchor)
    ok = [(r, *costed(r)) for r in pool if costed(r)[1]["buildable"]]
    rule = (f"as good as the best held-out (within {AUTO_PAIRED_Z:g} paired standard error), "
            "cheapest in fixed point" if anchor == best else
            "the best held-out candidates do not build in fixed point: as good as the best buildable "
            f"one (within {AUTO_PAIRED_Z:g} paired standard error), cheapest in fixed point")
    best_c = costed(best)[1]
    choice, model, c = min(ok, key=lambda t: (t[2]["cost"], t[0].mse))
    if best_c["buildable"]:
        other = (f"{best_c['cost']:.0f} LUT4-eq., {best.terms} terms, "
                 f"{best_c['weight_bits']}-bit weights")
    else:
        other = f"does not build: {best_c['why'].split(': the model')[0]}"
    anchored = "" if anchor == best else f", best buildable {anchor.rms_mm:.4g} mm"
    traded = (f"held-out RMS {choice.rms_mm:.4g} mm (best {best.rms_mm:.4g} mm{anchored}) for "
              f"{c['cost']:.0f} LUT4-equivalents, {choice.terms} terms, {c['weight_bits']}-bit "
              f"weights (best: {other})")
    info = {"selected_by": rule,
            "as_good_candidates": len(pool),
            "candidates_costed": len(costs),
            "best_heldout": _key(best),
            "chosen": _key(choice),
            "fixed_point": {k: c[k] for k in ("cost", "luts", "brams", "weight_bits", "term_bits",
                                               "phase_bits", "output_lsb_mm")},
            "traded": traded if choice != best else "nothing: the best candidate is also the cheapest"}
    return choice, model, info


def judged_converter(model) -> tuple[int, float | None, str] | None:
    """(bits, volts per code or None, where it came from) of the converter ``model`` was judged
    buildable at (``training.converter``), or None."""
    conv = model.training.get("converter") if isinstance(getattr(model, "training", None), dict) else None
    if not isinstance(conv, dict) or not isinstance(conv.get("input_bits"), int):
        return None
    lsb = conv.get("input_lsb_v")
    return conv["input_bits"], None if lsb is None else float(lsb), str(conv.get("from", "?"))


def same_converter(judged: tuple[int, float | None, str], input_bits: int, input_lsb_v: float | None) -> bool:
    bits, lsb, _ = judged
    return bits == input_bits and (lsb is None or input_lsb_v is None
                                   or abs(float(input_lsb_v) - lsb) <= 1e-3 * abs(lsb))


def converter_text(bits: int, lsb: float | None) -> str:
    return f"{bits}-bit" + (f" x {lsb:.6g} V" if lsb is not None else "")


def converter_mismatch(model: FlannModel, input_bits: int, input_lsb_v: float | None) -> str:
    """'' when ``model`` was judged buildable at this converter (or at none in particular),
    else one line saying which converter it was judged for."""
    conv = judged_converter(model)
    if conv is None or same_converter(conv, input_bits, input_lsb_v):
        return ""
    bits, lsb, _ = conv
    judged = converter_text(bits, lsb)
    given = f"{input_bits}-bit" + (f" x {input_lsb_v:.6g} V" if input_lsb_v is not None else "")
    return (f"the model's terms and widths were chosen for a {judged} converter ({conv[2]}), "
            f"this design is for {given}: retrain with flann train --input-bits {input_bits}"
            + (f" --input-lsb-v {input_lsb_v:.6g}" if input_lsb_v is not None else "")
            + " for a model judged at this converter")
