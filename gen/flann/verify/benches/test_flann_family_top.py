"""flann_family_top benches: two sensors' images loaded through cfg_*, every input code each,
bit-exact against each sensor's twin; reset keeps the memory; a write mid-sample cancels it.

Config (through flann.verify.runner, ``extra``): ``design`` (the design directory) and
``images`` (list of {name, hex}: plain hex images written by ``flann calibrate``).
"""

from __future__ import annotations

import cocotb
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge

from flann.hardware.family.render import load_design
from flann.hardware.family.twin import FlannFamilyTop
from flann.hardware.family.images import parse_hex
from flann.verify.benches.flann_bench import TopBench, config, reset, write_record


class FamilyBench(TopBench):
    """flann_family_top through the one top bench, its twin fed with what is written through
    the cfg port."""

    def __init__(self, dut):
        cfg = config()
        self.fam = load_design(cfg["design"])
        super().__init__(dut, FlannFamilyTop(self.fam), cfg)   # memory as initialised by the design
        self.images = [(im["name"], parse_hex(open(im["hex"]).read(), im["hex"])) for im in cfg["images"]]
        dut.cfg_we.value = 0
        dut.cfg_addr.value = 0
        dut.cfg_data.value = 0

    async def write(self, addr: int, data: int) -> None:
        """One cfg_we cycle (inputs change away from the rising edge)."""
        self.dut.cfg_addr.value = addr
        self.dut.cfg_data.value = data
        self.dut.cfg_we.value = 1
        await FallingEdge(self.dut.clk)
        self.dut.cfg_we.value = 0
        self.twin.write(addr, data)
        self.forget()

    async def load(self, words) -> None:
        await FallingEdge(self.dut.clk)
        for a, w in enumerate(words):
            await self.write(a, w)

    def codes(self) -> list[int]:
        s = self.fam.spec
        return list(range(s.code_min, s.code_max + 1))


@cocotb.test()
async def family_initial_contents_are_the_first_member(dut):
    """Before any load the memory holds what the design was generated with (the block RAM's INIT,
    the first member): codes at both ends, the null and at random bit-exact vs that twin.  First
    in this module: the tests share one simulation, and the later ones load other sensors."""
    bench = FamilyBench(dut)
    await bench.start()
    s = bench.fam.spec
    codes = [s.code_min, s.code_max, 0, *(bench.rng.randint(s.code_min, s.code_max) for _ in range(13))]
    await bench.run_codes(codes)
    assert bench.sb.checked == len(codes) and bench.sb.ok, f"{bench.sb.mismatches} mismatches vs the initial twin"


@cocotb.test()
async def family_two_sensors_every_code(dut):
    """Load sensor A then sensor B through cfg_*: every input code bit-exact vs that sensor's twin."""
    bench = FamilyBench(dut)
    await bench.start()
    lat = bench.fam.latency_cycles
    assert len(bench.images) >= 2, "the bench needs two sensors' images"
    outs = {}
    for name, words in bench.images:
        await bench.load(words)
        before = bench.sb.checked
        await bench.run_codes(bench.codes())
        got = bench.sb.records[before:]
        outs[name] = [d for _, d, _ in got]
        assert bench.sb.ok, f"{name}: {bench.sb.mismatches} mismatches vs its twin"
        assert len(got) == len(bench.codes())
    assert set(bench.sb.latencies) == {lat}, f"latencies {sorted(set(bench.sb.latencies))}, manifest {lat}"
    (a, words_a), (b, words_b) = bench.images[:2]
    if list(words_a) != list(words_b):   # two identical sensors' images cannot show the load
        assert outs[a] != outs[b], "the two sensors gave identical outputs: the load had no effect"
    write_record(bench.cfg, "family_every_code", {"codes": bench.codes(), "outputs": outs,
                                                  "mismatches": bench.sb.mismatches})


@cocotb.test()
async def family_reset_keeps_memory(dut):
    """rst mid-sample: no stale output, the memory keeps the loaded sensor."""
    bench = FamilyBench(dut)
    await bench.start()
    name, words = bench.images[1]
    await bench.load(words)
    s = bench.fam.spec
    dut.in_data.value = s.code_max // 2
    dut.in_valid.value = 1
    await RisingEdge(dut.clk)
    dut.in_valid.value = 0
    await ClockCycles(dut.clk, bench.fam.param_words + s.input_bits)
    before = bench.monitor.count
    await FallingEdge(dut.clk)
    await reset(dut)
    await ClockCycles(dut.clk, bench.fam.latency_cycles + 4)
    assert bench.monitor.count == before, "output after reset"
    codes = [bench.rng.randint(s.code_min, s.code_max) for _ in range(12)]
    await bench.run_codes(codes)
    assert bench.sb.ok and bench.sb.checked == len(codes), f"{name} after reset: {bench.sb.mismatches} mismatches"


@cocotb.test()
async def family_write_mid_sample(dut):
    """A cfg write at any phase of a sample cancels it; the next sample uses the new word."""
    bench = FamilyBench(dut)
    await bench.start()
    a_words, b_words = bench.images[0][1], bench.images[1][1]
    await bench.load(a_words)
    s = bench.fam.spec
    lat = bench.fam.latency_cycles
    # every phase of flann_family_norm (first fetch, first product, second fetch, second
    # product, hand-over), then the expansion / multiplier / adder pipeline
    fam, B = bench.fam, s.input_bits
    k0 = next(f for f in fam.fields if f.name == "k0")
    first = k0.addr + k0.words - fam.param_base  # words of the first fetch (clamps, k1, k0)
    norm_end = fam.norm_latency
    points = sorted({1, 2, first, first + 2 + B // 2, first + 2 + B + 1, norm_end - B // 2, norm_end - 1,
                     norm_end, lat // 2, lat - 2, lat - 1, bench.rng.randint(1, lat - 1)})
    addrs = list(range(len(b_words)))
    for k in points:
        dut.in_data.value = bench.rng.randint(s.code_min, s.code_max)
        dut.in_valid.value = 1
        await RisingEdge(dut.clk)  # in_ready is high between samples: accepted
        dut.in_valid.value = 0
        await ClockCycles(dut.clk, k)
        before = bench.monitor.count
        await FallingEdge(dut.clk)
        a = bench.rng.choice(addrs)
        await bench.write(a, b_words[a])  # B's word into A's image
        await ClockCycles(dut.clk, lat + 4)
        assert bench.monitor.count == before, f"a sample written into at cycle {k} still gave an output"
        # the mixed memory is what the next samples use, bit for bit
        codes = [bench.rng.randint(s.code_min, s.code_max) for _ in range(3)]
        await bench.run_codes(codes)
        assert bench.sb.ok, f"after a write at cycle {k}: {bench.sb.mismatches} mismatches"
    # in_ready is low in a write cycle
    dut.cfg_we.value = 1
    await FallingEdge(dut.clk)
    assert dut.in_ready.value == 0, "in_ready high during a cfg write"
    dut.cfg_we.value = 0
