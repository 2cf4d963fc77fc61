"""Shared cocotb test-bench pieces for the generated FLANN VHDL (cocotb 2.x, GHDL).

GHDL's VPI cannot read generics, so the runner (flann.verify.runner) writes a JSON config and
names it in ``FLANN_BENCH_CONFIG`` (flann.verify.benches.config): model path + generator options (to rebuild the same
Spec and bit-true twin), the manifest, the seed and where to write the bench's records.

Shape (as cocotb's own examples): a driver, a monitor, a model (the twin), a scoreboard
checking in order, a small bench class wiring them; the ``@cocotb.test`` functions in
``test_*.py`` stay thin.
"""

from __future__ import annotations

import json
import random
from collections import deque
from pathlib import Path

import numpy as np

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, Event, FallingEdge, RisingEdge

from flann.hardware.fixed.render import load
from flann.verify.benches import CLK_NS, config
from flann.hardware.fixed.twin import FlannTop



def load_spec(cfg: dict):
    spec = load(cfg["model"], **cfg.get("options", {}))
    man = cfg.get("manifest") or {}
    if man and man.get("model_sha256") and spec.model_sha256 != man["model_sha256"]:
        raise RuntimeError("manifest model_sha256 differs from the model file: regenerate the HDL")
    return spec


def rng(cfg: dict, log) -> random.Random:
    seed = int(cfg.get("seed", 1))
    log.info("random seed %d", seed)
    return random.Random(seed)


def write_record(cfg: dict, name: str, record: dict) -> None:
    """Bench data for the runner's summary (pass/fail itself comes from cocotb's results)."""
    out = cfg.get("records_dir")
    if out:
        Path(out).mkdir(parents=True, exist_ok=True)
        (Path(out) / f"{name}.json").write_text(json.dumps(record))


async def start_clock(dut) -> None:
    Clock(dut.clk, CLK_NS, unit="ns").start()


async def reset(dut, cycles: int = 2) -> None:
    dut.rst.value = 1
    await ClockCycles(dut.clk, cycles)
    await FallingEdge(dut.clk)
    dut.rst.value = 0


async def two_input_sweep(dut, rebuild, what: str):
    """Wait for a two-input sweep's done, rebuild its spec (``rebuild(model, manifest, what)``)
    and read its file: (config, spec, rows, voltage codes, temperature codes)."""
    cfg = config()
    await RisingEdge(dut.done)
    spec, _ = rebuild(cfg["model"], cfg["manifest"], what)
    return (cfg, spec, *two_input_samples(cfg))


def two_input_samples(cfg: dict):
    """A two-input sweep's file (code, temperature code, out, sat, latency per line), checked
    to hold every listed sample in order: (rows, voltage codes, temperature codes)."""
    sweep = cfg["sweep"]
    got = np.loadtxt(sweep["file"], dtype=np.int64, ndmin=2)
    codes = np.arange(sweep["code_lo"], sweep["code_hi"] + 1, dtype=np.int64)
    temps = np.asarray(sweep["temps"], dtype=np.int64)
    want_c, want_t = np.tile(codes, temps.size), np.repeat(temps, codes.size)
    assert got.shape[0] == want_c.size, f"{got.shape[0]} outputs for {want_c.size} samples"
    assert np.array_equal(got[:, 0], want_c) and np.array_equal(got[:, 1], want_t), "samples out of order"
    return got, want_c, want_t


def judge_two_input(dut, cfg: dict, name: str, got, out, sat, latency: int, record: dict) -> None:
    """Record and judge a two-input sweep against its twin's ``out``/``sat``: bit-exact, one latency."""
    bad = (got[:, 2] != out) | (got[:, 3] != np.asarray(sat).astype(np.int64))
    write_record(cfg, name, {"mismatches": int(np.count_nonzero(bad)), "samples": int(got.shape[0]),
                             **record, "latency": sorted(set(got[:, 4].tolist()))})
    for k in np.flatnonzero(bad)[:10]:
        dut._log.error("code %d temp %d: HDL %d sat %d, twin %d sat %d", got[k, 0], got[k, 1], got[k, 2],
                       got[k, 3], out[k], sat[k])
    assert not bad.any(), f"{int(np.count_nonzero(bad))} mismatches vs the twin"
    lat = set(got[:, 4].tolist())
    assert lat == {latency}, f"latencies {sorted(lat)} (manifest {latency})"


def cycle_now() -> int:
    return int(cocotb.utils.get_sim_time(unit="ns")) // CLK_NS


# ------------------------------------------------------------------------------------------
# top level: driver / monitor / scoreboard
# ------------------------------------------------------------------------------------------
class TopDriver:
    """Offers codes on in_valid/in_data; a code is taken at an edge where in_ready was high.

    ``gaps``: callable -> idle cycles before offering the next code (None: back-to-back, and
    the driver waits for each result so an exhaustive run costs a few wake-ups per sample).
    """

    def __init__(self, dut, on_accept):
        self.dut = dut
        self.on_accept = on_accept
        dut.in_valid.value = 0
        dut.in_data.value = 0

    async def send(self, code: int) -> None:
        dut = self.dut
        dut.in_data.value = int(code)
        dut.in_valid.value = 1
        while True:
            await RisingEdge(dut.clk)
            # read in the edge's own callback: registers have not moved yet, so this is the
            # value the DUT sampled.  (No ReadOnly here: under GHDL an edge awaited right after
            # a ReadOnly in the same time step can fire at once.)
            if dut.in_ready.value == 1:
                break
        self.on_accept(int(code), cycle_now())
        dut.in_valid.value = 0


