"""flann synth on the fixtures in tests/fixtures/synth (GHDL synthesis + Yosys xcv).

Expected counts are derived by hand from the fixture sources (see their header comments)
and from the DS001 capacities typed in below, not from the code under test.
"""

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from flann.cli import main
from flann.eda import SynthCheckError, yosys_cells

FIX = Path(__file__).parent / "fixtures" / "synth"
ISSUE_KEYS = {"device", "luts", "ffs", "brams", "lut_pct", "ff_pct", "bram_pct", "fits", "smallest_device"}

needs_tools = pytest.mark.skipif(
    not (shutil.which("ghdl") and shutil.which("yosys")), reason="ghdl and yosys are required (scripts/ensure_tools.sh)"
)


def _run(capsys, *argv):
    rc = main(["synth", *map(str, argv)])
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.mark.synth
@needs_tools
def test_good_design_fits_with_hand_counted_registers(capsys, tmp_path):
    rc, out, err = _run(capsys, FIX / "good", "--device", "xc2s30-pq208-5", "--json", "--work", tmp_path)
    assert rc == 0, err
    rep = json.loads(out)
    assert ISSUE_KEYS <= set(rep)
    assert rep["device"] == "xc2s30-pq208-5"
    assert rep["ffs"] == 18 + 1  # accumulator + valid
    assert rep["brams"] == 1  # 256 x 16 ROM = 4096 bits = one 4 Kbit block RAM
    assert 18 <= rep["luts"] < 400  # at least one LUT per accumulator bit
    assert rep["lut_pct"] == pytest.approx(100 * rep["luts"] / 864, abs=0.05)  # XC2S30: 216 CLBs
    assert rep["ff_pct"] == pytest.approx(100 * 19 / 864, abs=0.05)
    assert rep["bram_pct"] == pytest.approx(100 / 6, abs=0.05)
    assert rep["fits"] is True
    assert rep["smallest_device"] == "xc2s30-pq208-5"  # XC2S15 comes in no PQ208
    assert rep["io"] == 1 + 1 + 12 + 1 + 1 + 18 + 1  # every port but clk
    assert rep["entities"]["flann_top"] == {"luts": rep["luts"], "ffs": 19, "brams": 1}  # one entity
    assert (tmp_path / "flann_top.v").is_file() and (tmp_path / "yosys.log").is_file()


@pytest.mark.synth
@needs_tools
def test_too_big_exits_2_and_names_smallest_device(capsys):
    rc, out, err = _run(capsys, FIX / "too_big", "--device", "xc2s15-tq144-5", "--json")
    assert rc == 2
    rep = json.loads(out)
    assert rep["ffs"] == 33 * 12 + 33  # hand count from the fixture
    assert rep["fits"] is False
    assert rep["ff_pct"] == pytest.approx(100 * 429 / 384, abs=0.05)
    # 429 FF > 384 (XC2S15) but <= 864 (XC2S30), which is offered in TQ144
    assert rep["smallest_device"] == "xc2s30-tq144-5"
    assert "does not fit xc2s15-tq144-5" in err
    assert "429 flip-flops > 384" in err and "xc2s30-tq144-5" in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.synth
@needs_tools
def test_latch_is_refused_with_the_signal_named(capsys):
    rc, out, err = _run(capsys, FIX / "latch", "--json")
    assert rc == 2 and out == ""
    assert 'latch inferred for "out_sat"' in err and "flann_top.vhd:" in err


@pytest.mark.synth
@needs_tools
def test_multiple_drivers_are_refused(capsys):
    rc, out, err = _run(capsys, FIX / "multidriver", "--json")
    assert rc == 2 and out == ""
    assert 'multiple drivers for "out_sat"' in err


def test_missing_manifest_is_one_line(capsys, tmp_path):
    rc, out, err = _run(capsys, tmp_path)
    assert rc == 2
    assert err.strip() == f"error: {tmp_path / 'manifest.json'} not found: generate the design first (flann gen MODEL -o {tmp_path})"


def test_manifest_listing_a_missing_file(capsys, tmp_path):
    (tmp_path / "manifest.json").write_text(json.dumps({"top": "flann_top", "files": ["nope.vhd"]}))
    rc, out, err = _run(capsys, tmp_path)
    assert rc == 2 and "'nope.vhd' does not exist" in err


