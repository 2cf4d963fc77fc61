"""Explanations the recordings cannot tell apart.

Forward selection adds one effect at a time, so when two sets of effects fit equally well
the one it names depends on the noise: on 20 identical simulated sensors (+3 mV null offset,
0.5 % secondary imbalance, independent forward model) it named secondary_imbalance +
zero_shift on 13 and secondary_imbalance + null_offset (at -9 mV, the wrong sign) on 6.
Both are even in the displacement, and with the geometry calibrated they differ only where
the slope rolls off.  Picking one by chance is worse than saying so.

After selection, every set of the same size drawn from the named effects and the candidates
that were strong on their own (lowered BIC by the acceptance margin in the first round) is
fitted, each with its own shape term, and, beside a single named effect, every pair that
forward selection did not build (neither of its effects was its first choice).  A larger set
takes part only when each of its effects earns the acceptance margin over the set without it
(BIC charges every parameter), so a single effect's recording keeps answering one effect; one
far ahead of every other set becomes the choice.  Sets whose BIC is within the margin of the best are
equally good explanations: ``CONFOUND_BIC``, or ``CONFOUND_FRACTION`` of what the best set
gains over the calibrated simulation alone when that is more (the physics model's own
imperfection -- geometry calibrated, a smooth shape term -- leaves a misfit that grows with
the effects it must reproduce); so is a set that another recording of the same sensor may
put within that margin (``REPEAT_Z``).  When more than one is, the diagnosis names a choice
(the set forward selection built, or the best by BIC when that set is not among them), ranks
the others as alternatives, and names the measurement that would tell them apart
(:func:`separations`).  Beside an effect the shape term may hide, the effects the curve
confounds it with are weighed whatever their first-round figure; each set is judged at its own
shape term and at the choice's (:func:`_near`); two equally good single effects the curve
confounds are listed together too (:func:`with_mixtures`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np

from .select import (BIC_MARGIN, CV_T, TIE_BIC, Fit, Selection, make_folds, oof_errors,
                     paired_t)

# Sets within this BIC of the best fit the recordings equally well: a difference below 6 is
# not "strong" evidence on the Kass-Raftery scale (BIC_MARGIN, 10, is "very strong": what an
# effect needs to be accepted).  The demo's small effects beat their closest alternative
# by 8-10 (null_offset 1.5 mV against secondary_imbalance: 9.2).
CONFOUND_BIC = 6.0
# ... or within this fraction of the best set's gain over the calibrated simulation.  On the
# 20 identical sensors above (gain ~2,650) the three pairs of {null_offset,
# secondary_imbalance, zero_shift} lay 5-22 apart, moving by several units from one noise
# draw to the next: any fixed margin near that split them at random.  (The demo's
# backlash + null_offset, gain ~750, beats its alternative by 9.5: 1 % keeps it named.)
CONFOUND_FRACTION = 0.01
# ... or whose BIC is behind by more than the margin on these recordings, but not so far
# that another recording of the same sensor would put it there too: ΔBIC - margin must
# exceed REPEAT_Z standard errors of the difference between two recordings' ΔBIC (sqrt 2
# times one's, from the per-point differences of squared residuals: the variance Vuong's
# test of two non-nested fits uses), one-sided 99 %.  On 20 identical sensors with a
# 0.05 mm zero shift an offset lay 3-35 BIC behind (margin 17): any fixed margin split them.
REPEAT_Z = 2.33
# ... judged so only where the differences are spread over at least this many readings
# (their participation ratio): the spread of a few readings' differences is not known.  A
# standard deviation from m values is uncertain by about 1/sqrt(2m): 16 % at 20, which moves
# REPEAT_Z's one-sided 99 % to between 97.5 and 99.8 %.  (An offset against a 40 mV
# quadrature null differs over the 28-58 readings at the tip of the V.)
SAME_READINGS = 20.0
# at most this many sets are fitted (a budget: each is one nonlinear fit)
MAX_SETS = 12
# a mixture's fit names, under this key of its ``extra``, the two effects whose split the
# recordings do not fix (see with_mixtures)
UNSPLIT = "unsplit"


@dataclass(frozen=True)
class Confounding:
    """Equally good explanations (each a tuple of effect names, the choice first, then by
    BIC), the BIC of each relative to the best, and the effects they all share; ``fits``
    holds each set's fit and ``notes`` why it is listed, in the order of ``sets``."""

    sets: tuple[tuple[str, ...], ...]
    delta_bic: tuple[float, ...]
    shared: tuple[str, ...]
    best: Fit | None
    margin: float = CONFOUND_BIC      # the margin used (BIC units)
    fits: tuple[Fit, ...] = ()
    notes: tuple[str, ...] = ()       # per set: why it is listed ("" for the margin's reasons)

    @property
    def confounded(self) -> bool:
        return len(self.sets) > 1


