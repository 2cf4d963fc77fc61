"""cocotb: flann_f18_top against its twin FlannF18Top over a list of input codes (bit-exact).

The expected outputs come from the twin, computed by the runner and passed in the bench
configuration (flann.verify.benches.config; GHDL's VPI cannot read generics):
{"codes": [...], "out": [...], "sat": [...], "latency": N, "in_bits": B, "seed": S,
 "records": optional path where the HDL's outputs are written as JSON,
 "stage_codes": optional codes at which the internal stages are captured too}

Stage capture (monitors on the top's own signals, read through GHDL's VPI): every
converted term (term_f at term_valid), product (prod_f at prod_valid) and running sum
(sum_f at sum_valid), in order, for ``flann trace --hdl`` to compare with the twin.
"""

import json
import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from flann.verify.benches import CLK_NS, config


class TopBench:
    def __init__(self, dut):
        self.dut = dut
        self.spec = config()
        self.rng = random.Random(self.spec["seed"])
        dut._log.info(f"seed {self.spec['seed']}, {len(self.spec['codes'])} codes")
        self.mask = (1 << self.spec["in_bits"]) - 1
        self.errors = []
        self.latencies = set()
        self.record = []                     # (code, out_data, out_sat) as the HDL gave them
        self.stage_codes = set(self.spec.get("stage_codes", []))
        self.stages = {}                     # code -> {"terms": [...], "products": [...], "sums": [...]}

    async def reset(self):
        cocotb.start_soon(Clock(self.dut.clk, CLK_NS, unit="ns", impl="gpi").start())
        self.dut.in_valid.value = 0
        self.dut.in_data.value = 0
        self.dut.rst.value = 1
        for _ in range(3):
            await RisingEdge(self.dut.clk)
        await FallingEdge(self.dut.clk)
        self.dut.rst.value = 0

    async def capture(self, valid, data, out: list):
        """Monitor one internal stage: the data of every valid pulse, in order."""
        while True:
            await RisingEdge(valid)
            await ReadOnly()
            out.append(data.value.to_unsigned())

    async def one(self, code, want_out, want_sat):
        """Driver + monitor for one sample: wait for in_ready, present, wait for out_valid."""
        while str(self.dut.in_ready.value) != "1":
            await FallingEdge(self.dut.clk)
        monitors = []
        if code in self.stage_codes:
            st = self.stages[code] = {"terms": [], "products": [], "sums": []}
            d = self.dut
            monitors = [cocotb.start_soon(self.capture(d.term_valid, d.term_f, st["terms"])),
                        cocotb.start_soon(self.capture(d.prod_valid, d.prod_f, st["products"])),
                        cocotb.start_soon(self.capture(d.sum_valid, d.sum_f, st["sums"]))]
        self.dut.in_data.value = code & self.mask
        self.dut.in_valid.value = 1
        await RisingEdge(self.dut.clk)            # the accepting edge
        t0 = cocotb.utils.get_sim_time(unit="ns")
        await FallingEdge(self.dut.clk)
        self.dut.in_valid.value = 0
        await RisingEdge(self.dut.out_valid)
        await ReadOnly()
        self.latencies.add(round((cocotb.utils.get_sim_time(unit="ns") - t0) / 10))
        got = self.dut.out_data.value.to_unsigned()
        sat = str(self.dut.out_sat.value) == "1"
        self.record.append((code, got, sat))
        for m in monitors:
            m.cancel()
        if got != want_out or sat != want_sat:
            self.errors.append(f"code {code}: out {got:#07x} sat {sat}, twin {want_out:#07x} sat {want_sat}")
        await FallingEdge(self.dut.clk)


@cocotb.test()
async def every_code(dut):
    tb = TopBench(dut)
    await tb.reset()
    s = tb.spec
    order = list(range(len(s["codes"])))
    tb.rng.shuffle(order)                # independent of the previous sample's state
    for k in order:
        await tb.one(s["codes"][k], s["out"][k], s["sat"][k])
    if s.get("records"):
        # the HDL's own outputs, for `flann trace --hdl` and the runner's summary
        with open(s["records"], "w") as fh:
            json.dump({"codes": [r[0] for r in tb.record], "out": [r[1] for r in tb.record],
                       "sat": [r[2] for r in tb.record], "latency": sorted(tb.latencies),
                       "stages": {str(c): v for c, v in tb.stages.items()}}, fh)
    for e in tb.errors[:20]:
        dut._log.error(e)
    dut._log.info(f"{len(order) - len(tb.errors)} of {len(order)} codes bit-exact; latency {sorted(tb.latencies)}")
    assert not tb.errors, f"{len(tb.errors)} mismatches vs the twin"
    assert tb.latencies == {s["latency"]}, f"latency {sorted(tb.latencies)}, spec says {s['latency']}"
