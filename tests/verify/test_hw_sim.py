"""GHDL + cocotb co-simulation of the generated VHDL (benches in flann.verify.benches, one runner).

Budget: the exhaustive sweep of the default design dominates (4096 codes x 611 cycles, stimulus
and response in VHDL; codes/s in bench/bench_sim.py); everything else uses small random + corner sets.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from flann.cli import main
from flann.golden.model import FlannModel
from flann.hardware.design import from_directory, from_model
from flann.hardware.fixed.verify import run_bench
from flann.verify.runner import sweep

pytestmark = pytest.mark.sim

REPO = Path(__file__).resolve().parents[2]
MODEL = REPO / "data" / "default_model.json"
DEFAULT = {"device": "xc2s200-pq208-5"}


@pytest.fixture(scope="module")
def default_design(tmp_path_factory):
    d = tmp_path_factory.mktemp("default")
    return from_model(MODEL, d, DEFAULT), d


def test_default_design_every_input_code_bit_exact(default_design):
    design, d = default_design
    r = sweep(design, d / "build")
    assert r["bench"].ok, f"failed: {r['bench'].failed_tests} (see {d}/build/sweep)"
    assert r["codes"].tolist() == list(range(-2048, 2048))
    # independent of the twin: within the stated bound of the float model
    ref = design.spec.float_reference(r["codes"]) / design.spec.output_lsb_mm
    assert np.abs(r["data"] - ref).max() <= max(1.0, design.spec.analysis["bound_total_lsb"])


def test_default_design_handshake_reset_saturation(default_design):
    design, d = default_design
    r = run_bench(design, "top", d / "build", extra={"handshake_samples": 40})
    assert r.tests == 3 and r.ok, f"failed: {r.failed_tests}"


def test_top_bench_with_the_clamp_at_the_converter_ends(tmp_path_factory):
    """A design without the clamp (--no-clamp: the clamp codes are the converter's end codes)
    has no code beyond its range edges: the top bench's saturation test runs with none, where
    it drove -129 (out of the 8-bit port's range) and failed a good design."""
    d = tmp_path_factory.mktemp("noclamp")
    design = from_model(MODEL, d, {**DEFAULT, "input_bits": 8, "clamp": False})
    assert (design.spec.clamp_lo, design.spec.clamp_hi) == (design.spec.code_min, design.spec.code_max)
    r = run_bench(design, "top", d / "build", extra={"handshake_samples": 12})
    assert r.tests == 3 and r.ok, f"failed: {r.failed_tests}"


@pytest.mark.parametrize("block", ["norm", "expansion", "multiplier", "adder"])
def test_default_design_each_block_vs_twin(default_design, block):
    design, d = default_design
    r = run_bench(design, block, d / "build", seed=3)
    assert r.tests == 1 and r.ok, f"{block} failed (see {d}/build/{block})"
    assert r.records[block]["mismatches"] == 0


@pytest.mark.parametrize("bits", [6, 12])
def test_norm_every_code_vs_twin(tmp_path_factory, bits):
    """flann_norm (LSB first, the offsets as start values, no offset adder) against its twin over
    every input code: theta and the linear part bit for bit, clamped codes flagged."""
    d = tmp_path_factory.mktemp(f"norm{bits}")
    design = from_model(MODEL, d, {**DEFAULT, "input_bits": bits})
    r = run_bench(design, "norm", d / "build", extra={"block_every_code": True})
    assert r.tests == 1 and r.ok, f"failed (see {d}/build/norm)"
    assert r.records["norm"] == {"samples": 1 << bits, "mismatches": 0}


@pytest.mark.parametrize("opts,benches", [
    ({"mult_style": "lut"}, ["top", "multiplier"]),
    # 3 lanes need 15 block RAMs (a table copy per lane): no Spartan-II, simulated anyway
    ({"lanes": 3, "check_device": False}, ["top", "expansion", "multiplier", "adder"]),
    ({"input_bits": 14, "mult_digit_bits": 4}, ["top", "norm"]),
], ids=["lut", "3lanes", "14bit"])
def test_other_architectures(tmp_path_factory, opts, benches):
    d = tmp_path_factory.mktemp("arch")
    design = from_model(MODEL, d, opts)
    r = sweep(design, d / "build", codes=(-40, 40))
    assert r["bench"].ok and r["codes"].size == 81, f"{opts}: {r['bench'].failed_tests}"
    for b in benches:
        r = run_bench(design, b, d / "build", extra={"handshake_samples": 12, "block_samples": 40,
                                                    "block_phases": 4, "block_runs": 2})
        assert r.ok, f"{opts} {b}: {r.failed_tests}"


def test_adder_saturates_both_ways(tmp_path_factory):
    # a finer output LSB makes the accumulator reach past the 16-bit output range
    d = tmp_path_factory.mktemp("sat")
    design = from_model(MODEL, d, {"output_lsb_mm": 0.001, "output_bits": 16})
    r = run_bench(design, "adder", d / "build")
    assert r.ok, r.failed_tests
    assert r.records["adder"]["sat_cases"] >= 2


def test_weights_far_below_an_output_lsb(tmp_path_factory):
    """A FLANN whose weights and bias are all far below an output LSB (a temperature order of a
    two-input model that carries almost nothing): the linear accumulator must hold the rounding
    half that k0 carries, and the adder's rounding half must fit its sum; HDL and twin agree."""
    d = tmp_path_factory.mktemp("tiny")
    model = d / "tiny.json"
    model.write_text(FlannModel(weights=(3.5e-6, 2e-7), bias=-1e-15, input_offset_v=0.01,
                                input_scale_v=1.3, voltage_range_v=(-1.3, 1.3),
                                displacement_range_mm=(-10.0, 10.0)).to_json())
    design = from_model(model, d, {"input_bits": 8, "output_lsb_mm": 0.000625})
    assert design.spec.weight_fmt.int_bits < 0          # the case: weights under an output LSB
    r = sweep(design, d / "build")
    assert r["bench"].ok and r["codes"].size == 256, r["bench"].failed_tests
    assert np.all(r["data"] == 0)                       # |x| < 1e-5 mm everywhere: 0 LSB
    for block in ("norm", "adder"):
        r = run_bench(design, block, d / "build", seed=5)
        assert r.ok and r.records[block]["mismatches"] == 0, f"{block}: {r.failed_tests}"


def test_sweep_detects_a_wrong_design(tmp_path_factory):
    """HDL rounding its products to other widths than the twin's: the sweep bench must fail."""
    d = tmp_path_factory.mktemp("wrong")
    hdl = from_model(MODEL, d / "wrong", {"product_frac_bits": 3})
    twin = from_model(MODEL, d / "right", {"product_frac_bits": 4})
    mixed = type(hdl)(hdl.directory, hdl.manifest, twin.model, twin.options, twin.spec)
    r = sweep(mixed, d / "build", codes=(0, 30))
    assert r["bench"].tests == 1 and r["bench"].failures == 1
    assert r["bench"].records["sweep_0"]["mismatches"] > 0


def test_design_directory_is_verified_as_generated(tmp_path, capsys, small_model):
    """`flann sim DIR`: the 9-bit design in DIR is what is verified (not a 12-bit regeneration)."""
    model = small_model(11)
    assert main(["gen", str(model), "-o", str(tmp_path / "d"), "--input-bits", "9"]) == 0
    capsys.readouterr()
    design = from_directory(tmp_path / "d", model)
    assert design.spec.input_bits == 9 and design.directory == (tmp_path / "d").resolve()
    code = main(["sim", str(tmp_path / "d"), "--model", str(model), "--json", "--build", str(tmp_path / "b")])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["codes_tested"] == 512 and out["mismatches"] == 0
    # another model than the manifest's: refused with one line
    other = small_model(7, "m7.json")
    assert main(["sim", str(tmp_path / "d"), "--model", str(other)]) == 2
    assert "not the model" in capsys.readouterr().err


def test_flann_sim_cli_json_and_plot(tmp_path, capsys, small_model):
    """`flann sim --json` on a small design (11 terms, 8-bit input: every code is 256 samples)."""
    model = small_model(11)
    png = tmp_path / "fig" / "sim.png"
    code = main(["sim", str(model), "--json", "--plot", str(png), "--input-bits", "8",
                 "--build", str(tmp_path / "build")])
    out = json.loads(capsys.readouterr().out)
    assert code == 0, out
    for k in ("codes_tested", "mismatches", "max_err_lsb", "max_err_mm", "cycles_per_sample",
              "samples_per_s_at_50mhz"):
        assert k in out, k
    assert out["codes_tested"] == 256 and out["mismatches"] == 0
    assert 0 <= out["max_err_lsb"] <= 1.0
    assert out["samples_per_s_at_50mhz"] == pytest.approx(50e6 / out["cycles_per_sample"], rel=1e-6)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