def none_confounded(named) -> Confounding:
    return Confounding((tuple(named),), (0.0,), tuple(named), None)


def equivalent_sets(family, sel: Selection, candidates, idx, order: tuple[str, ...],
                    margin: float = CONFOUND_BIC,
                    fraction: float = CONFOUND_FRACTION) -> Confounding:
    """The sets of effects that explain the recordings as well as the selected one."""
    named = tuple(order)
    if not named:
        return none_confounded(named)
    first = sel.trials[0] if sel.trials else []
    strong = [t.name for t in first if math.isfinite(t.delta_bic) and t.delta_bic < -BIC_MARGIN
              and not t.vetoed]
    # an effect the shape term may hide was judged with a shape complexity of its own, while
    # the first round judged every other candidate at the complexity chosen without it, where
    # the shape term already draws much of what they would: the effects the curve confounds
    # it with are weighed whatever their first-round figure (a 40 mV quadrature null: an
    # offset lay from 6 BIC ahead to 6 behind in that round, from 1 ahead to 25 behind fitted)
    hides = getattr(family, "shape_may_hide", None)
    hidden = [c for e in named if hides is not None and hides(e)
              for c in _confounders(e, candidates)]
    pool = [c for c in candidates if c in named or c in strong or c in hidden]
    # the pairs forward selection never built: it adds to the effect it holds, so a pair
    # without it is fitted only here (one with it, it has weighed already, with
    # cross-validation too).  Their effects need only have lowered BIC on their own: a 13 um
    # zero shift beside a 7 mV offset lowers it by less than the margin alone, and the pair
    # by 80 more than either.  Beside a single named effect only (each set is one more
    # nonlinear fit).
    weak = [t.name for t in first if math.isfinite(t.delta_bic) and t.delta_bic < 0
            and not t.vetoed]
    pairs = [c for c in itertools.combinations(
        [c for c in candidates if c in strong or c in weak], 2)
        if len(named) == 1 and named[0] not in c]
    if len(pool) <= len(named) and not pairs:
        return none_confounded(named)
    fits: dict[frozenset, Fit] = {frozenset(named): sel.final}
    # each set also as fitted at the shape complexity of the set forward selection built
    common: dict[frozenset, Fit] = {}
    for combo in list(itertools.combinations(pool, len(named))) + pairs:
        key = frozenset(combo)
        if key in fits:
            continue
        if len(fits) >= MAX_SETS:
            break
        # each set with its own shape term (chosen by cross-validation, as the selected set's
        # was): compared at one number of terms, the sets of an even residual swapped places
        # with it (2 terms: null_offset + zero_shift 360 behind; 6 terms: 12 ahead)
        common[key], f = _fitted(family, combo, idx, sel.final)
        # a fit that does not show what one of its effects names (a "rail" through readings
        # that still move) is no explanation, as in forward selection
        implausible = getattr(family, "implausible", None)
        if f.ok and not (len(combo) > len(named) and implausible is not None
                         and any(implausible(c, f, idx) for c in combo)):
            fits[key] = f
    fits = {key: f for key, f in fits.items() if _earns_its_size(key, f, fits)}
    # a set inside a pair that earned its second effect against it is beaten by that pair
    fits = {key: f for key, f in fits.items()
            if not any(len(k) == len(key) + 1 and key < k for k in fits)}
    best_bic = min(f.bic for f in fits.values())
    margin = max(margin, fraction * (sel.baseline.bic - best_bic))
    best = min(fits.values(), key=lambda f: f.bic)
    # a set weighed only because the curve confounds it with a hidden effect has not shown
    # its effect yet (the first round did so for the strong ones)
    unshown = set(hidden) - set(strong)
    shown = {key: _near(best, margin, f, common.get(key),
                        _shows(family, idx) if key & unshown and not key <= set(named) else None)
             for key, f in fits.items()}
    fits.update({key: f for key, f in shown.items() if f is not None})
    near = sorted(((fits[key].bic - best_bic, key) for key, f in shown.items() if f is not None),
                  key=lambda t: (t[0], sorted(t[1])))
    if len(near) <= 1:
        # one set left: forward selection's own, or a larger one far ahead of it
        key = near[0][1]
        if key == frozenset(named):
            return none_confounded(named)
        chosen = tuple(c for c in candidates if c in key)
        return Confounding((chosen,), (0.0,), chosen, fits[key], margin, (fits[key],))
    # the choice is the set forward selection built (each of its effects earned its keep
    # one at a time, converter-step and rail checks included) when it is among them
    mine = [t for t in near if t[1] == frozenset(named)]
    near = mine + [t for t in near if t[1] != frozenset(named)]
    sets = tuple(tuple(c for c in candidates if c in key) for _, key in near)
    shared = tuple(c for c in named if all(c in s for s in sets))
    return Confounding(sets, tuple(d for d, _ in near), shared, fits[near[0][1]], margin,
                       tuple(fits[key] for _, key in near))


