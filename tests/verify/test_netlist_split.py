"""The mapped-netlist check must not flag a correct netlist.

An outside user's thermal design (8-bit input clamped at code 109, 5-bit temperature): the
netlist Yosys maps is right (Icarus and the twin agree), but written with vectors that feed
back into themselves through the carry cells Verilator saw loops (101 UNOPTFLAT warnings) and
left the clamp off at codes 110..127: 563 of 8192 samples, and `flann synth` refused the
design.  Each net is now one bit in the netlist it simulates."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from flann.cli import main

pytestmark = [pytest.mark.synth,
              pytest.mark.skipif(not all(shutil.which(t) for t in ("ghdl", "yosys", "verilator")),
                                 reason="ghdl, yosys and verilator are required")]
ROOT = Path(__file__).resolve().parents[2]


def _recording(path):
    # 0..50 mm, null at 25 mm, 0.2 V/mm rolling off; gain -400 ppm/degC and a null drift;
    # 0.8 mV noise on a 16-bit +-5 V converter; -20, 25 and 70 degC
    rng = np.random.default_rng(42)
    lsb = 10 / 65536
    rows = ["displacement_mm,voltage_v,direction,temperature_c"]
    for t in (-20, 25, 70):
        for d, xs in ((1, np.arange(0, 50.0001, 0.25)), (-1, np.arange(0, 50.0001, 0.25)[::-1])):
            u = xs - 25
            v = 0.2 * (1 - 4e-4 * (t - 25)) * u / (1 + np.abs(u / 30) ** 3) ** (1 / 3) + 5e-4 * (t - 25) / 55
            v = np.round((v + rng.normal(0, 8e-4, xs.size)) / lsb) * lsb
            rows += [f"{a:.4f},{b:.7f},{d},{t}" for a, b in zip(xs, v)]
    path.write_text("\n".join(rows) + "\n")


def test_thermal_clamp_netlist_is_checked_as_it_is(tmp_path, capsys):
    rec, model, design = tmp_path / "rec_t.csv", tmp_path / "mt.json", tmp_path / "dth8"
    _recording(rec)
    assert main(["train", str(rec), "--temperature", "-o", str(model)]) == 0
    assert main(["gen", str(model), "-o", str(design), "--input-bits", "8", "--input-lsb-v", "0.04",
                 "--temp-bits", "5", "--temp-lsb-c", "5"]) == 0
    man = json.loads((design / "manifest.json").read_text())
    lo, hi = man["clamp_codes"]
    assert hi < 127   # codes above the clamp exist: the sweep drives them
    capsys.readouterr()
    assert main(["synth", str(design), "--json", "--no-lint"]) == 0, capsys.readouterr().err
    rep = json.loads(capsys.readouterr().out)
    assert rep["netlist_check"]["mismatches"] == 0 and rep["netlist_check"]["codes"] == 256 * 32


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
