"""flann_cond_nco against FlannCondNco, clock by clock: phase, DAC word and sigma-delta bit
for a random strobe pattern."""

import cocotb
import numpy as np
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from flann.hardware.conditioner.twin import FlannCondNco
from flann.verify.benches.cond_bench import setup, unsigned, signed


@cocotb.test()
async def nco_vs_twin(dut):
    cfg, spec, r = await setup(dut, ["in_en"])
    cycles = int(cfg["cycles"])
    en = [1 if r.random() < cfg.get("p_en", 0.5) else 0 for _ in range(cycles)]
    want = FlannCondNco(spec).process(en)
    bad = 0
    for i in range(cycles):
        dut.in_en.value = en[i]
        await RisingEdge(dut.clk)
        await ReadOnly()
        got = (unsigned(dut.out_phase), signed(dut.out_dac), int(dut.out_sd.value))
        exp = (int(want.out_phase[i]), int(want.out_dac[i]), int(want.out_sd[i]))
        if got != exp:
            bad += 1
            if bad <= 5:
                dut._log.error("cycle %d: got %s, twin %s", i, got, exp)
        await FallingEdge(dut.clk)
    assert bad == 0, f"{bad} of {cycles} cycles differ"
    # the run read as many table entries as the bench asked for (every one with a step of 1 or less)
    assert len(np.unique(want.out_phase)) >= int(cfg["entries"])
