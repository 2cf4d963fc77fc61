"""A design directory is verified as generated: the twin rebuilt from its manifest (no simulation)."""

from __future__ import annotations

import json

import pytest

from flann.cli import main
from flann.hardware.fixed.render import generate, load
from flann.hardware.design import from_directory


@pytest.mark.parametrize("opts", [
    {"input_bits": 9},
    {"input_bits": 14, "input_lsb_v": 0.0007, "output_bits": 18},
    {"lanes": 2, "mult_style": "lut", "interp": False, "check_device": False},
    {"mult_digit_bits": 4, "clamp": False, "term_frac_bits": 14},
], ids=["9bit", "14bit-adc", "lut-2lanes-nointerp", "digit4-noclamp"])
def test_twin_rebuilt_from_the_manifest_equals_the_generators(tmp_path, small_model, opts):
    model = small_model(11)
    generate(model, tmp_path / "d", **opts)
    d = from_directory(tmp_path / "d", model)
    want = load(model, **opts)
    assert d.spec.to_dict() == want.to_dict()
    assert d.spec.weight_rom == want.weight_rom and d.spec.input_bits == want.input_bits


def test_trace_of_a_directory_is_the_trace_of_its_options(tmp_path, small_model, capsys):
    model = small_model(11)
    assert main(["gen", str(model), "-o", str(tmp_path / "d"), "--input-bits", "10"]) == 0
    capsys.readouterr()
    assert main(["trace", str(tmp_path / "d"), "--model", str(model), "--json"]) == 0
    by_dir = json.loads(capsys.readouterr().out)
    assert main(["trace", str(model), "--input-bits", "10", "--json"]) == 0
    assert by_dir == json.loads(capsys.readouterr().out)
    assert main(["trace", str(model), "--json"]) == 0  # 12-bit default: another design
    assert by_dir != json.loads(capsys.readouterr().out)


def test_directory_without_model_or_with_another_model_is_refused(tmp_path, small_model, capsys):
    model = small_model(11)
    assert main(["gen", str(model), "-o", str(tmp_path / "d")]) == 0
    capsys.readouterr()
    # a directory flann gen wrote keeps its model; one from an older flann (no 'model') does not
    man = json.loads((tmp_path / "d" / "manifest.json").read_text())
    del man["model"]
    (tmp_path / "d" / "manifest.json").write_text(json.dumps(man))
    (tmp_path / "d" / "model.json").unlink()
    assert main(["sim", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(
        f"error: {(tmp_path / 'd' / 'manifest.json').resolve()} does not name its model: pass --model MODEL.json")
    assert main(["trace", str(tmp_path / "d"), "--model", str(small_model(9, "m9.json"))]) == 2
    assert "is not the model" in capsys.readouterr().err
