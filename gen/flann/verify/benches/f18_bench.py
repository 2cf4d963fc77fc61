"""Layered cocotb bench shared by the float18 block tests (flann_f18_mul / flann_f18_add).

driver (random bubbles on in_valid) -> DUT -> monitor (out_valid/out_y each edge)
model  (the Python twin's cycle model) -> scoreboard (in order, bit-exact, valid flag too)

The spec comes in the bench configuration (flann.verify.benches.config):
{"kind", "format": {...}, "seed", "n_random"}.
"""

from __future__ import annotations

import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from flann.numeric.float18 import FlannF18Add, FlannF18Mul, FloatFormat
from flann.verify.benches import CLK_NS, config

TWINS = {"mul": FlannF18Mul, "add": FlannF18Add}


def load_spec() -> dict:
    spec = config()
    f = spec["format"]
    spec["fmt"] = FloatFormat(exp_bits=f["exp_bits"], frac_bits=f["frac_bits"], bias=f["bias"],
                              name=f["name"])
    return spec


# -- stimulus -----------------------------------------------------------------------------
def corner_codes(fmt: FloatFormat) -> list[int]:
    s = fmt.sign_mask
    one = fmt.encode(1)
    codes = [0, s, 1, s | fmt.frac_mask,              # zero and non-canonical zeros
             fmt.max_code, s | fmt.max_code,           # +-max finite
             fmt.min_normal_code, s | fmt.min_normal_code, fmt.min_normal_code + 1,
             one, s | one, one + 1, one - 1, fmt.encode(2), fmt.encode(0.5), fmt.encode(3),
             fmt.pack(0, fmt.exp_max, 0), fmt.pack(0, fmt.bias + 1, fmt.frac_mask)]
    return codes


def stimuli(kind: str, fmt: FloatFormat, rng: random.Random, n_random: int) -> list[tuple[int, int]]:
    full = (1 << fmt.width) - 1
    corners = corner_codes(fmt)
    pairs = [(a, b) for a in corners for b in corners]
    for _ in range(n_random):
        a = rng.randint(0, full)
        r = rng.random()
        if r < 0.3:
            b = rng.randint(0, full)
        elif r < 0.55:
            # close exponents: alignment, cancellation and ties in the adder
            e = (a >> fmt.frac_bits) & fmt.exp_max
            e2 = min(fmt.exp_max, max(0, e + rng.randint(-14, 14)))
            b = (rng.getrandbits(1) << (fmt.width - 1)) | (e2 << fmt.frac_bits) | rng.getrandbits(fmt.frac_bits)
        elif r < 0.7:
            # -a or -a +- a few ulps: cancellation
            b = (a ^ fmt.sign_mask) + rng.randint(-3, 3)
            b = min(full, max(0, b))
        elif r < 0.85:
            # significands with trailing zeros: products and sums that tie
            tz = rng.randint(1, fmt.frac_bits)
            a = (a >> tz) << tz
            b = (rng.randint(0, full) >> (fmt.frac_bits - tz + 1)) << (fmt.frac_bits - tz + 1)
            if kind == "add":
                e = (a >> fmt.frac_bits) & fmt.exp_max
                e2 = min(fmt.exp_max, max(0, e - rng.randint(1, fmt.frac_bits + 2)))
                b = (b & ~(fmt.exp_max << fmt.frac_bits)) | (e2 << fmt.frac_bits)
        else:
            # near the range ends: overflow and underflow
            e = rng.choice([1, 2, 3, fmt.exp_max - 1, fmt.exp_max])
            a = (a & ~(fmt.exp_max << fmt.frac_bits)) | (e << fmt.frac_bits)
            e2 = (fmt.bias + rng.randint(-3, 3)) if kind == "mul" else rng.choice([1, 2, fmt.exp_max])
            b = (rng.getrandbits(1) << (fmt.width - 1)) | (e2 << fmt.frac_bits) | rng.getrandbits(fmt.frac_bits)
        pairs.append((a, b))
    return pairs


