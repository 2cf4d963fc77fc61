"""flann eval on a recording wider than the model's trained displacement range: the points
beyond it are counted in one warning line; the figures are reported as before (exit 0)."""

import json

import numpy as np

import pytest

from flann.golden.model import FlannModel, load_model


@pytest.fixture
def model(tmp_path):
    # y = 2 v over [-2, 2] V, trained on [-4, 4] mm
    p = tmp_path / "m.json"
    p.write_text(FlannModel(weights=(2.0,), bias=0.0, input_offset_v=0.0, input_scale_v=1.0,
                            voltage_range_v=(-2.0, 2.0), displacement_range_mm=(-4.0, 4.0)).to_json())
    return p


def test_points_beyond_the_trained_stroke_are_counted(cli, tmp_path, model):
    # x = 2 v everywhere; -6, -5, 5 and 6 mm lie outside [-4, 4] (4 of 9), -4 and 4 on its ends
    data = tmp_path / "wide.csv"
    data.write_text("displacement_mm,voltage_v\n" + "".join(
        f"{x},{x / 2}\n" for x in (-6, -5, -4, -2, 0, 2, 4, 5, 6)))
    rc, out, err = cli(["eval", model, data, "--json"])
    assert rc == 0
    stroke = [ln for ln in err.splitlines() if "displacement range" in ln]
    assert len(stroke) == 1 and stroke[0].startswith("warning: ")
    assert "4 of 9 points" in stroke[0] and "[-4, 4] mm" in stroke[0]
    # the figures as before: clamped at +-2 V -> +-4 mm, so the worst point is 2 mm off
    assert json.loads(out)["compensated"]["max_error_mm"] == pytest.approx(2.0)
    text = tmp_path / "wide_text.csv"   # another name: an identical warning is shown once a process
    text.write_text(data.read_text())
    rc, out, err = cli(["eval", model, text])
    assert rc == 0 and "max error (mm)" in out
    assert sum("displacement range" in ln for ln in err.splitlines()) == 1


def test_no_warning_within_the_trained_stroke(cli, tmp_path, model):
    data = tmp_path / "in.csv"
    data.write_text("displacement_mm,voltage_v\n-4,-2\n0,0\n4,2\n")
    rc, _, err = cli(["eval", model, data])
    assert rc == 0 and "displacement range" not in err


def test_eval_design_clamps_the_float_model_as_its_compensated_figures_do(cli, tmp_path, small_designs):
    """Beyond the trained range the hardware section compared the hardware with the float
    model's unclamped sum (|hardware - float| 0.045 mm on a 12-bit design whose datapath is
    within 0.001 mm), and its float ratio to the limit disagreed with the compensated max."""
    m = load_model(small_designs["model"])
    lo, hi = sorted(m.voltage_range_v)
    v = np.linspace(lo - 0.15 * (hi - lo), hi + 0.15 * (hi - lo), 61)
    data = tmp_path / "wide.csv"
    data.write_text("displacement_mm,voltage_v\n" + "".join(
        f"{x:.12g},{a:.12g}\n" for x, a in zip(m.predict(np.clip(v, lo, hi)), v)))
    rc, out, err = cli(["eval", small_designs["model"], data, "--design", small_designs["dir"] / "fixed", "--json"])
    assert rc == 0, err
    rep = json.loads(out)
    hw = rep["hardware"]
    float_max = hw["float_ratio_to_limit"] * hw["physical_limit_mm"]["max"]
    assert float_max == pytest.approx(rep["compensated"]["max_error_mm"], rel=1e-9, abs=1e-12)
    # with the float model clamped like the hardware, the two differ by the datapath and the ADC's step
    assert hw["max_abs_hardware_minus_float_mm"] < 0.05 * float(np.ptp(m.predict(np.array([lo, hi]))))
