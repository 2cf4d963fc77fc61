"""Sets one effect larger than the named one are compared too (confound.equivalent_sets), a
pair only when each of its effects earns its keep by BIC.  A stand-in family whose fits have
set residual sums keeps these cheap: the rule is statistics, not physics."""

import math

import numpy as np

from flann.diagnose.confound import UNSPLIT, equivalent_sets, with_mixtures
from flann.diagnose.select import BIC_MARGIN, Fit, Selection, Trial

N = 400
NOISE = 0.004


class Stand:
    """Each set's fit: one parameter per effect plus the baseline's, its residual RMS
    set so that its BIC is ``bic`` (BIC = n ln(RSS/n) + k ln n)."""

    def __init__(self, bic: dict):
        self.bic = {frozenset(k): v for k, v in bic.items()}

    def fit(self, effects, idx, start=None) -> Fit:
        key = frozenset(effects)
        k = 1 + len(effects)
        rms = math.sqrt(math.exp((self.bic[key] - k * math.log(N)) / N))
        # residuals of that RMS that differ from set to set only in their size
        resid = rms * np.where(np.arange(N) % 2, 1.0, -1.0)
        return Fit(tuple(effects), [f"{e}.p" for e in effects] + ["baseline.gain_ratio"],
                   np.zeros(k), np.zeros(k), resid, np.arange(N))

    def rechoose(self, effects, idx, fit):
        return fit


def _selection(family, named):
    base = family.fit([], None)
    final = family.fit(named, None)
    first = [Trial(c, family.bic[frozenset([c])] - base.bic, None, c in named)
             for c in ("x", "y", "z")]
    return Selection(base, [], [first], final, [])


def _bics(x, y, z, yz, **more):
    # the baseline far enough behind that the margin is the fixed one (6)
    out = {(): -1000.0, ("x",): x, ("y",): y, ("z",): z, ("y", "z"): yz,
           ("x", "y"): x + 3, ("x", "z"): x + 3}
    out.update(more)
    return out


def _sets(bics, named=("x",)):
    fam = Stand(bics)
    conf = equivalent_sets(fam, _selection(fam, list(named)), ("x", "y", "z"),
                           np.arange(N), tuple(named))
    return [frozenset(s) for s in conf.sets]


def test_a_pair_that_earns_each_effect_is_offered_beside_the_single():
    # y+z beats y and z alone by more than the margin, and is 3 behind x: equally good
    sets = _sets(_bics(x=-1300, y=-1285, z=-1280, yz=-1297))
    assert sets[0] == {"x"}
    assert {"y", "z"} in sets


def test_a_pair_whose_second_effect_does_not_pay_its_parameters_is_not_offered():
    # y+z beats y by less than the margin: the curve does not show z beside y
    sets = _sets(_bics(x=-1300, y=-1296, z=-1250, yz=-1296 - (BIC_MARGIN - 4)))
    assert {"y", "z"} not in sets
    assert all(len(s) == 1 for s in sets)


def test_a_pair_far_ahead_of_the_single_is_the_choice():
    # forward selection stopped at x (neither y nor z beside it helped); y+z is far better
    sets = _sets(_bics(x=-1300, y=-1260, z=-1250, yz=-1400))
    assert sets == [frozenset({"y", "z"})]


def test_a_single_inside_a_pair_that_earned_against_it_is_not_offered():
    # the baseline 1,310 behind: the margin is 1 % of that (13), so y alone (11 behind the
    # pair) would be near; but the pair beat it by more than an effect's margin
    bics = _bics(x=-1300, y=-1299, z=-1250, yz=-1310)
    bics[()] = 0.0
    sets = _sets(bics)
    assert {"y", "z"} in sets and {"x"} in sets
    assert {"y"} not in sets


EVEN = ("null_offset", "secondary_imbalance", "backlash")


def _mixed(pair_bic: float, backlash: float = -1200.0):
    """null_offset named, secondary_imbalance 2 BIC behind it (equally good); the pair of them
    at ``pair_bic``; backlash alone at ``backlash``."""
    o, i = -1300.0, -1298.0
    bics = {(): -1000.0, ("null_offset",): o, ("secondary_imbalance",): i,
            ("backlash",): backlash, ("null_offset", "secondary_imbalance"): pair_bic,
            ("null_offset", "backlash"): o + 6, ("secondary_imbalance", "backlash"): i + 6}
    fam = Stand(bics)
    base = fam.fit([], None)
    first = [Trial(c, fam.bic[frozenset([c])] - base.bic, None, c == "null_offset") for c in EVEN]
    sel = Selection(base, [], [first], fam.fit(["null_offset"], None), [])
    return with_mixtures(fam, np.arange(N), equivalent_sets(fam, sel, EVEN, np.arange(N),
                                                           ("null_offset",)))


def test_two_single_effects_the_curve_confounds_are_offered_together_too():
    # the pair: BIC's charge for one more parameter (ln 400 = 6) and 2 more behind the offset
    # alone; its second effect does not earn its keep, but the curve cannot tell either
    conf = _mixed(pair_bic=-1300 + math.log(N) + 2)
    sets = [frozenset(s) for s in conf.sets]
    assert sets[0] == {"null_offset"} and {"secondary_imbalance"} in sets
    mix = sets.index({"null_offset", "secondary_imbalance"})
    # its fit names the two effects whose shares the curve does not fix
    assert set(conf.fits[mix].extra[UNSPLIT]) == {"null_offset", "secondary_imbalance"}


def test_no_mixture_that_fits_worse_or_of_effects_the_curve_does_not_confound():
    # the pair fits worse than the offset alone by more than the margin beyond BIC's charge
    sets = [frozenset(s) for s in _mixed(pair_bic=-1300 + math.log(N) + 7).sets]
    assert {"null_offset", "secondary_imbalance"} not in sets and len(sets) == 2
    # backlash as good as the offset: no measurement separates it from the offset as a
    # confounded pair, so the two together are not offered
    sets = [frozenset(s) for s in _mixed(pair_bic=-1300 + math.log(N) + 7, backlash=-1299.0).sets]
    assert {"backlash"} in sets
    assert {"null_offset", "backlash"} not in sets