def test_bad_device_is_refused_before_synthesis(capsys):
    rc, out, err = _run(capsys, FIX / "good", "--device", "xc2s15-pq208-5", "--no-lint")
    assert rc == 2 and "not offered in pq208" in err


@pytest.mark.synth
@needs_tools
def test_fast_abc_keeps_the_hand_counts(capsys):
    rc, out, err = _run(capsys, FIX / "good", "--device", "xc2s30-pq208-5", "--json", "--abc", "fast", "--no-lint")
    assert rc == 0, err
    rep = json.loads(out)
    assert (rep["ffs"], rep["brams"]) == (19, 1)
    assert 18 <= rep["luts"] < 400
    assert "abc -fast" in rep["flow"]


def test_pmux_case_blocks_get_a_default():
    from flann.eda import complete_pmux_cases

    ghdl_style = (
        "  always @*\n"
        "    case (sel)\n"
        "      2'b10: n1_o <= a;\n"
        "      2'b01: n1_o <= b;\n"
        "    endcase\n"
    )
    text, n = complete_pmux_cases(ghdl_style)
    assert n == 1
    assert "      default: n1_o <= 'bx;\n    endcase" in text
    assert complete_pmux_cases(text)[0] == text  # idempotent


def test_ghdl_crash_is_reported_as_such():
    from flann.eda import _ghdl_errors

    stderr = (
        'x.vhd:10:5:note: found ROM "n1", width: 19 bits, depth: 512\n'
        "******************** GHDL Bug occurred ***************************\n"
        "Exception TYPES.INTERNAL_ERROR raised\n"
        "raised TYPES.INTERNAL_ERROR : netlists-memories.adb:334\n"
    )
    msg = str(_ghdl_errors(stderr, "flann_top"))
    assert "GHDL crashed" in msg and "netlists-memories.adb:334" in msg and "found ROM" not in msg


# -- the RTL / Verilog-netlist disagreement (GHDL 2.0's Verilog writer) -----------------------
def test_repair_ghdl_verilog_on_the_writers_two_errata():
    """Text as GHDL 2.0 prints it: a 36-bit constant as a string, an arithmetic shift as >>."""
    from flann.eda import repair_ghdl_verilog

    ghdl = ('  assign n120_o = n115_o + "000000000001000111001010110000010101";\n'
            "  assign n579_o = $signed(n577_o) >> 31'b0000000000000000000000000001010;\n"
            "  assign n130_o = code_r << 31'b0000000000000000000000000000001;\n"
            "  assign n115_o = acc_v >> 31'b0000000000000000000000000000001;\n")
    text, consts, shifts = repair_ghdl_verilog(ghdl)
    assert (consts, shifts) == (1, 1)
    assert "n115_o + 36'b000000000001000111001010110000010101;" in text
    assert "$signed(n577_o) >>> 31'b" in text
    # logical shifts stay logical
    assert "code_r << 31'b" in text and "acc_v >> 31'b" in text


def _iverilog_codes(verilog: Path, tmp: Path, codes) -> dict:
    """Simulate a GHDL-written flann_top under Icarus Verilog for ``codes``; code -> (data, sat)."""
    tb = tmp / "tb.v"
    stim = "\n".join(f"    run({c});" for c in codes)
    tb.write_text(f"""`timescale 1ns/1ps
module tb;
  reg clk = 0, rst = 1, in_valid = 0;
  reg [11:0] in_data = 0;
  wire in_ready, out_valid, out_sat;
  wire [15:0] out_data;
  flann_top dut(.clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready), .in_data(in_data),
                .out_valid(out_valid), .out_data(out_data), .out_sat(out_sat));
  always #5 clk = ~clk;
  task run(input integer c);
    begin
      in_data = c; in_valid = 1;
      @(posedge clk); while (!in_ready) @(posedge clk);
      #1 in_valid = 0;
      @(posedge clk); while (!out_valid) @(posedge clk);
      $display("%0d %0d %0d", c, $signed(out_data), out_sat);
    end
  endtask
  initial begin
    @(posedge clk); @(posedge clk); #1 rst = 0;
{stim}
    $finish;
  end
endmodule
""")
    exe = tmp / "sim.vvp"
    subprocess.run(["iverilog", "-g2012", "-o", str(exe), str(verilog), str(tb)], check=True, capture_output=True)
    out = subprocess.run(["vvp", "-n", str(exe)], check=True, capture_output=True, text=True).stdout
    rows = [ln.split() for ln in out.splitlines() if ln and ln[0] in "-0123456789"]
    return {int(c): (int(d), int(s)) for c, d, s in rows}