class TopMonitor:
    """One record per out_valid pulse: (data, sat, cycle); ``signed``: out_data as a two's
    complement number (a fixed-point output), else as its bits (a float18 code)."""

    def __init__(self, dut, on_output, signed: bool = True):
        self.dut = dut
        self.on_output = on_output
        self.signed = signed
        self.count = 0
        self.event = Event()
        self._task = cocotb.start_soon(self._run())

    async def _run(self) -> None:
        dut = self.dut
        while True:
            await RisingEdge(dut.out_valid)  # out_data/out_sat change in the same delta
            self.count += 1
            data = dut.out_data.value
            self.on_output(data.to_signed() if self.signed else data.to_unsigned(), int(dut.out_sat.value),
                           cycle_now())
            self.event.set()

    def stop(self) -> None:
        self._task.cancel()


class Scoreboard:
    """Checks outputs in order against the twin's expectation queue."""

    def __init__(self, log, max_report: int = 10):
        self.log = log
        self.expected: deque = deque()
        self.mismatches = 0
        self.unexpected = 0
        self.checked = 0
        self.latencies: list[int] = []
        self.max_report = max_report
        self.records: list[tuple[int, int, int]] = []

    def expect(self, code: int, data: int, sat: int, cycle: int) -> None:
        self.expected.append((code, data, sat, cycle))

    def got(self, data: int, sat: int, cycle: int) -> None:
        if not self.expected:
            self.unexpected += 1
            self.log.error("out_valid with no sample in flight (data %d sat %d)", data, sat)
            return
        code, edata, esat, c0 = self.expected.popleft()
        self.checked += 1
        self.latencies.append(cycle - c0)
        self.records.append((code, data, sat))
        if (data, sat) != (edata, esat):
            self.mismatches += 1
            if self.mismatches <= self.max_report:
                self.log.error("code %d: HDL %d sat %d, twin %d sat %d", code, data, sat, edata, esat)

    @property
    def ok(self) -> bool:
        return self.mismatches == 0 and self.unexpected == 0 and not self.expected


class TopBench:
    """A top (flann_top, flann_f18_top, flann_family_top) + its twin (the model) + driver /
    monitor / scoreboard: the one bench shape of every top.  ``twin``: anything with
    ``process(codes) -> (out, sat)`` and ``latency``; default: flann_top's, rebuilt from the
    configuration's model and options."""

    def __init__(self, dut, twin=None, cfg: dict | None = None, signed: bool = True):
        self.dut = dut
        self.cfg = cfg or config()
        self.spec = load_spec(self.cfg) if twin is None else None
        self.twin = FlannTop(self.spec) if twin is None else twin
        self.log = dut._log
        self.rng = rng(self.cfg, self.log)
        self.sb = Scoreboard(self.log)
        self.driver = TopDriver(dut, self._accepted)
        self.monitor: TopMonitor | None = None
        self.signed = signed
        self._exp_cache: dict[int, tuple[int, int]] = {}

    def expectation(self, codes) -> None:
        codes = np.asarray(list(codes), dtype=np.int64)
        out, sat = self.twin.process(codes)
        self._exp_cache.update({int(c): (int(o), int(s)) for c, o, s in zip(codes, out, sat)})

    def forget(self) -> None:
        """The twin changed (a weight written): expectations are computed again."""
        self._exp_cache.clear()

    def _accepted(self, code: int, cycle: int) -> None:
        if code not in self._exp_cache:
            self.expectation([code])
        data, sat = self._exp_cache[code]
        self.sb.expect(code, data, sat, cycle)

    async def start(self) -> None:
        if not self.cfg.get("harness"):  # the harness makes its clock in VHDL
            await start_clock(self.dut)
        await reset(self.dut)
        self.monitor = TopMonitor(self.dut, self.sb.got, self.signed)

    async def run_codes(self, codes, gap=None) -> None:
        """Send codes; with ``gap`` None wait for each result (fast exhaustive path)."""
        codes = [int(c) for c in codes]
        self.expectation(codes)
        for code in codes:
            if gap is not None:
                g = gap()
                if g:
                    await ClockCycles(self.dut.clk, g)
                await self.driver.send(code)
            else:
                self.monitor.event.clear()
                await self.driver.send(code)
                await self.monitor.event.wait()
                await FallingEdge(self.dut.clk)

    async def drain(self) -> None:
        budget = self.twin.latency + 4
        for _ in range(len(self.sb.expected) + 1):
            if not self.sb.expected:
                break
            await ClockCycles(self.dut.clk, budget)
        await ClockCycles(self.dut.clk, 2)


class TableTwin:
    """A twin given as its outputs at listed codes (computed by the runner, passed in the bench
    configuration): ``process`` looks them up."""

    def __init__(self, codes, out, sat, latency: int):
        self.table = {int(c): (int(o), int(s)) for c, o, s in zip(codes, out, sat)}
        self.latency = latency

    def process(self, codes):
        got = [self.table[int(c)] for c in codes]
        return [o for o, _ in got], [s for _, s in got]
