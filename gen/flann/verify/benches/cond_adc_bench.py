"""flann_cond_adc against FlannCondAdc: every code, one per clock, with strobe holes."""

import cocotb
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from flann.hardware.conditioner.twin import FlannCondAdc
from flann.verify.benches.cond_bench import setup, signed


@cocotb.test()
async def adc_every_code(dut):
    cfg, spec, r = await setup(dut, ["in_valid", "in_code"])
    codes = list(range(1 << spec.adc_bits))
    want = FlannCondAdc(spec).process(codes).out_sample
    bad = k = 0
    while k < len(codes):
        strobe = r.random() < 0.8
        dut.in_valid.value = int(strobe)
        dut.in_code.value = codes[k] if strobe else 0
        await RisingEdge(dut.clk)
        await ReadOnly()   # registered: the sample of this edge's strobe
        if strobe:
            if not (int(dut.out_valid.value) == 1 and signed(dut.out_sample) == int(want[k])):
                bad += 1
                dut._log.error("code %d: got %s, twin %d", codes[k], dut.out_sample.value, want[k])
            k += 1
        elif int(dut.out_valid.value):
            bad += 1
        await FallingEdge(dut.clk)
    assert bad == 0, f"{bad} codes differ"
