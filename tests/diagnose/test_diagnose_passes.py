"""The diagnosis as passes: each returns a new frozen result and changes nothing it was given."""

import dataclasses
import json
import warnings

import numpy as np
import pytest

from flann.diagnose import diagnose
from flann.diagnose import pipeline as P
from flann.diagnose.report import to_json
from flann.physics.sensor import default_sensor
from flann.physics.simulate import simulate_recordings


@pytest.fixture(scope="module")
def rec():
    s = default_sensor().with_effect("backlash", deadband_mm=0.05)
    return simulate_recordings(s, step_mm=0.5, noise_v=0.002, seed=3)


def test_passes_compose_to_diagnose_and_leave_their_inputs_alone(rec):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        shape = P.shape_pass(rec)
        rails = P.rails_pass(shape)
        calib = P.calibration_pass(shape, rails)
        x_before = shape.data.x.copy()
        term = P.shape_term_pass(shape, calib)
        chosen = P.selection_pass(shape, rails, calib, term)
        dg = P.report_pass(shape, rails, calib, term, chosen)
        again = diagnose(rec)
    # a family with a shape term is a new family; the calibration's is as it was
    assert term.family is not calib.family
    assert calib.family.shape_ref is None and calib.family.terms == 0
    assert term.family.terms == term.terms
    assert np.array_equal(shape.data.x, x_before)
    for result in (shape, rails, calib, term, chosen, dg):
        with pytest.raises(dataclasses.FrozenInstanceError):
            result.source = "changed"
    assert "backlash" in dg.named
    assert json.dumps(to_json(dg), sort_keys=True) == json.dumps(to_json(again), sort_keys=True)
    # findings apart from the plot's arrays
    assert dg.plot.x.size == dg.plot.resid_after.size and "plot" not in to_json(dg)
