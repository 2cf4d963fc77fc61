"""Terms for one design shared by a family of sensors, chosen like ``flann train --terms auto``.

Each member's recordings are put through the same selection as ``--terms auto`` (held-out
error by cross-validation, the cheapest buildable candidate as good as the best), restricted
to the family datapath's normalisation.  The shared design must serve the worst member: it
takes the fewest terms at which every member's held-out RMS (at the family's ridge) is within
``FAMILY_SHARE`` of its own choice's and whose weights are steady from member to member
(:func:`_steady`), at most the largest of the members' own term counts.  :func:`family_terms` also says what
sharing costs each member: its own choice (terms, held-out RMS, fixed-point cost) next to
its held-out RMS at the family's terms.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .train import AUTO_RIDGES, AUTO_TERMS, cross_validate, fit_auto, fit_lstsq

# the family's terms keep every member's held-out RMS within this factor of its own design's
FAMILY_SHARE = 1.2


@dataclass(frozen=True)
class MemberChoice:
    name: str
    own_terms: int
    own_ridge: float
    own_rms_mm: float
    own_cost: float | None          # LUT4 equivalents of its own design (None: not costed)
    family_rms_mm: float | None = None


def _steady(models, margin: float) -> bool:
    """Every member's bias, linear weight and largest sin/cos weight within (1 + margin) of
    the largest the other members have: a design sized without any one member still holds
    it, so a sensor like them fits too (high-order fits of nearly collinear terms cancel
    huge weights, which differ from sensor to sensor)."""
    if len(models) < 2:
        return True
    size = np.array([[abs(m.bias), abs(m.weights[0]), max((abs(w) for w in m.weights[1:]), default=0.0)]
                     for m in models])
    for i in range(len(models)):
        others = np.delete(size, i, axis=0).max(axis=0)
        if np.any(size[i] > (1 + margin) * others + 1e-12):
            return False
    return True


def family_terms(members, *, norm: str, ridge: float, margin: float = 0.5,
                 cost=None) -> tuple[int, list[MemberChoice]]:
    """(terms, per-member choices) for ``members``: (name, voltage_v, displacement_mm) tuples.

    ``cost(model)`` as for :func:`flann.golden.train.fit_auto` (the design at the user's
    converter).  The family's held-out RMS of each member is the same cross-validation at the
    family's terms, normalisation and ridge (what :func:`fit_lstsq` will be given).
    """
    own = []
    for name, v, x in members:
        # judged at the ridges the family trains with (its weights must fit one memory)
        model, choice = fit_auto(v, x, norms=(norm,), ridges=tuple(r for r in AUTO_RIDGES if r >= ridge),
                                 cost=cost)
        fp = model.training.get("fixed_point") or {}
        own.append((name, v, x, choice, fp.get("cost")))
    # the fewest terms that keep every member's held-out error within FAMILY_SHARE of its own
    # (fewer terms: smaller, steadier weights, so sensors like the members fit the memory too)
    top = max(c.terms for _n, _v, _x, c, _c in own)
    tried = [t for t in AUTO_TERMS if t <= top]
    table = {name: {r.terms: r.rms_mm for r in cross_validate(v, x, tried, (norm,), (ridge,))}
             for name, v, x, _c, _cost in own}
    def steady(t):
        return _steady([fit_lstsq(v, x, t, norm=norm, ridge=ridge) for _n, v, x, _c, _cost in own], margin)

    def accurate(t):
        return all(table[name][t] <= FAMILY_SHARE * c.rms_mm for name, _v, _x, c, _cost in own)

    terms = next((t for t in tried if accurate(t) and steady(t)), None)
    if terms is None:   # no count is both: the most accurate steady one, else the members' largest
        terms = next((t for t in reversed(tried) if steady(t)), top)
    out = [MemberChoice(name, c.terms, c.ridge, c.rms_mm, own_cost, table[name][terms])
           for name, v, x, c, own_cost in own]
    return terms, out


__all__ = ["MemberChoice", "family_terms"]


# a member whose error in the family design exceeds its own design's by more than this is
# flagged (calibrate, certificate): the shared design costs that sensor accuracy
REACH_FACTOR = 1.5


def own_reach_mm(voltage_v, displacement_mm, cost=None) -> tuple[float, int]:
    """(max |error| on the recording itself, terms) of the sensor's own ``--terms auto`` model:
    what its own design would reach on the same points (the float model; its hardware is
    within an output LSB of it)."""
    model, choice = fit_auto(voltage_v, displacement_mm, cost=cost)
    err = np.abs(model.predict(voltage_v) - np.asarray(displacement_mm, dtype=float))
    return float(np.max(err)), choice.terms


__all__ += ["REACH_FACTOR", "own_reach_mm"]