def _confounders(effect: str, candidates) -> list[str]:
    """The candidates whose DC curve bends as ``effect``'s does (those :data:`_PAIRS` names a
    separating measurement for)."""
    return [c for c in candidates if c != effect and frozenset({effect, c}) in _PAIRS]


def _fitted(family, effects, idx, start: Fit) -> tuple[Fit, Fit]:
    """``effects`` fitted at ``start``'s shape complexity, and with its own chosen again (by
    cross-validation, as the selected set's was)."""
    f = family.fit(list(effects), idx, start=start)
    return f, (family.rechoose(list(effects), idx, f) if f.ok else f)


def _near(best: Fit, margin: float, own: Fit, common: Fit | None = None,
          shows=None) -> Fit | None:
    """The fit by which a set is an equally good explanation (None if it is not): with its own
    shape complexity, or with the choice's.  Cross-validation picks a set's complexity from
    noisy readings (on 20 identical sensors, an offset in place of a quadrature null took 0
    terms on 12 and 2 on 8, 25 BIC worse), so another recording may well fit it at the
    choice's.  Of the two, the better by BIC.  ``shows``: whether a fit shows the effects it
    names (see :func:`_shows`)."""
    ok = [f for f in (own, common) if f is not None and f.ok
          and (f.bic - best.bic < margin or _not_beaten(best, f, margin))
          and (shows is None or shows(f))]
    return min(ok, key=lambda f: f.bic) if ok else None


def _shows(family, idx):
    """Whether a fit of one effect shows it: it beats the calibrated simulation with the same
    shape term by the acceptance margin, as the first round of forward selection asks of every
    candidate.  Fitted beside a named effect for its curve alone, a moved null of 2e-5 mm
    (none) came within the margin of a quadrature null whose complexity it shared."""
    def shows(f: Fit) -> bool:
        base = family.fit([], idx, start=f)
        return base.ok and f.bic - base.bic < -BIC_MARGIN
    return shows


def _earns_its_size(key: frozenset, fit: Fit, fits: dict) -> bool:
    """A set is compared with the others only when each of its effects earns its keep: it
    beats every fitted set of one effect fewer inside it by the margin forward selection asks
    of an effect (BIC charges each parameter ln n), by ``REPEAT_Z`` standard errors of that
    difference more (evidence on these recordings at 99 %; with the sqrt 2 of another
    recording, a 7 mV offset with a 13 um zero shift, 5 mV noise, that beat the offset alone by
    65 was left out on 8 of 20 identical sensors).  A single effect's recording, fitted with a
    pair that adds an effect the curve does not show, keeps answering one effect: on 20
    identical sensors with a 0.05 mm zero shift, null_offset + secondary_imbalance beat each
    alone by the margin on 4 and not on the other 16."""
    for k, f in fits.items():
        if len(k) == len(key) - 1 and k < key:
            se, _ = bic_spread(fit, f)
            if not f.bic - fit.bic - BIC_MARGIN > REPEAT_Z * se:
                return False
    return True


