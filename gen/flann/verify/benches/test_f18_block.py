"""cocotb tests of a float18 block (flann_f18_mul or flann_f18_add, the spec's ``kind``) against
its twin (FlannF18Mul, FlannF18Add), bit-exact, cycle by cycle."""

import cocotb
from flann.verify.benches.f18_bench import Bench, stimuli


@cocotb.test()
async def corners_and_random(dut):
    tb = Bench(dut)
    await tb.start()
    items = stimuli(tb.spec["kind"], tb.fmt, tb.rng, int(tb.spec["n_random"]))
    await tb.run(items)
    tb.finish(min_checked=len(items))


@cocotb.test()
async def reset_drops_inflight(dut):
    tb = Bench(dut)
    await tb.start()
    items = stimuli(tb.spec["kind"], tb.fmt, tb.rng, 40)[-60:]
    await tb.run(items, reset_at=20)
    tb.finish(min_checked=len(items) - 2 * tb.twin.latency)
