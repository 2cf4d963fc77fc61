"""The RAMB4 simulation model the netlist check compiles with Verilator (benches/ramb4_sim.v).

Verilator 5.006 fills a variable wider than 8 words from a constant in chunks, and its
VL_CONSTHI_W_* (the top chunk) zero-fills past the variable's end by as many words as the
chunk's offset: a 4096-bit memory initialised from one constant spilled up to 448 bytes past the
model and corrupted the heap (the 19-term family with temperature aborted before its first
sample).  The model is built with AddressSanitizer here, so any such write fails the run."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from flann.verify.benches import BENCH_DIR
from flann.verify.netlist import RAM_MODELS, NetlistSweep, compare, compile_netlist, run_netlist

pytestmark = [pytest.mark.synth,
              pytest.mark.skipif(not shutil.which("verilator"), reason="needs verilator (scripts/ensure_tools.sh)")]

# INIT_0E alone: the top chunk of the contents sits 112 words up, the most the old model spilled
FILLED = range(14 * 16, 15 * 16)
WORDS = np.array([(0x1357 * a + 0x2468) & 0xFFFF if a in FILLED else 0 for a in range(256)])


def _top() -> str:
    """A top the netlist driver drives: out_data is the RAMB4_S16 word at address in_data, one
    cycle after the driver's accepting edge; the write port is wired (to a condition the driver
    never makes) so that Verilator keeps the memory rather than folding it into a table."""
    inits = ", ".join(f".INIT_{k:02X}(256'h" + "".join(f"{WORDS[16 * k + j]:04x}" for j in reversed(range(16))) + ")"
                      for k in range(16))
    return f"""module ram_top(input clk, input rst, input in_valid, input [7:0] in_data, output in_ready,
               output reg out_valid, output [15:0] out_data, output out_sat);
  reg taken;
  assign in_ready = 1'b1;
  assign out_sat = 1'b0;
  always @(posedge clk) begin
    taken <= in_valid & ~rst;
    out_valid <= taken;
  end
  RAMB4_S16 #({inits}) ram (.DO(out_data), .ADDR(in_data), .DI(16'h0), .EN(1'b1), .CLK(clk),
                            .WE(rst & in_valid), .RST(1'b0));
endmodule
"""


def test_block_ram_contents_load_without_writing_outside_the_model(tmp_path, monkeypatch):
    # verilated.mk adds these to its own flags; the cache keys no environment, so it is off
    monkeypatch.setenv("CXXFLAGS", "-fsanitize=address -fno-omit-frame-pointer")
    monkeypatch.setenv("LDFLAGS", "-fsanitize=address")
    monkeypatch.setenv("FLANN_CACHE_DIR", "off")
    (tmp_path / "top.v").write_text(_top())
    sweep = NetlistSweep("ram_top", 8, 16, 1, lambda codes: (WORDS[codes & 0xFF], np.zeros(codes.size, int)))
    exe = compile_netlist(tmp_path / "top.v", tmp_path / "verilator", sweep, models=[str(BENCH_DIR / RAM_MODELS)])
    got = run_netlist(exe, sweep, tmp_path, shards=1)
    res = compare(sweep, got)
    assert res.codes_tested == 256 and res.mismatches == 0, res