def bic_spread(best: Fit, other: Fit) -> tuple[float, float]:
    """The standard error of ``other``'s BIC behind ``best`` over noise draws (from the
    per-point differences of squared residuals, in units of ``best``'s residual variance),
    and the number of readings those differences are spread over (participation ratio)."""
    n = best.resid.size
    if other.resid.size != n or n < 3 or best.rss <= 0:
        return math.inf, 0.0
    d = (other.resid ** 2 - best.resid ** 2) / (best.rss / n)
    den = float(d @ d)
    readings = float(np.sum(np.abs(d))) ** 2 / den if den > 0 else 0.0
    return math.sqrt(n) * float(np.std(d, ddof=1)), readings


def _not_beaten(best: Fit, other: Fit, margin: float) -> bool:
    """Another recording of the same sensor may put ``other`` within ``margin`` of ``best``."""
    se, readings = bic_spread(best, other)
    if readings < SAME_READINGS or not math.isfinite(se) or se <= 0:
        return False
    return other.bic - best.bic - margin < REPEAT_Z * math.sqrt(2.0) * se


SHAPE_NOTE = ("BIC prefers it, but cross-validation does not: the smooth shape term draws "
              "the same readings without it")


def with_shape_alternative(family, sel: Selection, idx, conf: Confounding,
                           candidates=()) -> Confounding:
    """Add "the sensor's shape" as an explanation beside an effect the shape term may draw
    (:meth:`PhysicsFamily.shape_may_hide`).  Nothing named, but such a candidate lowered BIC
    by the acceptance margin and failed only cross-validation: it is listed as an
    alternative to nothing, and so is each of ``candidates`` the curve confounds it with
    that is as good as it (as :func:`equivalent_sets` weighs a named one's).  The effect named
    alone, or beside equally good others: nothing (its shape term) is listed when it is within
    the margin or another recording may put it there.  Either way identical sensors get the
    same sets, whichever side of the line their noise puts them."""
    hides = getattr(family, "shape_may_hide", None)
    if hides is None or len(conf.sets[0]) > 1:
        return conf
    named = conf.sets[0]
    if not named:
        if conf.confounded:
            return conf
        first = sel.trials[0] if sel.trials else []
        strong = [t for t in first if hides(t.name) and not t.vetoed and not t.accepted
                  and math.isfinite(t.delta_bic) and t.delta_bic < -BIC_MARGIN
                  and (t.cv_t is None or t.cv_t > CV_T - REPEAT_Z * math.sqrt(2.0))]
        if not strong:
            return conf
        c = strong[0].name
        _, f = _fitted(family, [c], idx, sel.baseline)
        if not f.ok:
            return conf
        margin = max(conf.margin, CONFOUND_FRACTION * (sel.baseline.bic - f.bic))
        found = [((c,), f, SHAPE_NOTE)]
        for d in _confounders(c, candidates):
            common, own = _fitted(family, [d], idx, f)
            g = _near(f, margin, own, common, _shows(family, idx))
            if g is not None:
                found.append(((d,), g, f"as good an explanation as {c}, which BIC prefers to "
                               "nothing: the curve bends alike for both"))
        return _with_more(Confounding(((),), (0.0,), (), sel.final, margin, (sel.final,), ("",)),
                          found)
    if not hides(named[0]):
        return conf
    best, base = (conf.fits[0] if conf.fits else sel.final), sel.baseline
    # cross-validation's t, too, moves by about 1 from one recording to the next
    cv_t = sel.steps[0].cv_t if sel.steps else math.inf
    if not (base.bic - best.bic < conf.margin or _not_beaten(best, base, conf.margin)
            or cv_t - CV_T < REPEAT_Z * math.sqrt(2.0)):
        return conf
    note = ("the smooth shape term draws the same readings without it, nearly as well "
            f"(cross-validation t {cv_t:.1f})")
    if not conf.confounded:
        return Confounding((named, ()), (0.0, base.bic - best.bic), (), best, conf.margin,
                           (best, base), ("", note))
    return _with_more(conf, [((), base, note)])


