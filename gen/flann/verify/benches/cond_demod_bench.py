"""flann_cond_demod against FlannCondDemod: the windows' I and Q sums for random samples,
phases and offsets, the rails (a whole window at full scale on the table's peak) and random
gaps between the strobes."""

import cocotb
import numpy as np

from flann.hardware.conditioner.twin import FlannCondDemod
from flann.verify.benches.cond_bench import clocks, setup, signed


def stimulus(spec, r, windows: int):
    """(samples, phases, offset per window): random windows, then the rails."""
    lo, hi = -(1 << (spec.adc_bits - 1)), (1 << (spec.adc_bits - 1)) - 1
    half = 1 << (spec.table_bits - 1)
    m, mask = spec.window, (1 << spec.table_bits) - 1
    x, ph, off = [], [], []
    for _ in range(windows):
        x += [r.choice((lo, hi, 0, -1, r.randint(lo, hi))) for _ in range(m)]
        ph += [r.randint(0, mask) for _ in range(m)]
        off.append(r.randint(0, mask))
    # the rails: the largest sums of either sign (the accumulator's bound), a zero crossing
    for value, phase in ((lo, 0), (lo, half), (hi, 0), (hi, half)):
        x += [value] * m
        ph += [phase] * m
        off.append(0)
    return x, ph, off


@cocotb.test()
async def demod_vs_twin(dut):
    cfg, spec, r = await setup(dut, ["in_valid", "in_sample", "in_phase", "in_offset"])
    x, ph, off = stimulus(spec, r, int(cfg["windows"]))
    twin = FlannCondDemod(spec)
    want_i, want_q = [], []
    for w, o in enumerate(off):
        sl = slice(w * spec.window, (w + 1) * spec.window)
        d = twin.process(x[sl], ph[sl], o)
        want_i += list(d.out_i)
        want_q += list(d.out_q)
    busy = twin.latency + 1
    got = []

    def read():
        return signed(dut.out_i), signed(dut.out_q)

    for k in range(len(x)):
        dut.in_valid.value = 1
        dut.in_sample.value = x[k]
        dut.in_phase.value = ph[k]
        dut.in_offset.value = off[k // spec.window]
        await clocks(dut, busy + r.choice((0, 0, 1, 5)), read, got)
    await clocks(dut, busy, read, got)
    want = list(zip(want_i, want_q))
    bad = sum(1 for g, w in zip(got, want) if g != (int(w[0]), int(w[1])))
    for k, (g, w) in enumerate(zip(got, want)):
        if g != (int(w[0]), int(w[1])) and k < 5:
            dut._log.error("window %d: got %s, twin %s", k, g, w)
    assert len(got) == len(want), f"{len(got)} windows out, {len(want)} expected"
    assert bad == 0, f"{bad} of {len(want)} windows differ"
    bound = spec.window * (1 << (spec.adc_bits - 1)) * spec.amplitude
    assert max(abs(int(v)) for v in np.concatenate([want_i, want_q])) == bound   # the rails reached the bound
