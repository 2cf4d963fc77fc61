"""Few calibration positions: `flann train` fits the FLANN to the inverse of a forward spline
(flann.golden.sparse), judged against a sensor written here and the direct fit of x(v)."""

import json

import numpy as np
import pytest

from flann.cli import main as flann
from flann.golden.model import load_model
from flann.golden.sparse import SPARSE_POSITIONS, forward_curve, sparse_fit
from flann.golden.train import fit_auto


def sensor(x):
    """A saturating sensor of this test's own: the ends of +-20 mm roll off to a tenth of the
    slope at the null."""
    return 4.0 * np.tanh(x / 9.0) + 0.05 * np.tanh(x / 3.0) + 0.002


LSB = 2 * 4.2 / 2 ** 14


def recording(path, positions, seed, sweeps=1):
    rng = np.random.default_rng(seed)
    one = np.linspace(-20, 20, positions)
    x = np.concatenate([one if k % 2 == 0 else one[::-1] for k in range(sweeps)])
    v = np.round((sensor(x) + rng.normal(0, 3e-4, x.size)) / LSB) * LSB
    d = np.repeat([1 if k % 2 == 0 else -1 for k in range(sweeps)], positions) if sweeps > 1 else None
    rows = ["displacement_mm,voltage_v" + (",direction" if d is not None else "")]
    for i in range(x.size):
        rows.append(f"{x[i]:.9g},{v[i]:.9g}" + (f",{d[i]:+d}" if d is not None else ""))
    path.write_text("\n".join(rows) + "\n")
    return x, v


def held_out_max_mm(model):
    xt = np.linspace(-20, 20, 2001)
    lo, hi = sorted(model.voltage_range_v)
    return float(np.max(np.abs(model.predict(np.clip(sensor(xt), lo, hi)) - xt)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_thirteen_positions_fit_the_inverse_of_the_forward_spline(tmp_path, seed):
    rec, out = tmp_path / "rec.csv", tmp_path / "m.json"
    x, v = recording(rec, 13, seed)
    assert flann(["train", str(rec), "-o", str(out)]) == 0
    model = load_model(out)
    t = model.training
    assert t["forward_spline"] in ("cubic", "pchip")
    assert t["leave_one_out"]["positions"] == 11
    assert t["cv_heldout_rms_error_mm"] == pytest.approx(t["leave_one_out"]["rms_error_mm"])
    # against the direct fit of x(v) on the same readings (auto's own choice): the ends of
    # the stroke, where x(v) is steep, are where the direct fit swings between 13 points
    direct, _ = fit_auto(v, x)
    assert held_out_max_mm(model) < 0.25 * held_out_max_mm(direct)
    assert held_out_max_mm(model) < 0.1      # of a 40 mm stroke, noise 0.3 mV


def test_many_positions_keep_the_direct_fit(tmp_path):
    rec, out = tmp_path / "rec.csv", tmp_path / "m.json"
    recording(rec, SPARSE_POSITIONS, 3)
    assert flann(["train", str(rec), "-o", str(out)]) == 0
    t = json.loads(out.read_text())["training"]
    assert "forward_spline" not in t and "cv_folds" in t


def test_repeats_at_few_positions_are_averaged_into_the_spline(tmp_path):
    rec, out = tmp_path / "rec.csv", tmp_path / "m.json"
    recording(rec, 13, 4, sweeps=4)
    assert flann(["train", str(rec), "-o", str(out)]) == 0
    model = load_model(out)
    assert model.training["forward_spline"] in ("cubic", "pchip")
    assert held_out_max_mm(model) < 0.1


def test_no_monotone_curve_through_the_positions_is_no_spline():
    x = np.linspace(-20, 20, 9)
    v = sensor(x)
    v[-2], v[-1] = v[-1], v[-2]          # the last two positions read in the wrong order
    assert forward_curve(x, v) is None
    assert forward_curve(x[:4], sensor(x[:4])) is None      # too few positions
    assert forward_curve(x, sensor(x)) is not None


def test_no_candidate_that_builds_falls_back_to_the_direct_fit():
    x = np.linspace(-20, 20, 13)
    v = sensor(x)
    _, choice = fit_auto(v, x)
    never = sparse_fit(x, v, choice, lambda m: {"buildable": False, "why": "test", "cost": np.inf}, {})
    assert never is None
    built = sparse_fit(x, v, choice, lambda m: {"buildable": True, "why": "", "cost": float(m.terms),
                                                "luts": 0, "brams": 0, "weight_bits": 16,
                                                "term_bits": 16, "output_lsb_mm": 1e-3}, {})
    assert built is not None and built.training["forward_spline"] == "cubic"
