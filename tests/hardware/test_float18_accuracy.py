"""float18 design against its float model: the twin's error over every code and gen's warning."""

from __future__ import annotations

import dataclasses
import warnings
from math import erf

import numpy as np
import pytest

from flann.analysis.trace import run_trace
from flann.golden.train import fit_lms, fit_lstsq
from flann.hardware.float18.accuracy import float_model_error, warning_text
from flann.hardware.float18.spec import FlannF18Top, derive_f18_spec

WARNS = "off its float model"


def _sensor():
    """An asymmetric S-curve (not the project's physics) over +-25 mm, read forward and back
    with 0.8 mV noise on a 12-bit +-2.5 V converter."""
    x = np.arange(-25, 25.0001, 0.5)
    u = x - 1.3
    v = 1.9 * np.vectorize(erf)(u / 11.0) + 0.012 * (u / 10) ** 3 - 0.0004 * u ** 2 + 0.045
    rng = np.random.default_rng(1)
    v = np.r_[v, v[::-1]] + rng.normal(0, 0.0008, 2 * x.size)
    return np.round(v / (5 / 4096)) * (5 / 4096), np.r_[x, x[::-1]]


@pytest.fixture(scope="module")
def models():
    v, x = _sensor()
    # many terms, nearly no ridge, the inputs normalised to 0.85: the weights cancel (as
    # `flann train --terms auto` chose for this sensor)
    cancelling = fit_lstsq(v, x, 61, norm="0.85", ridge=1e-10)
    small = fit_lms(v, x, 11, eta=0.01, epochs=1000)
    return {"cancelling": cancelling, "small": small}


def _quiet_spec(model, bits):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return derive_f18_spec(model, input_bits=bits)


def test_cancelling_model_is_reported_with_the_trace_figure(models):
    spec = _quiet_spec(models["cancelling"], 10)
    e = float_model_error(spec)
    assert e.exhaustive and e.codes == spec.code_max - spec.code_min + 1
    # flann trace measures the same difference its own way (stage by stage)
    assert e.max_err_mm == pytest.approx(run_trace(models["cancelling"], "float18", input_bits=10).total["max_mm"],
                                         rel=1e-9)
    assert e.large and e.max_partial_mm > 10 * e.max_out_mm
    text = warning_text(e, "f10")
    assert text.startswith("f10: ") and f"{e.max_err_mm:.3g} mm" in text and "partial sums" in text


def test_small_lms_model_is_not_reported(models):
    for bits in (8, 10, 12):
        e = float_model_error(_quiet_spec(models["small"], bits))
        assert not e.large, (bits, e)
        assert warning_text(e) is None


def test_threshold_is_the_models_own_error(models):
    """The same design is not reported for a model that records a larger error of its own."""
    spec = _quiet_spec(models["cancelling"], 10)
    e = float_model_error(spec)
    coarse = dataclasses.replace(models["cancelling"], training={"cv_heldout_rms_error_mm": 2 * e.max_err_mm})
    assert not float_model_error(_quiet_spec(coarse, 10)).large


def test_wide_inputs_are_sampled_ends_included(models):
    spec = _quiet_spec(models["cancelling"], 12)
    full = float_model_error(spec)
    part = float_model_error(spec, limit=1000)
    assert not part.exhaustive and part.codes <= 1000 < full.codes
    assert part.max_err_mm <= full.max_err_mm
    twin = FlannF18Top(spec)
    ends = np.array([spec.code_min, spec.code_max])
    assert part.max_err_mm >= np.abs(twin.out_mm(ends) - spec.float_reference(ends)).max()


def test_gen_warns_for_the_cancelling_model_only(models, tmp_path, cli):
    for name, model in models.items():
        path = tmp_path / f"{name}.json"
        path.write_text(model.to_json())
        rc, _out, err = cli(["gen", path, "-o", tmp_path / name, "--input-bits", 10, "--format", "float18"])
        assert rc == 0
        assert (WARNS in err) == (name == "cancelling"), (name, err)
