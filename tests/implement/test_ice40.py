"""iCE40 place and route, bitstream and post-route simulation, on a small design (5 terms, 8 bits)."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from flann.cli import main
from flann.hardware.target import ICE40_PARTS, parse_ice40
from flann.implement.ice40 import global_clock_pins, package_pins
from flann.hardware.design import from_model
from flann.verify.post_route import check_post_route, non_ansi_header

REPO = Path(__file__).resolve().parents[2]
TOOLS = ("ghdl", "yosys", "nextpnr-ice40", "icepack", "icebox_vlog", "verilator")
needs_tools = pytest.mark.skipif(not all(shutil.which(t) for t in TOOLS), reason="needs " + ", ".join(TOOLS))


@pytest.fixture(scope="session")
def small(once, in_process):
    """A 5-term model and its design with 8 input bits (256 codes), made once per run."""
    def make(d):
        model = d / "m.json"
        if in_process(["train", REPO / "data" / "paper_table1.csv", "--terms", 5, "--method", "lstsq", "-o", model])[0] \
                or in_process(["gen", model, "-o", d / "hdl", "--input-bits", 8])[0]:
            raise RuntimeError("train or gen of the small design failed")
        return model, d / "hdl"
    return once("ice40_small", make)


@pytest.fixture(scope="session")
def hx1k(small, once, in_process):
    """The small design placed and routed on an HX1K once per run (``synth -o``): the output
    directory.  flann's tool cache then gives ``sim --post-route`` the same routed design."""
    def make(d):
        if in_process(["synth", small[1], "--device", "ice40-hx1k-tq144", "--no-lint", "-o", d / "o"])[0]:
            raise RuntimeError("synth of the small design on an HX1K failed")
        return d / "o"
    return once("ice40_small_hx1k", make)


