"""flann sim of a family design measures the hardware against each image's float model: the
model the design keeps beside each member's image, and the model.json flann calibrate wrote
beside a sensor's image when the image's header names that model's sha256 (another file
there is not the image's: no figure is better than a wrong one)."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from flann.cli import main
from flann.golden.model import load_model
from flann.hardware.family.images import read_image
from flann.hardware.family.render import load_design
from flann.hardware.family.twin import FlannFamilyTop
from flann.recordings import write_recordings

from test_calibrate_closed_form import sweep

pytestmark = pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl not installed")


def _max_err_mm(design_dir, image, model_path) -> float:
    """The twin holding ``image`` against the model at every code, the model's voltages
    clamped to its range as the hardware clamps the codes (computed here)."""
    fam = load_design(design_dir)
    s, model = fam.spec, load_model(model_path)
    codes = np.arange(s.code_min, s.code_max + 1)
    lo, hi = sorted(model.voltage_range_v)
    volts = np.clip(codes, np.floor(lo / s.input_lsb_v + 0.5), np.floor(hi / s.input_lsb_v + 0.5)) * s.input_lsb_v
    out = FlannFamilyTop(fam, read_image(image)).process(codes)[0] * s.output_lsb_mm
    return float(np.max(np.abs(out - model.predict(volts))))


def test_each_image_is_measured_against_its_model(tmp_path, capsys):
    for name, (amp, asym, seed) in {"a": (3.0, 0.02, 0), "b": (3.1, -0.01, 1), "c": (2.95, 0.0, 2)}.items():
        write_recordings(tmp_path / f"{name}.csv", sweep(amp, asym, seed))
    d = tmp_path / "d"
    assert main(["gen", "--family", str(tmp_path / "a.csv"), str(tmp_path / "b.csv"), "-o", str(d),
                 "--input-bits", "8", "--terms", "11"]) == 0
    assert main(["calibrate", str(tmp_path / "c.csv"), "-o", str(tmp_path / "cal"), "--design", str(d)]) == 0
    image = tmp_path / "cal" / "c" / "weights.hex"
    capsys.readouterr()
    assert main(["sim", str(d), "--image", str(image), "--json", "--build", str(tmp_path / "b")]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["mismatches"] == 0 and s["all_passed"]
    per = s["image_max_err_mm"]
    assert set(per) == {"d/a", "c/weights"}, per
    want = {"d/a": _max_err_mm(d, d / "image_a.hex", d / "model_a.json"),
            "c/weights": _max_err_mm(d, image, tmp_path / "cal" / "c" / "model.json")}
    for n, w in want.items():
        assert per[n] == pytest.approx(w, abs=2e-6), (n, per[n], w)
    assert s["max_err_mm"] == pytest.approx(max(want.values()), abs=2e-6)
    assert s["max_err_mm"] <= s["output_lsb_mm"]             # within the design's 1-LSB bound
    # another sensor's model.json beside the image: not the image's, so no figure
    shutil.copy(tmp_path / "cal" / "c" / "weights.hex", tmp_path / "c_copy.hex")
    (tmp_path / "model.json").write_text((d / "model_b.json").read_text())
    assert main(["sim", str(d), "--image", str(tmp_path / "c_copy.hex"), "--json", "--build",
                 str(tmp_path / "b2")]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["image_max_err_mm"]["c_copy"] is None and s["image_max_err_mm"]["d/a"] is not None
