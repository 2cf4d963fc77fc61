"""flann_cond_rotate against FlannCondRotate: random window sums and tangents (the whole signed
range of in_tan, so the saturation is reached) and the rails of both."""

import cocotb

from flann.hardware.conditioner.twin import FlannCondRotate
from flann.verify.benches.cond_bench import clocks, setup, signed


def cases(spec, r, n: int):
    hi, lo = (1 << (spec.acc_bits - 1)) - 1, -(1 << (spec.acc_bits - 1))
    thi, tlo = (1 << (spec.tan_bits - 1)) - 1, -(1 << (spec.tan_bits - 1))
    sums = [hi, lo, 0, 1, -1, hi - 1, lo + 1]
    tans = [0, 1, -1, thi, tlo, thi - 1, tlo + 1]
    out = [(a, b, c, d, t) for t in tans for a, b, c, d in ((hi, hi, lo, lo), (lo, hi, hi, lo), (hi, lo, lo, hi))]
    out += [(r.choice(sums), r.choice(sums), r.choice(sums), r.choice(sums), r.choice(tans)) for _ in range(40)]
    for _ in range(n):
        scale = 1 << r.randint(1, spec.acc_bits - 1)
        out.append(tuple(r.randint(-scale, scale - 1) for _ in range(4)) + (r.randint(tlo, thi),))
    return out


@cocotb.test()
async def rotate_vs_twin(dut):
    cfg, spec, r = await setup(dut, ["in_valid", "in_i_a", "in_q_a", "in_i_b", "in_q_b", "in_tan"])
    twin = FlannCondRotate(spec)
    todo = cases(spec, r, int(cfg["cases"]))
    got, exp = [], []
    for ia, qa, ib, qb, t in todo:
        exp.append((twin.one(ia, qa, t), twin.one(ib, qb, t)))
        dut.in_valid.value = 1
        dut.in_i_a.value, dut.in_q_a.value, dut.in_i_b.value, dut.in_q_b.value = ia, qa, ib, qb
        dut.in_tan.value = t
        await clocks(dut, twin.latency + r.choice((0, 0, 3)), lambda: (signed(dut.out_a), signed(dut.out_b)), got)
    for k, (g, w) in enumerate(zip(got, exp)):
        if g != w:
            dut._log.error("case %s: got %s, twin %s", todo[k], g, w)
    assert len(got) == len(exp), f"{len(got)} results out, {len(exp)} expected"
    assert got == exp
