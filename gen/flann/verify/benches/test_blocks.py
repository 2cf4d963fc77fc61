"""Each block alone against its bit-true twin class, random and corner stimuli.

The runner picks the toplevel entity and the matching test function (one per block).
Stage registers of expansion/multiplier/adder move only on ``in_adv``; the benches drive
``in_adv`` with random holes (at least the multiplier's period apart) to check the stall.
"""

from __future__ import annotations

import cocotb
import numpy as np
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from flann.hardware.fixed.twin import FlannAdder, FlannExpansion, FlannMultiplier, FlannNorm
from flann.verify.benches.flann_bench import config, load_spec, reset, rng, start_clock, write_record


def _lanes(value, n: int, width: int) -> list[int]:
    """Split a flat lane vector (lane 0 in the LSBs) into signed ints."""
    v = value.to_unsigned()
    out = []
    for _ in range(n):
        x = v & ((1 << width) - 1)
        out.append(x - (1 << width) if x >> (width - 1) else x)
        v >>= width
    return out


def _pack(values, width: int) -> int:
    v = 0
    for i, x in enumerate(values):
        v |= (int(x) & ((1 << width) - 1)) << (i * width)
    return v


class AdvancePattern:
    """Cycle-by-cycle in_adv: random holes, and at least ``period`` cycles between advances."""

    def __init__(self, r, period: int, p_hole: float = 0.3):
        self.r, self.period, self.p_hole = r, period, p_hole
        self.wait = 0

    def next(self) -> int:
        if self.wait > 0:
            self.wait -= 1
            return 0
        if self.r.random() < self.p_hole:
            return 0
        self.wait = self.period - 1
        return 1


async def _setup(dut):
    cfg = config()
    spec = load_spec(cfg)
    r = rng(cfg, dut._log)
    await start_clock(dut)
    for name in ("in_start", "in_adv", "in_valid", "in_finish"):
        if hasattr(dut, name):
            getattr(dut, name).value = 0
    await reset(dut)
    return cfg, spec, r


@cocotb.test()
async def norm_vs_twin(dut):
    """Clamp + serial normalisation: theta, linear part, sat flag and B+1 cycle latency."""
    cfg, s, r = await _setup(dut)
    twin = FlannNorm(s)
    corners = [s.code_min, s.code_min + 1, s.clamp_lo - 1, s.clamp_lo, s.clamp_lo + 1, -1, 0, 1,
               s.clamp_hi - 1, s.clamp_hi, s.clamp_hi + 1, s.code_max - 1, s.code_max]
    codes = [c for c in corners if s.code_min <= c <= s.code_max]
    codes += [r.randint(s.code_min, s.code_max) for _ in range(int(cfg.get("block_samples", 150)))]
    if cfg.get("block_every_code"):
        codes = list(range(s.code_min, s.code_max + 1))
    exp = twin.process(np.array(codes))
    bad = 0
    for i, c in enumerate(codes):
        await FallingEdge(dut.clk)
        dut.in_code.value = c
        dut.in_valid.value = 1
        await RisingEdge(dut.clk)
        dut.in_valid.value = 0
        for k in range(s.input_bits + 1):
            await RisingEdge(dut.clk)
        await ReadOnly()
        assert dut.out_valid.value == 1, f"code {c}: out_valid not high {s.input_bits + 1} edges later"
        got = (dut.out_theta.value.to_unsigned(), dut.out_lin.value.to_signed(), int(dut.out_sat.value))
        want = (int(exp["theta"][i]), int(exp["lin"][i]), int(exp["sat"][i]))
        if got != want:
            bad += 1
            dut._log.error("code %d: HDL %s twin %s", c, got, want)
    write_record(cfg, "norm", {"samples": len(codes), "mismatches": bad})
    assert bad == 0, f"{bad} mismatches"


@cocotb.test()
async def expansion_vs_twin(dut):
    """Every term of random and corner phases, with a stalling in_adv."""
    cfg, s, r = await _setup(dut)
    twin = FlannExpansion(s)
    P = s.phase_bits
    thetas = [0, 1, (1 << P) - 1, 1 << (P - 1), 1 << (P - 2), (1 << (P - 2)) - 1, 3 << (P - 2)]
    thetas += [r.randrange(1 << P) for _ in range(int(cfg.get("block_phases", 12)))]
    exp = twin.process(np.array(thetas))["terms"]  # (n, steps, lanes)
    T = s.term_fmt.width
    bad = 0
    for i, th in enumerate(thetas):
        await FallingEdge(dut.clk)
        dut.in_start.value = 1
        dut.in_theta.value = th
        await FallingEdge(dut.clk)
        dut.in_start.value = 0
        # shift-add designs form the slope product between advances: keep their spacing
        pat = AdvancePattern(r, s.adv_period)
        issued, got = 0, []
        while len(got) < s.steps:
            adv = pat.next()
            dut.in_adv.value = adv
            dut.in_valid.value = 1 if (adv and issued < s.steps) else 0
            issued += 1 if (adv and issued < s.steps) else 0
            await RisingEdge(dut.clk)
            await ReadOnly()
            if adv and dut.out_valid.value == 1:
                got.append(_lanes(dut.out_terms.value, s.lanes, T))
            await FallingEdge(dut.clk)
        dut.in_adv.value = 0
        dut.in_valid.value = 0
        diff = np.argwhere(np.array(got) != exp[i])
        if diff.size:
            bad += len(diff)
            k, l = diff[0]
            dut._log.error("theta %d step %d lane %d: HDL %d twin %d", th, k, l, got[k][l], exp[i][k][l])
    write_record(cfg, "expansion", {"phases": len(thetas), "mismatches": bad})
    assert bad == 0, f"{bad} mismatching terms"


