"""Shared pieces of the conditioner's cocotb benches: the spec from the runner's config, the
clock and reset of every bench, reading a signed port."""

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
