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


def _f18(args):
    args.format = "float18"
    return args


def run_gen(args):
    return gen.run(_f18(args))


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


def _f18_encode(x: float) -> int:
    """Independent float18 encoder (1 sign, 6 exponent bits, bias 31, 11 fraction bits, RNE),
    written from the seed's format description, not from flann.numeric.float18."""
    from fractions import Fraction

    if x == 0:
        return 0
    sign = 1 if x < 0 else 0
    a = Fraction(abs(x))
    e = a.numerator.bit_length() - a.denominator.bit_length()
    if Fraction(2) ** e > a:
        e -= 1
    sig = a / Fraction(2) ** e * 2 ** 11  # in [2^11, 2^12)
    q, r = divmod(sig, 1)
    if r > Fraction(1, 2) or (r == Fraction(1, 2) and q % 2 == 1):
        q += 1
    if q == 2 ** 12:
        q, e = 2 ** 11, e + 1
    return (sign << 17) | ((e + 31) << 11) | (int(q) - 2 ** 11)


def test_weight_rom_holds_every_weight_word_by_word(tmp_path):
    import re

    from flann.golden.model import load_model

    assert gen.run(_f18(_args(DEFAULT, "-o", tmp_path / "d"))) == 0
    man = json.loads((tmp_path / "d" / "manifest.json").read_text())
    text = (tmp_path / "d" / "flann_f18_top.vhd").read_text()
    rom = text[text.index("constant weight_rom_c"):]
    rom = rom[:rom.index(");")]
    words = [int(w, 2) for w in re.findall(r'"([01]{18})"', rom)]
    m = load_model(DEFAULT)
    # term 0 enters as the code read with the term format's fraction bits: its weight carries
    # lsb / scale * 2^Tf (docs/float18.md); the others are the model's weights as they are
    width, int_bits = (int(x) for x in re.match(r"sfix<(\d+),(\d+)", man["spec"]["term"]).groups())
    tf = width - int_bits
    want = [m.weights[0] * man["input_lsb_v"] / m.input_scale_v * 2.0 ** tf, *m.weights[1:]]
    assert len(words) == m.terms == 51
    for i, (got, w) in enumerate(zip(words, want)):
        assert got == _f18_encode(w), f"ROM word {i}: {got:018b} != float18({w})"
    start = re.search(r'constant start_c\s*:.*:= "([01]{18})"', text).group(1)
    assert int(start, 2) == _f18_encode(m.bias + m.weights[0] * (-m.input_offset_v / m.input_scale_v))