# An effect that BIC prefers by more than this, but by less than the acceptance margin, when
# forward selection stops: "positive" evidence on the Kass-Raftery scale (2-6), short of the
# "very strong" (BIC_MARGIN) that names it.  One parameter on n points lowers BIC by z^2 - ln n
# (z its value over its uncertainty), so on 500-2,000 points this asks z > 2.9-3.1: a pure
# noise draw does so for 1 candidate in 250-500.  Another recording of the same sensor moves
# z by about 1, so one at z = 3 is named on some recordings and not on others.
UNDECIDED_BIC = TIE_BIC
UNDECIDED_NOTE = ("BIC prefers it by {gain:.1f}, short of the {margin:g} that names an effect "
                  "(cross-validation t {cv}): the evidence leans towards it but does not decide, "
                  "and another recording of the same sensor may name it")


def with_undecided(family, sel: Selection, idx, conf: Confounding, candidates=()) -> Confounding:
    """Add, beside a choice the evidence otherwise decides, the effect forward selection
    stopped short of: the best candidate of its last round that BIC prefers by more than
    ``UNDECIDED_BIC`` but less than ``BIC_MARGIN`` (with the choice's effects, refitted).

    Forward selection asks "very strong" evidence of an effect, so an effect near its limit
    is named on some recordings and left out on others; saying nothing of it turns a choice
    the evidence leans against into a silent one.  On the filament model, a 3 mV offset with
    the null free (one pass off-centre, 487 points, 4.2 mV noise) lowers BIC by 3.1, fitted at
    19 +- 6 mV (cross-validation t 1.5), and a 4 mV offset beside a 30 um dead band (1,616
    points) by 4.1, at 5.8 +- 1.7 mV (t 1.5): with the null free an offset differs from a
    moved null only where the slope rolls off.  Listed as the one alternative, with the
    measurement that reveals it.  Only when nothing else is listed (at most one alternative
    beside the choice), and only when the choice is forward selection's own set.

    Only the effects the curve confounds (:data:`_PAIRS`): their evidence is capped by an
    effect that bends the curve alike, whatever their size.  The others have a signature of
    their own (direction, temperature, a period, flat rails) that the acceptance rule decides
    on, and a period is searched over many: BIC's ln n a parameter does not charge that search,
    and a lead-screw period "lowered BIC by 2.7" on a 48-point control."""
    if conf.confounded or not sel.trials:
        return conf
    named = tuple(conf.sets[0])
    last = sel.trials[-1]
    if (any(t.accepted for t in last) or sel.dropped
            or set(named) != {s.name for s in sel.steps}):
        return conf
    lean = sorted((t for t in last if t.name in _CURVE_CONFOUNDED and not t.vetoed
                   and not t.accepted and t.name not in named
                   and math.isfinite(t.delta_bic)
                   and -BIC_MARGIN <= t.delta_bic < -UNDECIDED_BIC),
                  key=lambda t: t.delta_bic)
    if not lean:
        return conf
    c = lean[0]
    final = sel.final
    f = family.fit(list(named) + [c.name], idx, start=final)
    implausible = getattr(family, "implausible", None)
    if (not f.ok or not f.bic - final.bic < -UNDECIDED_BIC
            or (implausible is not None and implausible(c.name, f, idx))):
        return conf
    alt = tuple(e for e in candidates if e in named or e == c.name) if candidates else \
        named + (c.name,)
    # its cross-validation t, as forward selection would have weighed it (it stopped at BIC)
    folds = make_folds(idx)
    t, _ = paired_t(oof_errors(family, list(named), idx, folds, final),
                    oof_errors(family, list(named) + [c.name], idx, folds, f))
    note = UNDECIDED_NOTE.format(gain=final.bic - f.bic, margin=BIC_MARGIN, cv=f"{t:.1f}")
    return Confounding((named, alt), (0.0, f.bic - final.bic), named, final, conf.margin,
                       (final, f), ("", note))


