"""An effect forward selection stopped short of: BIC prefers it, by less than the margin that
names an effect.  It is offered as the one alternative beside the choice, with the measurement
that reveals it; the demo counts "either A or B" right when the hidden set is that one
alternative."""

import warnings

import pytest

from flann.diagnose import demo as DM
from flann.diagnose import demo_independent as IND
from flann.diagnose.confound import UNDECIDED_BIC, _CURVE_CONFOUNDED
from flann.diagnose.select import BIC_MARGIN


def _ind(name):
    case = next(c for c in IND.CASES if c.name.startswith(name))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return IND.run_case(case)


def test_offset_with_the_null_free_is_offered_beside_nothing():
    # a 3 mV offset, null free, one pass off-centre: fitted 19 +- 6 mV, BIC lower by 3.1
    res = _ind("null_offset below noise")
    assert res.named == [] and res.alternatives == [["null_offset"]]
    assert any("both secondary amplitudes" in m for m in res.separate_by)
    assert res.right
    assert not res.named_right      # a detection limit counts only the set named


def test_offset_beside_backlash_is_offered_with_it():
    res = _ind("two at once: backlash + null_offset")
    assert res.named == ["backlash"]
    assert [sorted(a) for a in res.alternatives] == [["backlash", "null_offset"]]
    assert any("both secondary amplitudes" in m for m in res.separate_by)
    assert res.right


def test_a_period_on_few_points_is_not_offered():
    # a lead-screw period lowered BIC by 2.7 on this 48-point control: the period is searched
    # over many, which BIC's ln n does not charge; only the curve-confounded effects are offered
    assert "leadscrew_periodic" not in _CURVE_CONFOUNDED
    case = next(c for c in DM.CASES if c.name.startswith("control: other geometry"))
    res = DM.run_case(case)
    assert res.named == [] and res.alternatives == []


def test_thresholds_are_between_a_bare_mention_and_the_margin():
    assert 0 < UNDECIDED_BIC < BIC_MARGIN


@pytest.mark.parametrize("truth, named, alternatives, separate_by, right", [
    (["a"], ["a"], [], [], True),
    (["a"], [], [["a"]], ["m"], True),                  # either nothing or a: this tells
    (["a", "b"], ["b"], [["a", "b"]], ["m"], True),
    (["a"], [], [["a"]], [], False),                   # no measurement named
    (["a"], [], [["b"], ["a"]], ["m"], False),          # more than two explanations
    (["a"], ["b"], [], [], False),
    ([], [], [["a"]], ["m"], False),                    # a control: nothing offered
    ([], [], [], [], True),
    ([], ["a"], [], [], False),
])
def test_judged_right(truth, named, alternatives, separate_by, right):
    assert IND.judged_right(truth, named, 0, alternatives, separate_by) is right