@cocotb.test()
async def multiplier_vs_twin(dut):
    """Random and extreme terms x the weight ROM, advancing at the style's period with holes."""
    cfg, s, r = await _setup(dut)
    twin = FlannMultiplier(s)
    T, Wp, L = s.term_fmt.width, s.product_fmt.width, s.lanes
    tmax = s.term_bound
    runs = int(cfg.get("block_runs", 4))
    bad = 0
    for run in range(runs):
        if run == 0:
            terms = np.full((s.steps, L), tmax)
        elif run == 1:
            terms = np.full((s.steps, L), -tmax)
        else:
            terms = np.array([[r.randint(-tmax, tmax) for _ in range(L)] for _ in range(s.steps)])
        exp = twin.process(terms[None])["products"][0]
        await FallingEdge(dut.clk)
        dut.in_start.value = 1
        await FallingEdge(dut.clk)
        dut.in_start.value = 0
        pat = AdvancePattern(r, s.adv_period)
        issued, got = 0, []
        while len(got) < s.steps:
            adv = pat.next()
            feed = adv and issued < s.steps
            dut.in_adv.value = adv
            dut.in_valid.value = 1 if feed else 0
            dut.in_terms.value = _pack(terms[issued] if feed else [0] * L, T)
            issued += 1 if feed else 0
            await RisingEdge(dut.clk)
            await ReadOnly()
            if adv and dut.out_valid.value == 1:
                got.append(_lanes(dut.out_products.value, L, Wp))
            await FallingEdge(dut.clk)
        dut.in_adv.value = 0
        dut.in_valid.value = 0
        n = int(np.count_nonzero(np.array(got) != exp))
        if n:
            k = int(np.argwhere(np.array(got) != exp)[0][0])
            dut._log.error("run %d step %d: HDL %s twin %s", run, k, got[k], list(exp[k]))
        bad += n
    write_record(cfg, "multiplier", {"runs": runs, "mismatches": bad})
    assert bad == 0, f"{bad} mismatching products"


@cocotb.test()
async def adder_vs_twin(dut):
    """Start value, products, finish: rounding, saturation both ways, sat pass-through."""
    cfg, s, r = await _setup(dut)
    twin = FlannAdder(s)
    mult = FlannMultiplier(s)
    L, Wp = s.lanes, s.product_fmt.width
    tmax = s.term_bound
    lin_lo, lin_hi = s.lin_fmt.min_int, s.lin_fmt.max_int
    cases = []
    for k in range(int(cfg.get("block_runs", 4)) + 4):
        sign = [1, -1][k % 2]
        if k < 2:  # push towards the output limits: extreme start, all products one sign
            lin = lin_hi if sign > 0 else lin_lo
            w = np.array(s.weight_rom).T
            terms = np.where(w >= 0, sign * tmax, -sign * tmax)
        elif k < 4:  # zero products: output = round(start value)
            lin = r.randint(lin_lo, lin_hi)
            terms = np.zeros((s.steps, L), dtype=np.int64)
        else:
            lin = r.randint(lin_lo, lin_hi)
            terms = np.array([[r.randint(-tmax, tmax) for _ in range(L)] for _ in range(s.steps)])
        prods = mult.process(terms[None])["products"][0]
        # keep the start value inside what the accumulator is sized for (spec: never overflows)
        room = int(np.abs(prods).sum())
        lin = int(np.clip(lin, s.acc_fmt.min_int + room, s.acc_fmt.max_int - room))
        cases.append((lin, int(k % 3 == 0), prods))
    bad = sats = 0
    for lin, in_sat, prods in cases:
        exp = twin.process(np.array([lin]), prods[None], np.array([bool(in_sat)]))
        await FallingEdge(dut.clk)
        dut.in_start.value = 1
        dut.in_lin.value = lin
        dut.in_sat.value = in_sat
        await FallingEdge(dut.clk)
        dut.in_start.value = 0
        pat = AdvancePattern(r, 1)
        k = 0
        while k < s.steps:
            adv = pat.next()
            # an advance with in_valid low must not add anything
            valid = adv and r.random() < 0.8
            dut.in_adv.value = adv
            dut.in_valid.value = 1 if valid else 0
            dut.in_products.value = _pack(prods[k] if valid else [r.randint(-5, 5)] * L, Wp)
            k += 1 if valid else 0
            await FallingEdge(dut.clk)
        dut.in_adv.value = 0
        dut.in_valid.value = 0
        dut.in_finish.value = 1
        await FallingEdge(dut.clk)
        dut.in_finish.value = 0
        await ReadOnly()
        assert dut.out_valid.value == 1
        got = (dut.out_data.value.to_signed(), int(dut.out_sat.value))
        want = (int(exp["out"][0]), int(exp["sat"][0]))
        sats += want[1]
        if got != want:
            bad += 1
            dut._log.error("lin %d: HDL %s twin %s", lin, got, want)
    write_record(cfg, "adder", {"cases": len(cases), "mismatches": bad, "sat_cases": sats})
    assert bad == 0, f"{bad} mismatches"
