"""Training: one LMS step, least squares and ridge by hand; auto, LOO, determinism."""

import json

import numpy as np
import pytest

from flann.errors import FlannError, RecordingsError
from flann.golden.model import expand
from flann.golden.paper import s_curve
from flann.golden.train import (CvResult, as_good, design_matrix, check_fit_input, cv_folds, fit_auto,
                                fit_lms, fit_lstsq,
                         lms_epochs, lms_leave_one_out, lms_sequential,
                         normalisation)


def test_one_lms_step_by_hand():
    # s = [1 (bias), v] = [1, 2], w = [1, 1] -> y = 3, e = 5 - 3 = 2
    # w <- w + 0.1 * 2 * [1, 2] = [1.2, 1.4]; epoch MSE = e^2 = 4
    m = fit_lms([2.0], [5.0], 1, eta=0.1, epochs=1, offset_scale=(0.0, 1.0))
    assert m.bias == pytest.approx(1.2)
    assert m.weights == pytest.approx((1.4,))
    assert m.training["mse_per_epoch"] == pytest.approx([4.0])
    assert m.training["weights_start"] == 1.0


def test_two_lms_steps_in_file_order_by_hand():
    # after step 1 w = [1.2, 1.4]; sample (v=1, d=0): y = 2.6, e = -2.6
    # w <- [1.2, 1.4] - 0.26 * [1, 1] = [0.94, 1.14]; MSE = (4 + 6.76) / 2 = 5.38
    m = fit_lms([2.0, 1.0], [5.0, 0.0], 1, eta=0.1, epochs=1, offset_scale=(0.0, 1.0))
    assert (m.bias, *m.weights) == pytest.approx((0.94, 1.14))
    assert m.training["mse_per_epoch"] == pytest.approx([5.38])


def test_least_squares_line_by_hand():
    # v = [0, 2, 4] -> range normalisation offset 2, scale 2, v_n = [-1, 0, 1]; x = [1, 3, 4]
    # slope = sum(v_n (x - 8/3)) / sum(v_n^2) = (5/3 + 4/3) / 2 = 1.5; bias = mean x = 8/3
    m = fit_lstsq([0.0, 2.0, 4.0], [1.0, 3.0, 4.0], 1)
    assert (m.input_offset_v, m.input_scale_v) == (2.0, 2.0)
    assert m.weights[0] == pytest.approx(1.5)
    assert m.bias == pytest.approx(8 / 3)


def test_ridge_by_hand():
    # minimise mean(e^2) + lam w^2 with centred v_n = [-1, 0, 1]:
    # w = sum(v_n x) / (sum v_n^2 + n lam) = 3 / (2 + 3 lam); lam = 1/3 -> w = 1; bias unpenalised
    m = fit_lstsq([0.0, 2.0, 4.0], [1.0, 3.0, 4.0], 1, ridge=1 / 3)
    assert m.weights[0] == pytest.approx(1.0)
    assert m.bias == pytest.approx(8 / 3)


def test_underdetermined_lstsq_is_minimum_norm_by_hand():
    # one point, bias + v: b + w*1 = 2 with min b^2 + w^2 -> b = w = 1
    m = fit_lstsq([1.0], [2.0], 1, offset_scale=(0.0, 1.0))
    assert (m.bias, m.weights[0]) == pytest.approx((1.0, 1.0))


def test_more_terms_than_points_warns_but_fits(recwarn):
    with pytest.warns(UserWarning, match="under-determined"):
        check_fit_input(np.arange(13.0), np.arange(13.0), 51)


@pytest.mark.parametrize("v", [[1.0, 2.0], [1.0, 1.0, 1.0]])
def test_too_few_points_to_fit(v):
    with pytest.raises(RecordingsError, match="need at least"):
        check_fit_input(np.array(v), np.arange(len(v), dtype=float), 1)


def test_range_and_raw_normalisation():
    assert normalisation([-5.185, 5.276], "range") == pytest.approx((0.0455, 5.2305))
    assert normalisation([-5.185, 5.276], "half") == pytest.approx((0.0455, 10.461))
    assert normalisation([-5.185, 5.276], "none") == (0.0, 1.0)
    # a fraction f maps the range to [-f, f]: the ends at -0.85 and +0.85
    offset, scale = normalisation([-5.185, 5.276], "0.85")
    assert ((-5.185 - offset) / scale, (5.276 - offset) / scale) == pytest.approx((-0.85, 0.85))


