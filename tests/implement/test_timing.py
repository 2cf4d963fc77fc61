"""Spartan-II timing estimate on hand-built mapped netlists (Yosys JSON shape) and on a real one."""

import json
from pathlib import Path

import pytest

from flann.cli import main
from flann.errors import FlannError
from flann.hardware.target import parse_part
from flann.implement.timing import analyse

FIX = Path(__file__).parent / "fixtures" / "synth" / "good"
PART5 = parse_part("xc2s30-pq208-5")


def _netlist(tmp_path, cells) -> Path:
    data = {"modules": {"flann_top": {"cells": {
        f"c{i}": {"type": t, "connections": conns} for i, (t, conns) in enumerate(cells)}, "netnames": {
        "q_start": {"bits": [10]}, "d_end": {"bits": [99]}}}}}
    p = tmp_path / "mapped.json"
    p.write_text(json.dumps(data))
    return p


def _ff(d, q):
    return ("FDRE", {"C": [1], "CE": ["1"], "R": ["0"], "D": [d], "Q": [q]})


def test_two_luts_between_registers(tmp_path):
    # FF -> routed -> LUT -> routed -> LUT (same slice as the FF) -> FF.
    # DS001 -5: TCKO 1.3, TILO 0.7, TICK (LUT input to FF setup) 1.4; 1 ns per routed net.
    cells = [_ff(2, 10), ("LUT1", {"I0": [10], "O": [11]}), ("LUT2", {"I0": [11], "I1": ["0"], "O": [99]}),
             _ff(99, 3)]
    t = analyse(_netlist(tmp_path, cells), PART5)
    assert t.delay_ns == pytest.approx(1.3 + 1.0 + 0.7 + 1.0 + 1.4)
    assert t.logic_levels == 2 and t.carry_bits == 0 and t.routed_nets == 2
    assert (t.start, t.end) == ("q_start", "d_end")
    assert t.fmax_mhz == pytest.approx(1000 / 5.4)
    # -6 is faster: TCKO 1.1, TILO 0.6, TICK 1.3
    t6 = analyse(_netlist(tmp_path, cells), parse_part("xc2s30-pq208-6"))
    assert t6.delay_ns == pytest.approx(1.1 + 1.0 + 0.6 + 1.0 + 1.3)


def _adder(n):
    """FF -> LUT (half sum) -> n-bit carry chain -> XORCY -> FF."""
    cells = [_ff(2, 10), ("LUT2", {"I0": [10], "I1": ["1"], "O": [20]})]
    ci = "0"
    for k in range(n):
        cells.append(("MUXCY", {"CI": [ci] if isinstance(ci, int) else [ci], "DI": [10], "S": [20], "O": [30 + k]}))
        ci = 30 + k
    cells += [("XORCY", {"CI": [ci], "LI": [20], "O": [99]}), _ff(99, 3)]
    return cells


def test_carry_chain_counts_its_bits(tmp_path):
    t8 = analyse(_netlist(tmp_path, _adder(8)), PART5)
    t16 = analyse(_netlist(tmp_path, _adder(16)), PART5)
    assert (t8.carry_bits, t16.carry_bits) == (8, 16)
    assert t8.logic_levels == t16.logic_levels == 1
    assert t16.delay_ns > t8.delay_ns
    # the chain is dedicated routing: 8 more bits cost far less than one routed LUT level
    assert t16.delay_ns - t8.delay_ns < 1.0 + 0.7


def test_longest_of_two_paths_and_no_io_paths(tmp_path):
    cells = [_ff(2, 10), ("LUT1", {"I0": [10], "O": [99]}), _ff(99, 3),
             # a long path that starts at a pad (IBUF) is not register to register
             ("IBUF", {"I": [50], "O": [51]}), ("LUT1", {"I0": [51], "O": [52]}), ("LUT1", {"I0": [52], "O": [53]}),
             ("LUT1", {"I0": [53], "O": [54]}), _ff(54, 4)]
    t = analyse(_netlist(tmp_path, cells), PART5)
    assert t.logic_levels == 1


