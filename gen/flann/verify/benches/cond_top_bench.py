"""flann_cond_top against ConditionerChain: a simulated waveform's converter codes through the
whole conditioner, one strobe every cycles_per_sample clocks (with random extra gaps); every
window's ratio and saturation flag in order, and the DAC word after each strobe."""

import cocotb
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from flann.hardware.conditioner.spec import Reference
from flann.hardware.conditioner.twin import ConditionerChain
from flann.verify.benches.cond_bench import setup, signed
from flann.verify.benches.flann_bench import write_record


@cocotb.test()
async def waveform_through_the_chain(dut):
    cfg, spec, r = await setup(dut, ["in_valid", "in_code_a", "in_code_b", "in_offset", "in_tan"])
    a, b, ref = cfg["codes_a"], cfg["codes_b"], Reference(**cfg["ref"])
    chain = ConditionerChain(spec)
    want = chain.process(a, b, ref)
    table, dac_phase = spec.table(), spec.phases(len(a))
    dut.in_offset.value, dut.in_tan.value = ref.offset, ref.tan
    got, dac_bad = [], 0
    for k in range(len(a)):
        dut.in_valid.value = 1
        dut.in_code_a.value = a[k]
        dut.in_code_b.value = b[k]
        for c in range(int(cfg["cycles_per_sample"]) + r.choice((0, 0, 0, 2))):
            await RisingEdge(dut.clk)
            await ReadOnly()
            if c == 0 and signed(dut.out_dac) != int(table[dac_phase[k]]):
                dac_bad += 1
            if int(dut.out_valid.value):
                got.append((signed(dut.out_ratio), int(dut.out_sat.value)))
            await FallingEdge(dut.clk)
            dut.in_valid.value = 0
    for _ in range(chain.latency + 2):
        await RisingEdge(dut.clk)
        await ReadOnly()
        if int(dut.out_valid.value):
            got.append((signed(dut.out_ratio), int(dut.out_sat.value)))
        await FallingEdge(dut.clk)
    exp = [(int(q), int(s)) for q, s in zip(want.out_ratio, want.out_sat)]
    bad = 0
    for k, (g, w) in enumerate(zip(got, exp)):
        if g != w:
            bad += 1
            dut._log.error("window %d: got %s, twin %s", k, g, w)
    write_record(cfg, "cond_top", {"windows": len(exp), "mismatches": bad + abs(len(got) - len(exp)),
                                   "dac_mismatches": dac_bad, "saturated": sum(s for _q, s in exp)})
    assert dac_bad == 0, f"{dac_bad} DAC words differ from the table"
    assert len(got) == len(exp), f"{len(got)} ratios out, {len(exp)} expected"
    assert got == exp