def with_mixtures(family, idx, conf: Confounding) -> Confounding:
    """Add, beside equally good single effects that the curve confounds, the two together.

    A curve that cannot tell one effect from the other cannot tell either from a mixture of
    both (on 20 filament-model sensors with a 3 mV offset beside a 0.5 % imbalance, the pair
    fitted is 11 BIC behind the offset alone, its weaker effect within one uncertainty of
    zero, and the offset, the imbalance and a moved null are each named alone).  So the
    mixture of two offered single effects is listed too when it fits as well as the best set
    (its BIC, less the ln n BIC charges for each parameter it has more, within the margin),
    although its second effect does not earn its keep on this curve: that charge is the
    evidence against an effect the curve does not show, and the curve cannot show either of
    two effects it confounds.  Judged by BIC alone, the mixture sat on the margin's edge (a
    quadrature null and an offset: 6.2-6.4 behind, margin 6).  Its fit is one split of the two
    effects' sum among many that fit alike: its parameters are not determined (the fit carries
    the pair under ``UNSPLIT``).  The measurement that tells the two effects apart also tells
    whether both are there."""
    singles = [(s, f) for s, f in zip(conf.sets, conf.fits) if len(s) == 1]
    top = min(conf.fits, key=lambda f: f.bic) if conf.fits else None
    have = {frozenset(s) for s in conf.sets}
    more = []

    def fits_as_well(f: Fit) -> bool:
        return f.ok and f.bic - top.bic - (f.k - top.k) * math.log(max(f.n, 1)) < conf.margin

    for (a, fa), (b, fb) in itertools.combinations(singles, 2):
        if frozenset(a + b) in have or frozenset(a + b) not in _PAIRS:
            continue
        # the better single with the other effect added, at its shape term (its own chosen
        # again only when that does not fit): along a valley the curve does not resolve, a fit
        # that walks the shape terms ends anywhere along it (beside a 0.05 mm moved null, an
        # offset of -14 mV or of -208 mV with an imbalance of either sign, alike within the
        # noise), and each walk is several nonlinear fits
        f = family.fit(list(a + b), idx, start=min(fa, fb, key=lambda f: f.bic))
        if f.ok and not fits_as_well(f):
            f = family.rechoose(list(a + b), idx, f)
        if fits_as_well(f):
            f = replace(f, extra={**f.extra, UNSPLIT: (a[0], b[0])})
            more.append((a + b, f, f"{a[0]} and {b[0]} together: the curve cannot tell either "
                         "from the other, nor from both"))
    return _with_more(conf, more) if more else conf


def _with_more(conf: Confounding, more) -> Confounding:
    """``conf`` (with its choice's fit) with the explanations ``more`` ((effects, fit, note)
    each) among its alternatives, ranked by BIC; their ΔBIC measured as ``conf``'s are."""
    ref = conf.fits[0].bic - conf.delta_bic[0]
    notes = conf.notes or ("",) * len(conf.sets)
    rest = sorted(list(zip(conf.sets[1:], conf.delta_bic[1:], conf.fits[1:], notes[1:]))
                  + [(s, f.bic - ref, f, n) for s, f, n in more], key=lambda t: t[1])
    sets = (conf.sets[0],) + tuple(t[0] for t in rest)
    return replace(conf, sets=sets, delta_bic=(conf.delta_bic[0],) + tuple(t[1] for t in rest),
                   shared=tuple(e for e in conf.sets[0] if all(e in s for s in sets)),
                   fits=(conf.fits[0],) + tuple(t[2] for t in rest),
                   notes=(notes[0],) + tuple(t[3] for t in rest))


@dataclass(frozen=True)
class Separation:
    """A measurement that tells two confounded effects apart (``b`` None: that reveals
    ``a`` whatever else is there), and why it does."""

    a: str
    b: str | None
    measurement: str
    why: str


_SECONDARIES = "record both secondary amplitudes (sec_a_v, sec_b_v) over the travel"
_QUADRATURE = ("record the quadrature channel (the output demodulated 90 degrees from the "
               "excitation, or the waveforms exc_v, sec_a_v, sec_b_v)")