@pytest.mark.parametrize("kind", ["0", "1.5", "-0.5", "nan", "wide"])
def test_a_normalisation_neither_named_nor_in_zero_to_one_is_refused(kind):
    with pytest.raises(FlannError, match="normalisation must be one of range, half, none"):
        normalisation([0.0, 1.0], kind)


def test_lms_diverges_with_a_clear_error():
    with pytest.raises(FlannError, match="smaller --eta"):
        fit_lms([5.0, -5.0, 4.0], [1.0, 2.0, 3.0], 11, eta=5.0, epochs=50,
                offset_scale=(0.0, 1.0))


def test_fast_lms_equals_the_literal_sample_by_sample_loop():
    v = np.array([-5.185, -2.896, 0.001, 1.810, 4.799, 5.276])
    x = np.array([-30.0, -10.0, 0.0, 10.0, 20.0, 30.0])
    S = design_matrix(v, 11)
    w_fast, mse_fast = lms_epochs(S, x, 0.02, 200)
    w_ref, mse_ref = lms_sequential(S, x, 0.02, 200)
    np.testing.assert_allclose(w_fast, w_ref, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(mse_fast, mse_ref, rtol=1e-9, atol=1e-12)


def test_batched_leave_one_out_equals_separate_runs():
    v = np.array([-2.0, -1.1, 0.2, 0.9, 2.3])
    x = np.array([-3.0, -1.0, 0.5, 1.0, 3.5])
    S = design_matrix(v / 2.3, 5)
    pred = lms_leave_one_out(S, x, 0.05, 40)
    for i in range(v.size):
        keep = np.arange(v.size) != i
        w, _ = lms_sequential(S[keep], x[keep], 0.05, 40)
        assert pred[i] == pytest.approx(S[i] @ w, abs=1e-12)


def test_cv_never_holds_out_the_voltage_extremes():
    v = np.array([3.0, -1.0, 0.0, 5.0, 1.0, 2.0])   # min at row 1, max at row 3
    held = np.concatenate(cv_folds(v, 2))
    assert sorted(held.tolist()) == [0, 2, 4, 5]


def test_auto_on_a_straight_line_picks_the_linear_term_alone():
    v = np.linspace(-4.0, 4.0, 21)
    model, choice = fit_auto(v, 3.0 * v + 1.0)
    assert choice.terms == 1
    assert model.predict([2.5])[0] == pytest.approx(8.5, abs=1e-6)


def test_auto_held_out_error_is_honest_on_new_points():
    x = np.linspace(-30.0, 30.0, 121)
    model, choice = fit_auto(s_curve(x, 1e-3, seed=5), x)
    assert model.training["cv_heldout_rms_error_mm"] == choice.rms_mm
    x_new = np.linspace(-29.75, 29.75, 120)
    rms_new = np.sqrt(np.mean((model.predict(s_curve(x_new, 1e-3, seed=6)) - x_new) ** 2))
    assert 0.33 * choice.rms_mm < rms_new < 3.0 * choice.rms_mm


def _cv(name, errors):
    e = np.asarray(errors, dtype=float)
    return CvResult(len(name), name, 0.0, float(np.sqrt(np.mean(e**2))), float(np.max(np.abs(e))), e)


def test_as_good_compares_on_the_same_held_out_points_by_hand():
    ref = _cv("r", [1.0, -1.0, 2.0, -2.0])                 # squared: 1 1 4 4
    worse = _cv("w", [1.1, -1.1, 2.1, -2.1])               # d = .21 .21 .41 .41: mean .31, se .0577
    same = _cv("s", [-1.0, 1.0, -2.0, 2.0])                # d = 0
    noisy = _cv("n", [1.2, -0.8, 2.0, -2.0])               # d = .44 -.36 0 0: mean .02, se .1684
    got = as_good([ref, worse, same, noisy], ref, z=0.5)
    assert got == [ref, same, noisy]
    # a candidate better on every point is always kept; a worse one only with a wide enough z
    assert as_good([_cv("b", [0.5, 0.5, 1.0, 1.0])], ref, z=0.0) != []
    assert as_good([worse], ref, z=5.3) == [] and as_good([worse], ref, z=5.4) == [worse]


def test_training_is_deterministic():
    x = np.linspace(-30.0, 30.0, 61)
    v = s_curve(x, 1e-3, seed=7)
    a = fit_lstsq(v, x, 25).to_json()
    b = fit_lstsq(v, x, 25).to_json()
    assert a == b
    assert fit_lms(v, x, 5, eta=0.01, epochs=5).to_json() == \
        fit_lms(v, x, 5, eta=0.01, epochs=5).to_json()
    json.loads(a)


# -- many rows (a logger's file): bounded time and memory, same answer ------------------------
def _by_hand_lstsq(v_n, x, terms, ridge):
    """Reference: the full design solved at once (normal equations with the ridge on the weights)."""
    A = np.hstack([np.ones((v_n.size, 1)), expand(v_n, terms)])
    P = np.eye(terms + 1) * v_n.size * ridge
    P[0, 0] = 0.0
    return np.linalg.solve(A.T @ A + P, A.T @ x)


def test_blockwise_lstsq_gives_the_full_solution(monkeypatch):
    import flann.golden.train as train

    monkeypatch.setattr(train, "LSTSQ_BLOCK_ROWS", 97)     # 1000 rows in 11 uneven blocks
    rng = np.random.default_rng(3)
    v = np.sort(rng.uniform(-2.0, 3.0, 1000))
    x = 10 * np.tanh(v) + rng.normal(0, 0.01, v.size)
    m = train.fit_lstsq(v, x, 7, norm="range", ridge=1e-6)
    v_n = (v - 0.5 * (v.min() + v.max())) / (0.5 * (v.max() - v.min()))
    ref = _by_hand_lstsq(v_n, x, 7, 1e-6)
    np.testing.assert_allclose([m.bias, *m.weights], ref, rtol=0, atol=1e-8)
    rms = np.sqrt(np.mean((m.predict(v) - x) ** 2))
    assert m.training["train_rms_error_mm"] == pytest.approx(rms, rel=1e-9)


def test_auto_on_many_rows_chooses_on_a_spread_subset_and_fits_all(monkeypatch):
    import flann.golden.train as train

    monkeypatch.setattr(train, "AUTO_MAX_CV_POINTS", 150)
    x = np.linspace(-30.0, 30.0, 1201)
    v = s_curve(x, 1e-3, seed=7)
    model, choice = train.fit_auto(v, x, terms_list=(1, 3, 5, 9), ridges=(0.0, 1e-6))
    assert model.training["cv_points"] == 150
    assert model.training["points"] == 1201                    # the choice is fitted on every row
    assert model.voltage_range_v == (v.min(), v.max())         # extremes kept: same normalisation
    sub = train.cv_subset(v)
    assert sub.size == 150 and v.argmin() in sub and v.argmax() in sub
    gaps = np.diff(np.sort(v[sub]))
    assert gaps.max() < 3 * gaps.mean()                        # spread over the voltage range


def test_repeated_sweeps_do_not_leak_into_the_held_out_error():
    # four sweeps over 21 positions, identical after a 12-bit converter: a held-out row must
    # not have its twin in the training set, else auto interpolates and reports ~0
    def sensor(x):
        return np.round(3.0 * np.tanh(x / 2.0) / (10.0 / 4096)) * (10.0 / 4096)

    x = np.tile(np.linspace(-2.5, 2.5, 21), 4)
    model, choice = fit_auto(sensor(x), x)
    x_new = np.linspace(-2.4, 2.4, 301)
    rms_new = np.sqrt(np.mean((model.predict(sensor(x_new)) - x_new) ** 2))
    assert 0.33 * rms_new < choice.rms_mm < 3.0 * rms_new


def test_cv_folds_hold_out_a_position_with_all_its_rows():
    v = np.array([0.0, 1.0, 2.0, 3.0, 4.0, 1.01, 2.01, 3.01])
    x = np.array([0.0, 1.0, 2.0, 3.0, 4.0, 1.0, 2.0, 3.0])
    folds = cv_folds(v, 3, groups=x)
    assert sorted(map(sorted, (f.tolist() for f in folds))) == [[1, 5], [2, 6], [3, 7]]
