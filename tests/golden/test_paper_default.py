"""What `flann paper` calls the tool's default is what `flann train` writes: one procedure
(`flann.golden.inverse.fit_default`), not a copy that can drift from it."""

from __future__ import annotations

import numpy as np

from flann.cli import main
from flann.golden.model import load_model
from flann.golden.paper import default_fit, table1
from flann.hardware.fixed.cost import fixed_point_cost


def test_papers_default_row_is_the_model_train_writes(table1_csv, tmp_path, capsys):
    assert main(["train", str(table1_csv), "-o", str(tmp_path / "m.json")]) == 0
    trained = load_model(tmp_path / "m.json")
    fit = default_fit(table1(), fixed_point_cost)
    assert fit.model.terms == trained.terms
    np.testing.assert_allclose(fit.model.weights, trained.weights, rtol=1e-12, atol=1e-12)
    assert f"{trained.terms} terms" in fit.label
    capsys.readouterr()
    assert main(["paper"]) == 0
    assert f"flann train default (--terms auto): {fit.label}" in capsys.readouterr().out
