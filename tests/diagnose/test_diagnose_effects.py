"""flann diagnose on simulator recordings: every effect's signature is named, controls stay quiet.

Recordings come from the physics simulator with fixed seeds (600 points, 5 mV noise; the
effects at about twice the sizes of `flann diagnose --demo`, which uses 2001 points, so the
evidence per effect is similar).  Expected values are the simulator's true parameters.
"""

import math
import warnings

import numpy as np
import pytest

from flann.diagnose import diagnose
from flann.diagnose.demo import CASES, case_sensor, resolved_effects, simulate_case

POINTS = 600


def _case(prefix):
    return next(c for c in CASES if c.name.startswith(prefix))


def _run(case, scale=1.0, seed=None):
    rec = simulate_case(case, scale=scale, seed=seed, points=None if case.step_mm > 0.5 else POINTS)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(rec, sensor=case_sensor(case) if case.known_sensor else None)


CONTROLS = ["control: paper", "control: other geometry", "control: miniature",
            "control: rectified"]


@pytest.mark.parametrize("prefix", CONTROLS)
def test_control_claims_nothing(prefix):
    dg = _run(_case(prefix), seed=101)
    assert dg.named == []
    assert dg.regions == []
    # the calibrated ideal simulation fits to the noise (5 mV simulated)
    assert dg.final_rms < 0.0065
    assert 0.0035 < dg.noise_v < 0.0065


# (case prefix, scale, words the explanation must contain)
SIGNATURES = [
    ("null_offset", 2.0, ["same", "every displacement", "offset"]),
    ("quadrature_null", 4.0, ["never falls to zero", "quadrature"]),
    # 4x: at 2x a 10 um shift and a secondary imbalance fit these 600 points within 5 BIC of
    # each other and are reported as alternatives (test_small_zero_shift_is_confounded...)
    ("zero_shift", 4.0, ["slope", "null"]),
    ("secondary_imbalance", 3.0, ["both halves", "secondaries"]),
    ("backlash", 2.0, ["direction of travel", "slope", "lost motion"]),
    ("thermal_drift", 1.0, ["temperature", "sensitivity"]),
    ("adc_clipping", 1.0, ["flat", "rail"]),
    ("leadscrew_periodic", 2.0, ["period", "lead screw"]),
]


@pytest.mark.parametrize("prefix, scale, words", SIGNATURES)
def test_effect_signature_named_and_recovered(prefix, scale, words):
    case = _case(prefix)
    effect, param = case.main
    true = resolved_effects(case)[effect][param] * scale
    dg = _run(case, scale=scale, seed=202)
    assert dg.named == [effect]
    e = dg.effects[0]
    param = {"rail_v": "rail_high_v"}.get(param, param)  # each rail is fitted on its own
    got = e.params[param]["value"]
    se = e.params[param]["stderr"]
    assert se is not None and se > 0
    assert abs(abs(got) - abs(true)) < max(4 * se, 0.05 * abs(true)), (got, se, true)
    for w in words:
        assert w in e.explanation
    assert e.explanation.count(".") >= 1 and "\n" not in e.explanation
    assert e.delta_bic < -10
    assert e.rms_v_after < dg.baseline_rms
    assert math.isclose(dg.final_rms, e.rms_v_after, rel_tol=1e-6)


def test_small_zero_shift_is_confounded_with_an_imbalance():
    """Both are even in the displacement; on 600 points a 10 um shift and an imbalance fit
    within 6 BIC of each other: the report ranks the truth first as the choice, gives the
    imbalance as the first single-effect alternative with its figures (mixtures of the two
    with an offset may rank beside it), and says what would tell them apart."""
    dg = _run(_case("zero_shift"), scale=2.0, seed=202)
    assert dg.named == ["zero_shift"]
    alt = next(a for a in dg.alternatives if len(a.named) == 1)
    assert alt.named == ["secondary_imbalance"]
    assert 0 < alt.delta_bic < 6
    assert alt.rms_v > 0 and alt.effects[0].params["imbalance_fraction"]["stderr"] > 0
    assert dg.explanations[0] == ["zero_shift"] and dg.shared == []
    # ranked: every later alternative is further behind
    assert all(a.delta_bic <= b.delta_bic for a, b in zip(dg.alternatives, dg.alternatives[1:]))
    sep = next(s for s in dg.separate_by if {s.a, s.b} == {"zero_shift", "secondary_imbalance"})
    assert "both secondary amplitudes" in sep.measurement


def test_two_effects_at_once():
    """The 3 mV offset beside the backlash fits within 6 BIC of an imbalance on these 600
    points: the choice is backlash + null_offset (the truth), every alternative keeps the
    backlash."""
    case = _case("two at once: backlash")
    dg = _run(case, seed=303)
    assert sorted(dg.named) == ["backlash", "null_offset"]
    assert dg.alternatives and all("backlash" in a.named for a in dg.alternatives)
    assert dg.shared == ["backlash"]
    assert all(a.delta_bic <= b.delta_bic for a, b in zip(dg.alternatives, dg.alternatives[1:]))
    # the RMS falls at every added effect
    rms = [dg.baseline_rms] + [e.rms_v_after for e in dg.effects]
    assert all(a > b for a, b in zip(rms, rms[1:]))
    assert dg.improvement > 1


def test_backlash_region_is_both_directions_at_the_null():
    case = _case("backlash")
    dg = _run(case, scale=6.0, seed=404)  # 60 um: +-9 mV, above the noise
    assert dg.named == ["backlash"]
    assert any(r["direction"] == "both" and r["from_mm"] < 0 < r["to_mm"] for r in dg.regions)


def test_glitch_is_an_outlier_not_physics():
    case = _case("control: paper")
    rec = simulate_case(case, seed=505, points=POINTS)
    v = rec.voltage_v.copy()
    v[137] += 0.08  # one reading 16 x the noise off
    from flann.recordings import Recordings
    rec = Recordings(rec.displacement_mm, v, rec.direction, rec.time_s, rec.temperature_c)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dg = diagnose(rec)
    assert [o["row"] for o in dg.outliers] == [137]
    assert abs(dg.outliers[0]["residual_v"] - 0.08) < 0.02
    assert dg.named == []


def test_rectified_output_recognised():
    case = _case("control: rectified")
    rec = simulate_case(case, seed=606, points=POINTS)
    with pytest.warns(UserWarning, match="rectified"):
        dg = diagnose(rec)
    assert any("rectified" in n for n in dg.notes)
    assert np.all(rec.voltage_v > -0.03)  # the simulated output really is unsigned


def test_units_inches_and_millivolts_claim_nothing():
    # the paper LVDT recorded in inches and millivolts, falling, null at 1 inch: a control
    case = _case("control: paper")
    rec = simulate_case(case, seed=707, points=POINTS)
    from flann.recordings import Recordings
    rec = Recordings(rec.displacement_mm / 25.4 + 1.0, -1000 * rec.voltage_v, rec.direction,
                     rec.time_s, rec.temperature_c)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dg = diagnose(rec)
    assert dg.named == [] and dg.regions == []
    assert abs(dg.baseline_params["displacement_scale"]["value"] - 25.4) < 0.5
    assert abs(dg.baseline_params["origin_mm"]["value"] - 1.0) < 0.01
    assert 3.5 < dg.noise_v < 6.5  # the simulated 5 mV, recorded as 5 units of mV
