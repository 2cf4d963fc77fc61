"""flann_cond_ratio against FlannCondRatio: random pairs of in-phase sums and the boundary
cases (A + B = 0 or negative, |A - B| = A + B, equal inputs, the accumulator's rails)."""

import cocotb

from flann.hardware.conditioner.twin import FlannCondRatio
from flann.verify.benches.cond_bench import clocks, setup, signed


def pairs(spec, r, n: int):
    hi = (1 << (spec.acc_bits - 1)) - 1
    lo = -hi - 1
    edge = [(0, 0), (1, 0), (0, 1), (5, -5), (-5, 5), (-1, 0), (7, 7), (hi, hi), (lo, lo), (hi, lo), (lo, hi),
            (hi, 0), (0, hi), (hi, hi - 1), (hi - 1, hi), (hi, 1), (1, hi), (3, -1), (-1, 3)]
    rand = []
    for _ in range(n):
        scale = 1 << r.randint(1, spec.acc_bits - 1)
        rand.append((r.randint(-scale, scale - 1) if r.random() < 0.2 else r.randint(0, scale - 1),
                     r.randint(-scale, scale - 1) if r.random() < 0.2 else r.randint(0, scale - 1)))
    return [(max(lo, min(hi, a)), max(lo, min(hi, b))) for a, b in edge + rand]


@cocotb.test()
async def ratio_vs_twin(dut):
    cfg, spec, r = await setup(dut, ["in_valid", "in_a", "in_b"])
    ab = pairs(spec, r, int(cfg["pairs"]))
    twin = FlannCondRatio(spec)
    want = twin.process([a for a, _ in ab], [b for _, b in ab])
    got = []
    for a, b in ab:
        dut.in_valid.value = 1
        dut.in_a.value = a
        dut.in_b.value = b
        await clocks(dut, twin.latency + 1 + r.choice((0, 0, 3)),
                     lambda: (signed(dut.out_ratio), int(dut.out_sat.value)), got)
    exp = [(int(q), int(s)) for q, s in zip(want.out_ratio, want.out_sat)]
    for k, (g, w) in enumerate(zip(got, exp)):
        if g != w:
            dut._log.error("a=%d b=%d: got %s, twin %s", ab[k][0], ab[k][1], g, w)
    assert len(got) == len(exp), f"{len(got)} ratios out, {len(exp)} expected"
    assert got == exp