# -- layers --------------------------------------------------------------------------------
class Driver:
    def __init__(self, dut, rng: random.Random, p_valid: float = 0.8):
        self.dut, self.rng, self.p_valid = dut, rng, p_valid

    def idle(self):
        self.dut.in_valid.value = 0
        self.dut.in_a.value = 0
        self.dut.in_b.value = 0

    def present(self, item):
        """Drive one cycle: an item (a, b) or a bubble (None)."""
        if item is None:
            self.dut.in_valid.value = 0
        else:
            self.dut.in_valid.value = 1
            self.dut.in_a.value, self.dut.in_b.value = item


class Scoreboard:
    def __init__(self, log):
        self.log = log
        self.checked = 0
        self.errors: list[str] = []

    def compare(self, cycle, got_valid, got_y, want_valid, want_y, item):
        if got_valid != want_valid:
            self.errors.append(f"cycle {cycle}: out_valid {got_valid}, twin {want_valid}")
        elif want_valid:
            self.checked += 1
            if got_y != want_y:
                self.errors.append(f"cycle {cycle}: in {item[0]:#07x},{item[1]:#07x} -> out_y "
                                   f"{got_y:#07x}, twin {want_y:#07x}")


class Bench:
    def __init__(self, dut):
        self.dut = dut
        self.spec = load_spec()
        self.fmt = self.spec["fmt"]
        self.seed = int(self.spec["seed"])
        self.rng = random.Random(self.seed)
        dut._log.info(f"seed {self.seed}")
        self.twin = TWINS[self.spec["kind"]](self.fmt)
        self.driver = Driver(dut, self.rng)
        self.scoreboard = Scoreboard(dut._log)

    async def start(self):
        cocotb.start_soon(Clock(self.dut.clk, CLK_NS, unit="ns", impl="gpi").start())
        self.driver.idle()
        self.dut.rst.value = 1
        for _ in range(3):
            await RisingEdge(self.dut.clk)
        await FallingEdge(self.dut.clk)
        self.dut.rst.value = 0
        self.twin.reset()

    async def run(self, items, reset_at: int | None = None):
        """Stream items with random bubbles; compare every cycle against the twin's
        cycle model.  ``reset_at``: assert rst for one cycle mid-stream."""
        queue = list(items)
        history: list = []            # item presented at each cycle, for messages
        lat = self.twin.latency
        cycle = 0
        while queue or any(v for v, _ in self.twin._pipe):
            item = queue.pop(0) if queue and self.rng.random() < self.driver.p_valid else None
            rst = reset_at is not None and cycle == reset_at
            self.dut.rst.value = int(rst)
            self.driver.present(item)
            history.append(item)
            await RisingEdge(self.dut.clk)
            await ReadOnly()
            if rst:
                self.twin.reset()        # the in-flight items are dropped by the DUT too
                want_valid, want_y = False, None
            else:
                want_valid, want_y = self.twin.step(item is not None, *(item or (0, 0)))
            got_valid = str(self.dut.out_valid.value) == "1"
            got_y = self.dut.out_y.value.to_unsigned() if got_valid else None
            source = history[cycle - lat + 1] if cycle >= lat - 1 else None
            self.scoreboard.compare(cycle, got_valid, got_y, want_valid, want_y, source or (0, 0))
            await FallingEdge(self.dut.clk)
            cycle += 1
        self.driver.idle()
        self.dut.rst.value = 0

    def finish(self, min_checked: int):
        for e in self.scoreboard.errors[:20]:
            self.dut._log.error(e)
        assert not self.scoreboard.errors, f"{len(self.scoreboard.errors)} mismatches vs the twin"
        assert self.scoreboard.checked >= min_checked, \
            f"only {self.scoreboard.checked} results checked, expected >= {min_checked}"
        self.dut._log.info(f"{self.scoreboard.checked} results bit-exact against the twin")
