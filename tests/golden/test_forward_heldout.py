"""The screen's held-out predictions of every candidate at once (one factorisation per fold)
against each candidate fitted fold by fold on its own basis."""

import numpy as np
import pytest

from flann.golden.forward import aggregate, candidates, heldout_all, heldout_predictions, position_folds


def _positions(n, noise_v, seed):
    x = np.linspace(-10.0, 10.0, n)
    rng = np.random.default_rng(seed)
    v = 3.0 * (x / 7) / (1 + np.abs(x / 7) ** 2.5) ** 0.4 + rng.normal(0, noise_v, n)
    w = rng.uniform(0.5, 2.0, n)   # unequal weights: each position's count over its noise
    return aggregate(np.concatenate([x, x]), np.concatenate([v, v + rng.normal(0, noise_v, n)]),
                     np.concatenate([w, w]))


# 30: too few rows to factor either kind; 60: polynomials factored, splines fold by fold; 120: both
@pytest.mark.parametrize("n", [30, 60, 120])
def test_every_candidate_as_fitted_alone(n):
    pos = _positions(n, 1e-3, n)
    folds = position_folds(pos.x.size)
    cands = candidates(pos)
    fast = heldout_all(cands, pos, folds)
    held = np.concatenate(folds)
    for sm, got in zip(cands, fast):
        want = heldout_predictions(sm, pos, folds)
        assert np.all(np.isnan(got[1:-1]) == np.isnan(want[1:-1])), sm
        scale = max(1.0, float(np.max(np.abs(want[held]))))
        assert np.max(np.abs(got[held] - want[held])) <= 1e-9 * scale, sm
