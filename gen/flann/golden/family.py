"""Terms for one design shared by a family of sensors, chosen like ``flann train --terms auto``.

Each member's recordings are put through the same selection as ``--terms auto`` (held-out
error by cross-validation, the cheapest buildable candidate as good as the best), restricted
to the family datapath's normalisation.  The shared design must serve the worst member, so
it takes the largest of the members' own term counts.  :func:`family_terms` also says what
sharing costs each member: its own choice (terms, held-out RMS, fixed-point cost) next to
its held-out RMS at the family's terms.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .train import cross_validate, fit_auto


@dataclass(frozen=True)
class MemberChoice:
    name: str
    own_terms: int
    own_ridge: float
    own_rms_mm: float
    own_cost: float | None          # LUT4 equivalents of its own design (None: not costed)
    family_rms_mm: float | None = None


def family_terms(members, *, norm: str, ridge: float, cost=None) -> tuple[int, list[MemberChoice]]:
    """(terms, per-member choices) for ``members``: (name, voltage_v, displacement_mm) tuples.

    ``cost(model)`` as for :func:`flann.golden.train.fit_auto` (the design at the user's
    converter).  The family's held-out RMS of each member is the same cross-validation at the
    family's terms, normalisation and ridge (what :func:`fit_lstsq` will be given).
    """
    own = []
    for name, v, x in members:
        model, choice = fit_auto(v, x, norms=(norm,), cost=cost)
        fp = model.training.get("fixed_point") or {}
        own.append((name, v, x, choice, fp.get("cost")))
    terms = max(c.terms for _n, _v, _x, c, _c in own)
    out = []
    for name, v, x, c, own_cost in own:
        (res,) = cross_validate(v, x, (terms,), (norm,), (ridge,))
        out.append(MemberChoice(name, c.terms, c.ridge, c.rms_mm, own_cost, res.rms_mm))
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