def test_block_ram_output_is_a_start_point(tmp_path):
    cells = [("RAMB4_S8", {"CLK": [1], "ADDR": [5] * 9, "DI": ["0"] * 8, "EN": ["1"], "WE": ["0"], "RST": ["0"],
                           "DO": [10] + [60 + i for i in range(7)]}),
             ("LUT1", {"I0": [10], "O": [99]}), _ff(99, 3), _ff(2, 5)]
    t = analyse(_netlist(tmp_path, cells), PART5)
    assert t.start == "q_start" and t.logic_levels == 1
    plain = analyse(_netlist(tmp_path, [_ff(2, 10), ("LUT1", {"I0": [10], "O": [99]}), _ff(99, 3)]), PART5)
    assert t.delay_ns > plain.delay_ns  # block RAM clock-to-out is slower than a flip-flop's


def test_structural_loop_is_left_out_and_counted(tmp_path):
    """abc can close a loop that is logically open (a swap's comparator reading the muxed
    operands); the walk leaves the closing edge out, says so, and times the rest."""
    loop = [_ff(2, 10), ("LUT2", {"I0": [10], "I1": [12], "O": [11]}), ("LUT1", {"I0": [11], "O": [12]}), _ff(12, 3)]
    t = analyse(_netlist(tmp_path, loop), PART5)
    assert t.loops_broken == 1 and t.logic_levels == 2
    assert "1 structural loop" in t.method()


def test_unknown_cell_is_an_error(tmp_path):
    with pytest.raises(FlannError, match="no delay model for cell type DSP48"):
        analyse(_netlist(tmp_path, [_ff(2, 10), ("DSP48", {"A": [10], "O": [99]}), _ff(99, 3)]), PART5)


@pytest.mark.synth
def test_synth_json_reports_timing(tmp_path, capsys):
    assert main(["synth", str(FIX), "--device", "xc2s15-tq144-5", "--json", "--no-lint", "--no-netlist-check"]) == 0
    rep = json.loads(capsys.readouterr().out)
    t = rep["timing"]
    assert set(t) >= {"fmax_mhz_estimate", "logic_levels", "carry_bits", "method"}
    assert t["logic_levels"] >= 1 and "DS001" in t["method"] and "routing allowance" in t["method"]
    assert 10 < t["fmax_mhz_estimate"] < 400
    assert rep["device"] == "xc2s15-tq144-5"


@pytest.mark.synth
def test_default_design_meets_the_default_clock_with_margin(capsys):
    from flann.hardware.target import CLOCK_HZ
    from flann.implement.timing import MARGIN

    hdl = Path(__file__).resolve().parents[2] / "hdl"
    assert main(["synth", str(hdl), "--device", "xc2s30-pq208-5", "--json", "--no-lint", "--no-netlist-check"]) == 0
    t = json.loads(capsys.readouterr().out)["timing"]
    assert t["meets_clock"] and t["fmax_mhz_estimate"] >= MARGIN * CLOCK_HZ / 1e6


@pytest.mark.synth
def test_a_missed_clock_is_said(monkeypatch, capsys):
    import flann.implement.synth as synth_report   # the report says its warnings (the JSON lists them too)

    monkeypatch.setattr(synth_report, "CLOCK_HZ", 400e6)  # no Spartan-II path with a LUT reaches 400 MHz
    assert main(["synth", str(FIX), "--device", "xc2s30-pq208-5", "--no-lint", "--no-netlist-check"]) == 0
    err = capsys.readouterr().err
    assert "below the design's clock 400 MHz" in err and "flann ise writes that PERIOD" in err


def test_lut_ram_is_read_through_a_lut_level(tmp_path):
    # FF -> routed address -> RAM16X1S read (a LUT) -> FF; its write port is an end point
    cells = [_ff(2, 10), ("RAM16X1S", {"WCLK": [1], "A0": [10], "A1": ["0"], "A2": ["0"], "A3": ["0"],
                                       "D": [10], "WE": ["1"], "O": [11]}), ("LUT1", {"I0": [11], "O": [99]}),
             _ff(99, 3), ("GND", {"G": [40]})]
    t = analyse(_netlist(tmp_path, cells), PART5)
    assert t.logic_levels == 2 and t.delay_ns == pytest.approx(1.3 + 1.0 + 0.7 + 1.0 + 1.4)


def test_a_combinational_block_has_no_clock_to_estimate(tmp_path):
    """A datapath's block synthesised alone (bench/bench_float18.py's flann_f18_cvt) stopped
    flann synth with "no register-to-register path"; it is reported as having none."""
    cells = [("LUT2", {"I0": [10], "I1": [11], "O": [12]}), ("LUT1", {"I0": [12], "O": [99]})]
    assert analyse(_netlist(tmp_path, cells), PART5) is None