# the physical signal that separates two effects whose DC output curves bend alike
_PAIRS: dict[frozenset, tuple[str, str]] = {
    frozenset({"secondary_imbalance", "zero_shift"}): (
        _SECONDARIES, "an imbalance makes one secondary larger than the other at every "
        "position; a zero shift moves the position where they are equal and keeps their sizes "
        "alike"),
    frozenset({"null_offset", "secondary_imbalance"}): (
        _SECONDARIES, "an imbalance shows as unequal secondaries; an offset of the demodulator "
        "or amplifier is in neither secondary"),
    frozenset({"null_offset", "zero_shift"}): (
        _SECONDARIES, "a zero shift moves the position where the secondaries are equal; an "
        "offset leaves it where the core is centred and only adds to the output"),
    frozenset({"quadrature_null", "null_offset"}): (
        _QUADRATURE + ", or record at a second excitation frequency, or record densely across "
        "the null (steps well below the quadrature voltage over the slope there)",
        "a quadrature null is 90 degrees out of phase with the excitation (capacitive coupling "
        "grows with frequency); an offset is in phase or DC.  On the curve alone, a quadrature "
        "null rounds the tip of a rectified V over about its voltage over the slope on each "
        "side while an offset lifts the V and keeps its tip sharp: only the readings that "
        "close to the null tell them apart"),
    frozenset({"quadrature_null", "secondary_imbalance"}): (
        _QUADRATURE, "a quadrature null is 90 degrees out of phase with the excitation; an "
        "imbalance is in phase with the secondaries"),
    frozenset({"quadrature_null", "zero_shift"}): (
        _QUADRATURE, "a quadrature null fills the null in with an out-of-phase voltage; a moved "
        "null keeps the in-phase output's zero crossing sharp"),
}
# the effects whose DC curve bends as another's does
_CURVE_CONFOUNDED = frozenset(e for pair in _PAIRS for e in pair)
# what reveals an effect whatever it is confounded with
_ALONE: dict[str, tuple[str, str]] = {
    "null_offset": (_SECONDARIES, "an offset is in neither secondary"),
    "zero_shift": (_SECONDARIES, "a zero shift moves the position where the secondaries are "
                   "equal"),
    "secondary_imbalance": (_SECONDARIES, "an imbalance makes one secondary larger at every "
                            "position"),
    "quadrature_null": (_QUADRATURE, "a quadrature null is out of phase with the excitation"),
    "backlash": ("record both directions of travel over the same positions, with a dial gauge "
                 "on the core", "lost motion makes the two directions differ by the dead band"),
    "thermal_drift": ("record a second run at constant temperature, or with the temperature "
                      "changing on the way back", "a thermal drift follows the temperature, "
                      "not the displacement or the sweep"),
    "adc_clipping": ("record with the excitation lowered by a known fraction",
                     "a rail stays at the same voltage while the sensor's curve scales"),
    "leadscrew_periodic": ("record the core's position with a reference gauge at a step of at "
                           "most a third of the period", "a lead-screw error is in the "
                           "actuator's position, not in the sensor's output"),
}


# effects the plain output curve carries at every position: a pair of one of these with a
# rarer effect is told apart by what reveals the rarer one
_PAIRS_COMMON = ("null_offset", "zero_shift", "secondary_imbalance")


def separations(sets) -> tuple[Separation, ...]:
    """The measurements that tell the first set from each other one (one per pair of effects
    they do not share, each pair once)."""
    if len(sets) < 2:
        return ()
    choice = tuple(sets[0])
    out: list[Separation] = []
    seen: set = set()
    for other in sets[1:]:
        only_a = [e for e in choice if e not in other]
        only_b = [e for e in other if e not in choice]
        pairs = [(a, b) for a in only_a for b in only_b] or \
            [(e, None) for e in only_a + only_b]
        for a, b in pairs:
            key = frozenset({a, b} - {None})
            if key in seen:
                continue
            seen.add(key)
            if b is not None and key in _PAIRS:
                out.append(Separation(a, b, *_PAIRS[key]))
            else:
                # a pair without its own measurement: what reveals the rarer of the two
                e = a if a in _ALONE and (b is None or a not in _PAIRS_COMMON) else (b or a)
                m, why = _ALONE.get(e, (_SECONDARIES, ""))
                out.append(Separation(a, b, m, why))
    return tuple(out)


__all__ = ["Confounding", "Separation", "bic_spread", "equivalent_sets", "none_confounded",
           "separations", "with_mixtures", "with_shape_alternative", "with_undecided",
           "CONFOUND_BIC", "UNDECIDED_BIC", "UNSPLIT"]
