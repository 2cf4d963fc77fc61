"""VHDL generation: manifest, determinism, headers, `ghdl -a`, CLI errors, checked-in hdl/ fresh."""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import pytest

from flann import __version__
from flann.cli import main
from flann.hardware.fixed.render import generate, render
from flann.golden.model import FlannModel, load_model, model_sha256
from flann.hardware.fixed.spec import derive_spec

from test_hw_spec import table1_model

REPO = Path(__file__).resolve().parents[2]
DEFAULT_MODEL = REPO / "data" / "default_model.json"
MAKE_GEN_DEVICE = "xc2s200-pq208-5"  # the Makefile's DEVICE default used by `make gen`
MANIFEST_KEYS = {"top", "files", "input_bits", "input_lsb_v", "output_bits", "output_lsb_mm",
                 "latency_cycles", "cycles_per_sample", "spec", "model_sha256"}


@pytest.fixture(scope="module")
def model_file(tmp_path_factory):
    p = tmp_path_factory.mktemp("model") / "model.json"
    table1_model().save(p)
    return p


def test_manifest_fields_and_files(model_file, tmp_path):
    man = generate(model_file, tmp_path / "hdl")
    assert MANIFEST_KEYS <= set(man)
    assert man["top"] == "flann_top"
    assert man["files"][-1] == "flann_top.vhd" and len(man["files"]) == 6  # + the shared flann_seq
    assert man["model_sha256"] == model_sha256(model_file)
    on_disk = json.loads((tmp_path / "hdl" / "manifest.json").read_text())
    assert on_disk == man
    for f in man["files"]:
        assert (tmp_path / "hdl" / f).is_file()
    # volts = code x input_lsb_v: the trained range lies inside the code range
    m = load_model(model_file)
    half = 1 << (man["input_bits"] - 1)
    assert -half * man["input_lsb_v"] < min(m.voltage_range_v)
    assert (half - 1) * man["input_lsb_v"] > max(m.voltage_range_v)
    # the schedule: serial normaliser, one adv per multiplier period, pipeline drain
    s = man["spec"]
    assert man["latency_cycles"] == man["input_bits"] + 4 + (s["steps"] + 4) * s["adv_period"]
    assert man["cycles_per_sample"] == man["latency_cycles"] + 1


def test_regeneration_is_byte_identical_and_headers_carry_provenance(model_file, tmp_path):
    generate(model_file, tmp_path / "a", lanes=2)
    generate(model_file, tmp_path / "b", lanes=2)
    sha = model_sha256(model_file)
    for f in sorted((tmp_path / "a").iterdir()):
        assert f.read_bytes() == (tmp_path / "b" / f.name).read_bytes(), f.name
        if f.suffix == ".vhd":
            text = f.read_text()
            assert f"flann {__version__}" in text and sha in text and "lanes = 2" in text
            assert not re.search(r"\d{4}-\d\d-\d\d|\d\d:\d\d:\d\d", text), "timestamp in output"


def test_templates_only_place_computed_text(model_file):
    spec = derive_spec(load_model(model_file))
    texts = render(spec)
    top = texts["flann_top.vhd"]
    for port in ("clk", "rst", "in_valid", "in_ready", "in_data", "out_valid", "out_data", "out_sat"):
        assert re.search(rf"^\s+{port}\s+:", top, re.M), port
    assert f"in_data   : in  std_logic_vector({spec.input_bits - 1} downto 0)" in top
    # every weight is in the ROM, in order, as a checked two's-complement literal
    mul = texts["flann_multiplier.vhd"]
    lits = re.findall(r'"([01]{%d})"' % spec.weight_fmt.width, mul)
    vals = [int(b, 2) - (1 << len(b)) * (b[0] == "1") for b in lits]
    assert vals[: spec.n_trig] == list(spec.weight_rom[0][: spec.n_trig])
    for t in texts.values():
        assert "{{" not in t and "{%" not in t


@pytest.mark.parametrize("entity,signal,fmt", [
    ("flann_adder", "acc", "acc_fmt"), ("flann_adder", "data_r", "out_fmt"), ("flann_norm", "lin_r", "lin_fmt"),
])
def test_signals_are_declared_in_their_formats_width_and_sign(model_file, entity, signal, fmt):
    spec = derive_spec(load_model(model_file), lanes=2)
    decl = re.search(rf"signal {signal}\s+: (signed|unsigned)\((\d+) downto 0\);", render(spec)[f"{entity}.vhd"])
    f = getattr(spec, fmt)
    assert decl and int(decl[2]) + 1 == f.width and (decl[1] == "signed") == f.signed


FIXED_TEMPLATES = REPO / "gen" / "flann" / "hardware" / "fixed" / "templates"


@pytest.mark.parametrize("entity,variants", [("flann_expansion", "expansion/interp"),
                                             ("flann_multiplier", "multiplier")])
def test_every_variant_fragment_has_its_place(entity, variants):
    """A fragment file no entity places, or a place no variant fills, is a misspelt name."""
    placed = set(re.findall(r'fragments ~ "/([\w.]+)"', (FIXED_TEMPLATES / f"{entity}.vhd.j2").read_text()))
    provided = {f.name for f in (FIXED_TEMPLATES / variants).glob("*/*.vhd.j2")}
    assert placed and placed == provided


