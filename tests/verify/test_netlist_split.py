"""The mapped-netlist check must not flag a correct netlist.  Written with vectors that feed back
into themselves through the carry cells, a two-input design's netlist made Verilator see loops
(UNOPTFLAT) and leave the clamp off at the codes above it; each net is one bit in the netlist
it simulates, and the sweep drives those codes."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from flann.cli import main

pytestmark = [pytest.mark.synth,
              pytest.mark.skipif(not all(shutil.which(t) for t in ("ghdl", "yosys", "verilator")),
                                 reason="ghdl, yosys and verilator are required")]
ROOT = Path(__file__).resolve().parents[2]


def test_thermal_clamp_netlist_is_checked_as_it_is(small_designs, small_synths):
    """A two-input design whose clamp leaves input codes above it: the mapped netlist is swept over
    every (input, temperature) code, those above the clamp too, with 0 mismatches (the run's one
    synthesis of the small thermal design, which the datapath matrix's synth cell shares)."""
    man = json.loads((small_designs["dir"] / "thermal" / "manifest.json").read_text())
    bits, temp_bits = man["input_bits"], man["spec"]["temp_bits"]
    lo, hi = man["clamp_codes"]
    assert hi < 2 ** (bits - 1) - 1   # codes above the clamp exist: the sweep drives them
    rc, _out, err, rep = small_synths("thermal")
    assert rc == 0, err
    assert rep["netlist_check"]["mismatches"] == 0
    assert rep["netlist_check"]["codes"] == 2 ** bits * 2 ** temp_bits


def test_a_large_table_netlist_compiles(tmp_path, capsys):
    # split into bits, the 1024-word sine table's constant wire was one assignment of 14,336
    # nets on one line, more than Verilator's preprocessor takes (40,000 tokens): unused after
    # mapping, it is dropped before the split
    design = tmp_path / "t10"
    assert main(["gen", str(ROOT / "data" / "default_model.json"), "-o", str(design), "--input-bits", "8",
                 "--table-addr-bits", "10"]) == 0
    capsys.readouterr()
    assert main(["synth", str(design), "--json", "--no-lint", "--abc", "fast"]) == 0, capsys.readouterr().err
    rep = json.loads(capsys.readouterr().out)
    assert rep["netlist_check"]["mismatches"] == 0 and rep["netlist_check"]["codes"] == 256