@pytest.mark.synth
@pytest.mark.pnr
@needs_tools
def test_hx8k_place_route_bitstream_and_post_route(small, tmp_path, capsys):
    model, hdl = small
    out = tmp_path / "ice40"
    assert main(["synth", str(hdl), "--device", "ice40-hx8k-ct256", "--json", "--no-lint", "--post-route",
                 "--model", str(model), "-o", str(out)]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["device"] == "ice40-hx8k-ct256"
    assert rep["luts"] > 20 and rep["ffs"] > 20 and 0 <= rep["brams"] <= 32
    # nextpnr's own report is the source of Fmax and of the device's size
    nx = json.loads((out / "nextpnr_report.json").read_text())
    achieved = [c["achieved"] for c in nx["fmax"].values()]
    assert rep["fmax_mhz"] == pytest.approx(min(achieved), abs=0.01)
    assert rep["timing_met"] == (min(achieved) >= 50.0)
    part = parse_ice40("ice40-hx8k-ct256")
    assert nx["utilization"]["ICESTORM_LC"]["available"] == part.logic_cells == 7680
    assert nx["utilization"]["ICESTORM_RAM"]["available"] == part.brams == 32
    # the bitstream: an iCE40 configuration image starts with the sync word 7E AA 99 7E
    bit = Path(rep["bitstream"])
    assert bit.is_file() and b"\x7e\xaa\x99\x7e" in bit.read_bytes()[:64]
    # the example pin file: every port bit once, each on its own bonded pin of the package
    pcf = dict(re.findall(r"^set_io (\S+) (\S+)$", Path(rep["pcf"]).read_text(), re.M))
    out_bits = json.loads((hdl / "manifest.json").read_text())["output_bits"]
    want = {"clk", "rst", "in_valid", "in_ready", "out_valid", "out_sat"} | {f"in_data[{i}]" for i in range(8)} \
        | {f"out_data[{i}]" for i in range(out_bits)}
    assert set(pcf) == want
    assert len(set(pcf.values())) == len(pcf)
    assert set(pcf.values()) <= set(package_pins(part).values())
    assert pcf["clk"] in global_clock_pins(part)  # a global clock input, not a fabric-routed pin
    # every input code through the routed design
    assert rep["post_route"]["codes_tested"] == 256 and rep["post_route"]["mismatches"] == 0


@pytest.mark.synth
@pytest.mark.pnr
@needs_tools
def test_post_route_sees_a_wrong_design(hx1k, tmp_path):
    out = hx1k
    # the twin of another model (7 terms) against the 5-term design's routed bitstream
    other = tmp_path / "m7.json"
    assert main(["train", str(REPO / "data" / "paper_table1.csv"), "--terms", "7", "--method", "lstsq",
                 "-o", str(other)]) == 0
    design = from_model(other, tmp_path / "d7", {"input_bits": 8})
    res = check_post_route(design, out / "flann_top.asc", out / "flann_top.pcf", parse_ice40("ice40-hx1k-tq144"),
                           tmp_path / "pr")
    assert res.codes_tested == 256 and res.mismatches > 0 and not res.passed


@pytest.mark.synth
def test_errors_are_one_line(small, tmp_path, capsys):
    model, hdl = small
    assert main(["synth", str(hdl), "--device", "ice40-hx9k-ct256", "--no-lint", "-o", str(tmp_path / "o")]) == 2
    assert "unknown iCE40 part" in capsys.readouterr().err
    assert main(["synth", str(hdl), "--device", "xc2s30-pq208-5", "--post-route", "--no-lint"]) == 2
    assert "--post-route needs an iCE40 part" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("command", ["sim", "synth"])
def test_post_route_of_a_design_without_a_twin_is_refused_before_any_tool(tmp_path, capsys, command):
    """Every datapath flann gen writes has a netlist sweep; a design flann did not write (VHDL with
    a hand-written manifest) has no twin: refused in one line by both commands, before synthesis
    or a bench starts (no output or build directory is made)."""
    plain = tmp_path / "plain"
    shutil.copytree(REPO / "tests" / "implement" / "fixtures" / "synth" / "good", plain)
    argv = {"sim": ["sim", str(plain), "--post-route", "--build", str(tmp_path / "b")],
            "synth": ["synth", str(plain), "--device", "ice40-hx8k-ct256", "--post-route", "--no-lint",
                      "-o", str(tmp_path / "o")]}[command]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: "), err
    if command == "sim":
        assert "no twin" in err[0], err
    else:
        named = re.search(r"the netlist sweep has a driver and twin for (.+) designs only", err[0])
        assert named and set(re.split(r", | and ", named.group(1))) == {
            "fixed", "float18", "family", "thermal", "family_thermal"}, err
    assert not (tmp_path / "o").exists() and not (tmp_path / "b").exists()


def test_every_table_part_has_its_package_in_the_chip_database():
    if not shutil.which("nextpnr-ice40"):
        pytest.skip("needs fpga-icestorm's chip database")
    for part in ICE40_PARTS:
        pins = package_pins(part)
        assert len(pins) >= 30, part.name  # the smallest package here (SG48) bonds 39 I/O


def test_global_clock_pins_agree_with_boards():
    if not shutil.which("nextpnr-ice40"):
        pytest.skip("needs fpga-icestorm's chip database")
    # the oscillators of public boards sit on global clock inputs: iCEstick (HX1K-TQ144) pin 21,
    # iCE40-HX8K breakout board (CT256) J3, iCEBreaker (UP5K-SG48) pin 35
    assert "21" in global_clock_pins(parse_ice40("ice40-hx1k-tq144"))
    assert "J3" in global_clock_pins(parse_ice40("ice40-hx8k-ct256"))
    assert "35" in global_clock_pins(parse_ice40("ice40-up5k-sg48"))


def test_non_ansi_header():
    text = "\nmodule chip (output a, input [3:0] \\b , input c);\nwire c;\nendmodule\n"
    got = non_ansi_header(text)
    assert got.startswith("\nmodule chip (a, \\b , c);\noutput a;\ninput [3:0] \\b ;\ninput c;\nwire c;")


@pytest.mark.sim
@pytest.mark.pnr
@needs_tools
def test_flann_sim_post_route(small, hx1k, capsys):
    model, hdl = small
    assert main(["sim", str(hdl), "--model", str(model), "--post-route", "--post-route-device", "ice40-hx1k-tq144",
                 "--json", "--engine", "verilator"]) == 0
    s = json.loads(capsys.readouterr().out)
    pr = s["post_route"]
    assert pr["device"] == "ice40-hx1k-tq144" and pr["codes_tested"] == 256 and pr["mismatches"] == 0
    assert pr["fmax_mhz"] > 0