@pytest.mark.parametrize("opts,expansion_has,expansion_lacks", [
    # one table for value and slope (fewer block RAMs): its second port reads the next sample
    ({}, ["icnt <= icnt - 1;", "value_rom_s(to_integer(s1_addr(l) + 1))", "par(l) <= not par(l);",
          "sampled at bin edges"],
     [" * signed('0' & s2_slope(l))", "slope_rom_c", "not dqf(", "s2_slope(l) <="]),
    ({"mult_style": "lut"}, ["* signed('0' & (s2_next(l)(", "value_rom_s(to_integer(s1_addr(l) + 1))"],
     ["icnt", "slope_rom_c"]),
    ({"interp": False, "table_addr_bits": 8}, ["s2_slope(l) <= (others => '0');", "sampled at bin centres",
                                               "not dqf("],
     ["slope_rom_c", "prod :=", "value_rom_s"]),
    # an even lane count: a lane's terms are all sin or all cos, its parity never flips
    ({"lanes": 2}, ["value_rom_s"], ["par(l) <= not par(l);"]),
], ids=["serial_shared", "array_shared", "plain", "lanes2"])
def test_each_architecture_choice_places_its_own_fragment(model_file, opts, expansion_has, expansion_lacks):
    text = render(derive_spec(load_model(model_file), **opts))["flann_expansion.vhd"]
    for s in expansion_has:
        assert s in text, s
    for s in expansion_lacks:
        assert s not in text, s


def test_an_exact_accumulator_skips_the_rounding_shift(model_file, recwarn):
    m = load_model(model_file)
    assert "shift_right(resize(acc" in render(derive_spec(m))["flann_adder.vhd"]
    exact = render(derive_spec(m, product_frac_bits=0))["flann_adder.vhd"]
    assert "shift_right" not in exact and "y := resize(acc, " in exact


CONFIGS = [{}, {"mult_style": "lut"}, {"lanes": 2}, {"lanes": 3, "check_device": False},
           {"interp": False, "table_addr_bits": 8}, {"input_bits": 14, "clamp": False}]


@pytest.mark.parametrize("opts", CONFIGS, ids=lambda o: ",".join(f"{k}={v}" for k, v in o.items()) or "default")
def test_ghdl_analyses_every_generated_file(model_file, tmp_path, opts, recwarn):
    man = generate(model_file, tmp_path / "hdl", **opts)
    work = tmp_path / "work"
    work.mkdir()
    files = [str(tmp_path / "hdl" / f) for f in man["files"]]
    r = subprocess.run(["ghdl", "-a", "--std=93c", f"--workdir={work}", *files], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    r = subprocess.run(["ghdl", "-e", "--std=93c", f"--workdir={work}", "flann_top"], capture_output=True,
                       text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr


def test_checked_in_hdl_is_fresh(tmp_path):
    """`make gen` output in hdl/ must equal a fresh generation from data/default_model.json."""
    if not DEFAULT_MODEL.is_file():
        pytest.fail("data/default_model.json is missing")
    generate(DEFAULT_MODEL, tmp_path / "hdl", device=MAKE_GEN_DEVICE)
    fresh = sorted(p.name for p in (tmp_path / "hdl").iterdir())
    for name in fresh:
        checked = REPO / "hdl" / name
        assert checked.is_file(), f"hdl/{name} missing: run `make gen`"
        assert checked.read_bytes() == (tmp_path / "hdl" / name).read_bytes(), \
            f"hdl/{name} is stale: run `make gen` and commit hdl/"


# ---- CLI: bad input -> one line, exit 2, nothing written ----------------------------------
def _cli(args, capsys):
    code = main(args)
    err = capsys.readouterr().err.strip().splitlines()
    return code, err


@pytest.mark.parametrize("extra,word", [
    (["--device", "xc9999-pq208-5"], "device"),
    (["--input-bits", "40"], "input_bits"),
    (["--output-bits", "6", "--output-lsb-mm", "0.002"], "output_bits"),
    (["--lanes", "0"], "lanes"),
    (["--phase-bits", "70"], "phase_bits"),
])
def test_gen_bad_options_exit_2_without_output(model_file, tmp_path, capsys, extra, word):
    out = tmp_path / "out"
    code, err = _cli(["gen", str(model_file), "-o", str(out), *extra], capsys)
    assert code == 2
    assert len(err) == 1 and err[0].startswith("error:") and word in err[0]
    assert not out.exists() or not any(out.iterdir())


def test_gen_rejects_model_of_another_format_and_too_many_terms(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"format": "other/1", "weights": [1.0]}))
    code, err = _cli(["gen", str(bad), "-o", str(tmp_path / "o1")], capsys)
    assert code == 2 and len(err) == 1 and "format" in err[0]
    big = tmp_path / "big.json"
    table1_model(61).save(big)   # the most terms a model.json may hold, too many for this part
    code, err = _cli(["gen", str(big), "-o", str(tmp_path / "o2"), "--device", "xc2s30-pq208-5",
                      "--lanes", "16", "--mult-style", "lut"], capsys)
    assert code == 2 and len(err) == 1 and "xc2s30" in err[0]
    assert not (tmp_path / "o2").exists()
    table1_model(801).save(big)  # beyond MAX_TERMS: refused as it is read
    code, err = _cli(["gen", str(big), "-o", str(tmp_path / "o2")], capsys)
    assert code == 2 and len(err) == 1 and "'terms' = 801 out of range [1, 61]" in err[0]


def test_gen_cli_writes_manifest(model_file, tmp_path, capsys):
    code = main(["gen", str(model_file), "-o", str(tmp_path / "h"), "--json"])
    assert code == 0
    man = json.loads(capsys.readouterr().out)
    assert man == json.loads((tmp_path / "h" / "manifest.json").read_text())


def test_generate_accepts_a_model_object(tmp_path):
    m = table1_model(11)
    assert isinstance(m, FlannModel)
    man = generate(m, tmp_path / "h")
    assert man["spec"]["terms"] == 11 and man["model_sha256"] == ""
