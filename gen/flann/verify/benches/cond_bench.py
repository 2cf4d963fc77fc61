"""Shared pieces of the conditioner's cocotb benches: the spec from the runner's config, the
clock and reset of every bench, stepping the clock while collecting the outputs, reading a
signed port."""

from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from flann.hardware.conditioner.spec import ConditionerSpec
from flann.verify.benches import config
from flann.verify.benches.flann_bench import reset, rng, start_clock


async def setup(dut, inputs):
    """(config, spec, random generator) with the clock running, ``inputs`` low, reset done."""
    cfg = config()
    spec = ConditionerSpec(**cfg["spec"])
    r = rng(cfg, dut._log)
    await start_clock(dut)
    for name in inputs:
        getattr(dut, name).value = 0
    await reset(dut)
    return cfg, spec, r


def signed(handle) -> int:
    return handle.value.to_signed()


def unsigned(handle) -> int:
    return handle.value.to_unsigned()


async def clocks(dut, n: int, read, got: list) -> None:
    """``n`` clocks; after each, ``read()`` appended to ``got`` where ``out_valid`` is high; the
    strobe ``in_valid`` dropped after the first."""
    for _ in range(n):
        await RisingEdge(dut.clk)
        await ReadOnly()
        if int(dut.out_valid.value):
            got.append(read())
        await FallingEdge(dut.clk)
        dut.in_valid.value = 0