@pytest.mark.synth
@pytest.mark.skipif(shutil.which("iverilog") is None, reason="needs iverilog (scripts/ensure_tools.sh)")
def test_ghdl_verilog_of_the_default_design_agrees_with_the_twin(tmp_path):
    """Reproduction: GHDL's Verilog as printed gives 32767 for code -2048 (RTL: -14903); the
    repaired Verilog, the one Yosys maps, agrees with the twin."""
    from flann.hardware.fixed.render import load
    from flann.hardware.fixed.twin import FlannTop
    from flann.eda import complete_pmux_cases, ghdl_to_verilog, repair_ghdl_verilog
    from flann.hardware.manifest import read_manifest

    repo = Path(__file__).resolve().parents[2]
    work = tmp_path / "w"
    verilog = ghdl_to_verilog(read_manifest(repo / "hdl"), work)
    codes = [-2048, -1825, -1000, -1, 0, 1, 777, 1857, 2047]
    out, sat = FlannTop(load(repo / "data" / "default_model.json")).process(codes)
    want = {c: (int(o), int(s)) for c, o, s in zip(codes, out, sat)}
    assert want[-2048] == (-14903, 1)  # the figure of the RTL simulation
    assert _iverilog_codes(verilog, tmp_path, codes) == want
    assert repair_ghdl_verilog(verilog.read_text())[1:] == (0, 0)  # nothing left to repair
    # GHDL's own text, not repaired: the disagreement this test guards against
    raw = subprocess.run(["ghdl", "--synth", "--std=93c", f"--workdir={work / 'ghdl'}", "--out=verilog",
                          "flann_top"], capture_output=True, text=True, check=True).stdout
    (tmp_path / "raw.v").write_text(complete_pmux_cases(raw)[0])
    assert _iverilog_codes(tmp_path / "raw.v", tmp_path, [-2048]) == {-2048: (32767, 1)}


@pytest.mark.synth
@pytest.mark.skipif(shutil.which("verilator") is None, reason="needs verilator (scripts/ensure_tools.sh)")
def test_synth_refuses_a_netlist_that_disagrees_with_its_twin(tmp_path, capsys, monkeypatch):
    """Without the Verilog repair (GHDL's text as printed) the mapped netlist is wrong: refused."""
    from flann import cache, eda

    repo = Path(__file__).resolve().parents[2]
    model = tmp_path / "m.json"
    assert main(["train", str(repo / "data" / "paper_table1.csv"), "--terms", "11", "--method", "lstsq",
                 "-o", str(model)]) == 0
    assert main(["gen", str(model), "-o", str(tmp_path / "d"), "--input-bits", "8"]) == 0
    capsys.readouterr()
    monkeypatch.setattr(eda, "repair_ghdl_verilog", lambda text: (text, 0, 0))
    monkeypatch.setenv(cache.ENV, "off")   # synthesised here, not the repaired netlist of another test
    rc, out, err = _run(capsys, tmp_path / "d", "--model", model, "--no-lint", "--abc", "fast", "--json")
    assert rc == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and "disagrees with its twin" in err


@pytest.mark.synth
@needs_tools
def test_yosys_check_refuses_two_drivers_by_its_exit_code(tmp_path):
    """A netlist with two drivers on one wire passes GHDL's front end (it is Verilog here) and
    must stop at Yosys's ``check -assert``, naming what the check found."""
    (tmp_path / "two.v").write_text("module top(input a, input b, output y);\n"
                                    "  assign y = a;\n  assign y = b;\nendmodule\n")
    with pytest.raises(SynthCheckError, match="conflicting drivers"):
        yosys_cells(tmp_path / "two.v", "top", tmp_path)
