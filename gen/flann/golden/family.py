"""Terms for one design shared by a family of sensors, chosen like ``flann train --terms auto``.

Each member's recordings are put through the same selection as ``--terms auto`` (held-out
error by cross-validation, the cheapest buildable candidate as good as the best), restricted
to the family datapath's normalisation.  The shared design must serve the worst member: it
takes the fewest terms, and at those the largest of :data:`FAMILY_RIDGES` (the smallest
weights), at which every member's held-out RMS and max error are within ``FAMILY_SHARE`` of
its own choice's and whose weights are steady from member to member (:func:`_steady`), at
most the largest of the members' own term counts.  :func:`family_terms` also says what
sharing costs each member: its own choice (terms, held-out RMS and max, fixed-point cost)
next to its held-out figures at the family's terms and ridge.

:func:`family_thermal_terms` is the same rule for a family with temperature (x = sum_j t_n^j
f_j(v), one term count shared by every order and member): each member's own choice is
``flann train --temperature``'s selection (:mod:`.thermal_train`: held-out positions and
temperatures) restricted to the family design's form (no input correction, the design's
temperature normalisation, the family's voltage normalisation and ridge).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..errors import FlannError
from . import thermal_train
from .train import AUTO_RIDGES, AUTO_TERMS, cross_validate, fit_auto, fit_lstsq

# the family's terms keep every member's held-out RMS and max error within this factor of its
# own design's
FAMILY_SHARE = 1.2
# The ridges a family design may train its members with, largest (smallest weights) first.  A
# fixed 1e-6 bent the ends: on 20 S-curve sensors 41 terms reached 1.2-1.7 x each member's own
# max error where 25 terms at 1e-10 reach 1.0-1.1 with weights of at most 10 (bench/family_reach.py).
FAMILY_RIDGES = (1e-6, 1e-8, 1e-10)
DEFAULT_RIDGE = FAMILY_RIDGES[0]    # --terms N, and designs whose manifest names no ridge
# calibrate tries the design's ridge first, then these larger ones until a sensor's weights fit
CALIBRATE_RIDGES = (*sorted(FAMILY_RIDGES), 1e-5, 1e-4, 1e-3)


def ridge_ladder(ridge: float) -> tuple[float, ...]:
    """The ridges calibrate tries for a design trained at ``ridge``: that one, then larger."""
    return (ridge, *(r for r in CALIBRATE_RIDGES if r > ridge))


@dataclass(frozen=True)
class MemberChoice:
    name: str
    own_terms: int
    own_ridge: float
    own_rms_mm: float
    own_cost: float | None          # LUT4 equivalents of its own design (None: not costed)
    family_rms_mm: float | None = None
    own_max_mm: float | None = None     # held-out max error (None: judged by RMS alone)
    family_max_mm: float | None = None


def _steady(models, margin: float) -> bool:
    """Every member's linear weight and largest sin/cos weight within (1 + margin) of the
    largest the other members have: a design sized without any one member still holds it, so
    a sensor like them fits too (high-order fits of nearly collinear terms cancel huge weights,
    which differ from sensor to sensor).  ``models``: (bias, weights) pairs.  The bias is not
    judged: it follows the sensor's null, near 0 on a centred stroke, where any two members'
    ratio is noise (3 erf sensors: 0.003 and 0.063 mm at every count from 13 to 51 terms, their
    weights within 1 %), and the design sizes it with the null's spread (the offset constant
    k0, :data:`flann.hardware.family.spec.SPREAD`)."""
    if len(models) < 2:
        return True
    size = np.array([[abs(w[0]), max((abs(c) for c in w[1:]), default=0.0)] for _b, w in models])
    for i in range(len(models)):
        others = np.delete(size, i, axis=0).max(axis=0)
        if np.any(size[i] > (1 + margin) * others + 1e-12):
            return False
    return True


def family_terms(members, *, norm: str, ridges=FAMILY_RIDGES, margin: float = 0.5,
                 cost=None) -> tuple[int, float, list[MemberChoice]]:
    """(terms, ridge, per-member choices) for ``members``: (name, voltage_v, displacement_mm) tuples.

    ``cost(model)`` as for :func:`flann.golden.train.fit_auto` (the design at the user's
    converter).  The family's held-out figures of each member are the same cross-validation at
    the family's terms, normalisation and each of ``ridges`` (what :func:`fit_lstsq` will be
    given).
    """
    ridges = tuple(sorted(ridges, reverse=True))
    own = []
    for name, v, x in members:
        # judged at the ridges the family may train with (its weights must fit one memory)
        try:
            model, choice = fit_auto(v, x, norms=(norm,), ridges=tuple(r for r in AUTO_RIDGES if r >= ridges[-1]),
                                     cost=cost)
        except FlannError as exc:
            raise FlannError(f"{name}: {exc}") from None
        fp = model.training.get("fixed_point") or {}
        own.append((name, v, x, choice, fp.get("cost")))
    top = max(c.terms for _n, _v, _x, c, _c in own)
    counts = [t for t in AUTO_TERMS if t <= top]
    tried = [(t, r) for t in counts for r in ridges]
    table = [{(r.terms, r.ridge): (r.rms_mm, r.max_mm) for r in cross_validate(v, x, counts, (norm,), ridges)}
             for _n, v, x, _c, _cost in own]

    def steady(key):
        t, ridge = key
        fits = [fit_lstsq(v, x, t, norm=norm, ridge=ridge) for _n, v, x, _c, _cost in own]
        return _steady([(m.bias, m.weights) for m in fits], margin)

    key = shared_terms(tried, table, [(c.rms_mm, c.max_mm) for _n, _v, _x, c, _cost in own], steady,
                       describe=lambda k: f"{k[0]} terms at ridge {k[1]:g}")
    out = [MemberChoice(name, c.terms, c.ridge, c.rms_mm, own_cost, held[key][0], c.max_mm, held[key][1])
           for (name, v, x, c, own_cost), held in zip(own, table)]
    return key[0], key[1], out


def shared_terms(tried, table, own, steady, describe=lambda t: f"{t} terms"):
    """The family's rule: of the candidates ``tried`` (in order of preference: fewer terms,
    then smaller weights; up to the members' largest own count), the first that keeps every
    member's held-out figures (``table[k][candidate]``, member k: one number or a tuple, RMS
    then max) within ``FAMILY_SHARE`` of its own choice's (``own[k]``, the same figures) and
    whose weights are ``steady(candidate)`` (fewer terms: smaller, steadier weights, so sensors
    like the members fit the memory too); if none is both, the steady one whose worst member
    is nearest its own (the first of equals), said in a warning, else the last."""
    calm: dict = {}

    def is_steady(c):
        if c not in calm:
            calm[c] = steady(c)
        return calm[c]

    def within(c):
        return all(np.all(np.atleast_1d(held[c]) <= FAMILY_SHARE * np.atleast_1d(mine))
                   for held, mine in zip(table, own))

    def worst(c):
        return max(float(h / m) if m > 0 else np.inf for held, mine in zip(table, own)
                   for h, m in zip(np.atleast_1d(held[c]), np.atleast_1d(mine)))

    found = next((c for c in tried if within(c) and is_steady(c)), None)
    if found is None:
        found = min((c for c in tried if is_steady(c)), key=worst, default=tried[-1])
        warnings.warn(f"no shared term count keeps every member's held-out error within {FAMILY_SHARE:g} x its "
                      f"own design's ({len(tried)} candidates tried): {describe(found)}, the most "
                      f"accurate with steady weights, leave the worst member at {worst(found):.2f} x its own",
                      stacklevel=2)
    return found


# the family design's temperature orders take these expansion sizes (the design needs >= 2)
THERMAL_TERMS = tuple(n for n in thermal_train.AUTO_TERMS if n >= 2)
# A family with temperature takes the one-input family's ridges: on bench/thermal_line.py 1e-10
# holds out 0.0021 mm with 19 terms, where 1e-6 alone holds out 0.0048 mm with 25.
THERMAL_RIDGES = FAMILY_RIDGES


def family_thermal_terms(members, *, orders: int, temperature_norm: tuple[float, float], norm: str,
                         ridges=THERMAL_RIDGES, margin: float = 0.5) -> tuple[int, float, list[MemberChoice]]:
    """(terms per temperature order, ridge, per-member choices) for ``members``: (name,
    voltage_v, temperature_c, displacement_mm) tuples, fitted as x = sum_j t_n^j f_j(v) with
    ``orders`` orders, t_n = (T - offset) / scale for ``temperature_norm`` (the design's), the
    voltage normalisation ``norm`` and no input correction.  A member's own choice is
    :func:`flann.golden.thermal_train.select_thermal` over the ridges down to the least of
    ``ridges``; the family's count and ridge are :func:`shared_terms` of the held-out RMS at
    each of ``ridges``."""
    ridges = tuple(sorted(ridges, reverse=True))
    own_ridges = tuple(sorted({*(r for r in thermal_train.AUTO_RIDGES if r >= ridges[-1]), *ridges}))
    own, table = [], []
    for name, v, t, x in members:
        run = thermal_train.cross_validate_thermal(v, t, x, orders=orders, terms=THERMAL_TERMS, norms=(norm,),
                                                   ridges=own_ridges, temperature_norm=temperature_norm,
                                                   correct_input=False, source=name)
        choice, _best, _good = thermal_train.select_thermal(run.results, x)
        # compared over the position folds: with three temperatures the held-out middle one's
        # error (the temperature orders') swamped the terms', and 19 terms passed for 41
        own.append((name, v, t, x, choice))
        table.append({(r.terms[0], r.ridge): r.position_rms_mm for r in run.results if r.ridge in ridges})
    top = max(c.terms[0] for *_m, c in own)
    tried = [(n, r) for n in THERMAL_TERMS if n <= top for r in ridges if all((n, r) in held for held in table)]
    if not tried:
        raise FlannError("--terms auto: the members' recordings are too few points for a common term count")

    def steady(key):
        n, ridge = key
        fits = [thermal_train.fit_thermal(v, t, x, (n,) * orders, norm=norm, ridge=ridge, correct_input=False,
                                          temperature_norm=temperature_norm) for _n, v, t, x, _c in own]
        return all(_steady([(m.bias[j], m.weights[j]) for m in fits], margin) for j in range(orders))

    key = shared_terms(tried, table, [c.position_rms_mm for *_m, c in own], steady,
                       describe=lambda k: f"{k[0]} terms at ridge {k[1]:g}")
    out = [MemberChoice(name, c.terms[0], c.ridge, c.position_rms_mm, None, held[key])
           for (name, _v, _t, _x, c), held in zip(own, table)]
    return key[0], key[1], out


__all__ = ["CALIBRATE_RIDGES", "DEFAULT_RIDGE", "FAMILY_RIDGES", "MemberChoice", "family_terms",
           "family_thermal_terms", "ridge_ladder", "shared_terms", "THERMAL_RIDGES", "THERMAL_TERMS"]


# a member whose error in the family design exceeds its own design's by more than this is
# flagged (calibrate, certificate): the shared design costs that sensor accuracy
REACH_FACTOR = 1.5


def own_reach_mm(voltage_v, displacement_mm, cost=None, received=None) -> tuple[float, int]:
    """(max |error| on the recording itself, terms) of the sensor's own direct fit of x(v)
    (``--terms auto``'s cross-validated choice): what its own design would reach on the same
    points (the float model; its hardware is within an output LSB of it).  The direct fit,
    not the forward curve's inverse ``train`` now writes: on the noisy points it was fitted
    to, it is the stricter yardstick.  ``received(voltage_v)``: the voltages as the design's
    converter hands them on (its codes' voltages), which the model is asked at, as the
    hardware it is compared with is: three members of a 10-bit design of 12-bit recordings
    were flagged at 1.85-2.60x their own reach at the recordings' voltages, and are 0.99-1.00x
    it at the design's codes."""
    model, choice = fit_auto(voltage_v, displacement_mm, cost=cost)
    v = np.asarray(voltage_v, dtype=float) if received is None else received(voltage_v)
    err = np.abs(model.predict(v) - np.asarray(displacement_mm, dtype=float))
    return float(np.max(err)), choice.terms


__all__ += ["REACH_FACTOR", "own_reach_mm"]
