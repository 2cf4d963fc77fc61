"""GHDL + cocotb co-simulation of the generated VHDL (benches in sim/, run via flann.verify.runner).

Budget: the exhaustive run of the default design dominates (~4.7 M clock cycles, see
bench/bench_sim.py for the codes/s figure); everything else uses small random + corner sets.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from flann.hardware.fixed.render import generate
from flann.verify.runner import run_bench

pytestmark = pytest.mark.sim

REPO = Path(__file__).resolve().parents[2]
MODEL = REPO / "data" / "default_model.json"
DEFAULT = {"device": "xc2s200-pq208-5"}


def _design(tmp_path_factory, name, opts):
    d = tmp_path_factory.mktemp(name)
    generate(MODEL, d / "hdl", **opts)
    return d


@pytest.fixture(scope="module")
def default_design(tmp_path_factory):
    return _design(tmp_path_factory, "default", DEFAULT)


def _run(design, bench, opts, **kw):
    return run_bench(design / "hdl", bench, model=MODEL, options=opts, build_dir=design / "build", **kw)


def test_default_design_every_input_code_bit_exact(default_design):
    r = _run(default_design, "top", DEFAULT, testcase="top_every_code", extra={"codes": "all"})
    rec = r.records["top_every_code"]
    assert r.ok, f"failed: {r.failed_tests} (see {default_design}/build/top/sim.log)"
    assert len(rec["codes"]) == 4096 and sorted(rec["codes"]) == list(range(-2048, 2048))
    assert rec["mismatches"] == 0


def test_default_design_handshake_reset_saturation(default_design):
    r = _run(default_design, "top", DEFAULT, extra={"codes": 20, "handshake_samples": 40},
             testcase="top_handshake_random_gaps|top_reset_mid_sample|top_out_of_range_saturates")
    assert r.tests == 3 and r.ok, f"failed: {r.failed_tests}"


@pytest.mark.parametrize("block", ["norm", "expansion", "multiplier", "adder"])
def test_default_design_each_block_vs_twin(default_design, block):
    r = _run(default_design, block, DEFAULT, seed=3)
    assert r.tests == 1 and r.ok, f"{block} failed (see {default_design}/build/{block}/sim.log)"
    assert r.records[block]["mismatches"] == 0


@pytest.mark.parametrize("opts,benches", [
    ({"mult_style": "lut"}, ["top", "multiplier"]),
    # 3 lanes need 15 block RAMs (a table copy per lane): no Spartan-II, simulated anyway
    ({"lanes": 3, "check_device": False}, ["top", "expansion", "multiplier", "adder"]),
    ({"input_bits": 14, "mult_digit_bits": 4}, ["top", "norm"]),
], ids=["lut", "3lanes", "14bit"])
def test_other_architectures(tmp_path_factory, opts, benches):
    d = _design(tmp_path_factory, "arch", opts)
    for b in benches:
        r = _run(d, b, opts, extra={"codes": 80, "handshake_samples": 12, "block_samples": 40,
                                     "block_phases": 4, "block_runs": 2})
        assert r.ok, f"{opts} {b}: {r.failed_tests}"


def test_adder_saturates_both_ways(tmp_path_factory):
    # a finer output LSB makes the accumulator reach past the 16-bit output range
    opts = {"output_lsb_mm": 0.001, "output_bits": 16}
    d = _design(tmp_path_factory, "sat", opts)
    r = _run(d, "adder", opts)
    assert r.ok, r.failed_tests
    assert r.records["adder"]["sat_cases"] >= 2


def test_bench_detects_a_wrong_design(tmp_path_factory):
    """HDL rounding its products to other widths than the twin's: the scoreboard must fail."""
    d = _design(tmp_path_factory, "wrong", {"product_frac_bits": 3})
    r = _run(d, "top", {"product_frac_bits": 4}, testcase="top_every_code", extra={"codes": 30})
    assert r.tests == 1 and r.failures == 1
    assert r.records["top_every_code"]["mismatches"] > 0


def test_flann_sim_cli_json_and_plot(tmp_path, capsys):
    """`flann sim --json` on a small design (11 terms, 8-bit input: every code is 256 samples)."""
    import json

    from flann.cli import main

    from test_hw_spec import table1_model

    model = tmp_path / "m11.json"
    table1_model(11).save(model)
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
