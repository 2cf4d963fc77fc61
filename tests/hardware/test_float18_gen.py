"""`flann gen --format float18`: files, manifest, determinism, option errors."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from flann.commands import gen
from flann.errors import SpecError
from flann.golden.model import model_sha256

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = ROOT / "data" / "default_model.json"


def _args(*argv):
    p = argparse.ArgumentParser()
    gen.add_arguments(p)
    return p.parse_args([str(a) for a in argv])


def run_gen(args):
    args.format = "float18"
    return gen.run(args)


def test_writes_design_and_manifest_deterministically(tmp_path, capsys):
    assert run_gen(_args(DEFAULT, "-o", tmp_path / "a")) == 0
    assert "flann_f18_top" in capsys.readouterr().out
    assert run_gen(_args(DEFAULT, "-o", tmp_path / "b")) == 0
    man = json.loads((tmp_path / "a" / "manifest.json").read_text())
    assert man["top"] == "flann_f18_top" and man["number_format"] == "float18"
    assert man["files"] == ["flann_norm.vhd", "flann_expansion.vhd", "flann_f18_cvt.vhd",
                            "flann_f18_mul.vhd", "flann_f18_add.vhd", "flann_f18_top.vhd"]
    assert man["model_sha256"] == model_sha256(DEFAULT)
    assert man["output"]["exp_bits"] == 6 and man["output"]["frac_bits"] == 11 and man["output"]["bias"] == 31
    for f in man["files"] + ["manifest.json"]:
        assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes(), f
    top = (tmp_path / "a" / "flann_f18_top.vhd").read_text()
    assert model_sha256(DEFAULT) in top
    # 51 float18 weight words in the ROM
    assert top.count('",\n') + 1 >= 51


def test_fixed_only_option_is_an_error_and_writes_nothing(tmp_path):
    with pytest.raises(SpecError, match="output-bits"):
        run_gen(_args(DEFAULT, "-o", tmp_path / "x", "--output-bits", "14"))
    with pytest.raises(SpecError, match="lanes"):
        run_gen(_args(DEFAULT, "-o", tmp_path / "x", "--lanes", "2"))
    assert not (tmp_path / "x").exists()


def test_flann_gen_format_float18_cli(tmp_path, capsys):
    from flann.cli import main

    assert main(["gen", str(DEFAULT), "-o", str(tmp_path / "f"), "--format", "float18"]) == 0
    assert "float18" in capsys.readouterr().out
    man = json.loads((tmp_path / "f" / "manifest.json").read_text())
    assert man["top"] == "flann_f18_top"
    assert main(["gen", str(DEFAULT), "-o", str(tmp_path / "g"), "--format", "float18",
                 "--weight-frac-bits", "9"]) == 2
    assert "weight-frac-bits" in capsys.readouterr().err and not (tmp_path / "g").exists()
    # the fixed default is unchanged
    assert main(["gen", str(DEFAULT), "-o", str(tmp_path / "x")]) == 0
    assert json.loads((tmp_path / "x" / "manifest.json").read_text())["top"] == "flann_top"
