"""flann_top reactive benches: handshake gaps, reset mid sample, saturation (every code: test_sweep.py)."""

from __future__ import annotations

import cocotb
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge

from flann.verify.benches.flann_bench import TopBench, reset


@cocotb.test()
async def top_handshake_random_gaps(dut):
    """Random idle gaps, in_valid held while busy, back-to-back runs; order and count kept."""
    bench = TopBench(dut)
    await bench.start()
    s = bench.spec
    n = int(bench.cfg.get("handshake_samples", 60))
    codes = [bench.rng.randint(s.code_min, s.code_max) for _ in range(n)]
    r = bench.rng

    def gap():
        return 0 if r.random() < 0.5 else r.randint(1, 5)

    await bench.run_codes(codes, gap=gap)
    await bench.drain()
    assert bench.sb.checked == n and bench.sb.ok, \
        f"checked {bench.sb.checked}/{n}, mismatches {bench.sb.mismatches}, unexpected {bench.sb.unexpected}"
    assert set(bench.sb.latencies) == {s.latency_cycles}
    # in_valid is held high while the design is busy: it must not take a second sample
    assert bench.monitor.count == n


@cocotb.test()
async def top_reset_mid_sample(dut):
    """Reset at every phase of a sample: nothing stale comes out, the next sample is right."""
    bench = TopBench(dut)
    await bench.start()
    s = bench.spec
    lat = s.latency_cycles
    points = sorted({1, 2, s.input_bits, s.input_bits + 2, lat // 2, lat - 2, lat - 1,
                     bench.rng.randint(1, lat - 1)})
    for k in points:
        dut.in_data.value = s.clamp_hi
        dut.in_valid.value = 1
        await RisingEdge(dut.clk)  # in_ready is high after reset: accepted
        dut.in_valid.value = 0
        await ClockCycles(dut.clk, k)
        before = bench.monitor.count
        await FallingEdge(dut.clk)
        await reset(dut)
        await ClockCycles(dut.clk, lat + 4)
        assert bench.monitor.count == before, f"output after reset at cycle {k}"
        assert dut.in_ready.value == 1
    # the design still works and agrees with the twin
    await bench.run_codes([0, s.clamp_lo, 1, -1])
    await bench.drain()
    assert bench.sb.ok and bench.sb.checked == 4


@cocotb.test()
async def top_out_of_range_saturates(dut):
    """Codes outside the trained range: out_sat = 1 and the output of the range edge (no wrap)."""
    bench = TopBench(dut)
    await bench.start()
    s = bench.spec
    below = sorted({s.code_min, s.code_min + 1, s.clamp_lo - 1, (s.code_min + s.clamp_lo) // 2})
    above = sorted({s.clamp_hi + 1, (s.clamp_hi + s.code_max) // 2, s.code_max - 1, s.code_max})
    # a clamp at the converter's end code leaves nothing beyond it on that side
    below = [c for c in below if s.code_min <= c < s.clamp_lo]
    above = [c for c in above if s.clamp_hi < c <= s.code_max]
    edges = [s.clamp_lo, s.clamp_hi]
    await bench.run_codes(edges + below + above)
    await bench.drain()
    rec = {c: (d, f) for c, d, f in bench.sb.records}
    for c in below:
        assert rec[c] == (rec[s.clamp_lo][0], 1), f"code {c}: {rec[c]} vs edge {rec[s.clamp_lo]}"
    for c in above:
        assert rec[c] == (rec[s.clamp_hi][0], 1), f"code {c}: {rec[c]} vs edge {rec[s.clamp_hi]}"
    assert rec[s.clamp_lo][1] == 0 and rec[s.clamp_hi][1] == 0
    assert bench.sb.ok

