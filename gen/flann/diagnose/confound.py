"""Explanations the recordings cannot tell apart.

Forward selection adds one effect at a time, so when two sets of effects fit equally well
the one it names depends on the noise: on 20 identical simulated sensors (+3 mV null offset,
0.5 % secondary imbalance, independent forward model) it named secondary_imbalance +
zero_shift on 13 and secondary_imbalance + null_offset (at -9 mV, the wrong sign) on 6.
Both are even in the displacement, and with the geometry calibrated they differ only where
the slope rolls off.  Picking one by chance is worse than saying so.

After selection, every set of the same size drawn from the named effects and the candidates
that were strong on their own (lowered BIC by the acceptance margin in the first round) is
fitted, each with its own shape term.  Sets whose BIC is within the margin of the best are
equally good explanations: ``CONFOUND_BIC``, or ``CONFOUND_FRACTION`` of what the best set
gains over the calibrated simulation alone when that is more (the physics model's own
imperfection -- geometry calibrated, a smooth shape term -- leaves a misfit that grows with
the effects it must reproduce).  When more than one is, the diagnosis reports them all as ``alternatives`` and
names only the effects they share.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

from .select import BIC_MARGIN, Fit, Selection

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
# at most this many sets are fitted (a budget: each is one nonlinear fit)
MAX_SETS = 12


@dataclass(frozen=True)
class Confounding:
    """Equally good explanations (each a tuple of effect names, best first), the BIC of
    each relative to the best, and the effects they all share."""

    sets: tuple[tuple[str, ...], ...]
    delta_bic: tuple[float, ...]
    shared: tuple[str, ...]
    best: Fit | None
    margin: float = CONFOUND_BIC      # the margin used (BIC units)

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
    pool = [c for c in candidates if c in named or c in strong]
    if len(pool) <= len(named):
        return none_confounded(named)
    fits: dict[frozenset, Fit] = {frozenset(named): sel.final}
    for combo in itertools.combinations(pool, len(named)):
        key = frozenset(combo)
        if key in fits:
            continue
        if len(fits) >= MAX_SETS:
            break
        # each set with its own shape term (chosen by cross-validation, as the selected set's
        # was): compared at one number of terms, the sets of an even residual swapped places
        # with it (2 terms: null_offset + zero_shift 360 behind; 6 terms: 12 ahead)
        f = family.fit(list(combo), idx, start=sel.final)
        if f.ok:
            f = family.rechoose(list(combo), idx, f)
        if f.ok:
            fits[key] = f
    best_bic = min(f.bic for f in fits.values())
    margin = max(margin, fraction * (sel.baseline.bic - best_bic))
    near = sorted(((f.bic - best_bic, key) for key, f in fits.items() if f.bic - best_bic < margin),
                  key=lambda t: (t[0], sorted(t[1])))
    if len(near) <= 1:
        return none_confounded(named)
    sets = tuple(tuple(c for c in candidates if c in key) for _, key in near)
    shared = tuple(c for c in named if all(c in s for s in sets))
    return Confounding(sets, tuple(d for d, _ in near), shared, fits[near[0][1]], margin)


__all__ = ["Confounding", "equivalent_sets", "none_confounded", "CONFOUND_BIC"]
