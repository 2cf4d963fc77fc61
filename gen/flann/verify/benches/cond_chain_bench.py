"""flann_chain_top against FlannChainTop: a waveform's converter codes through the conditioner and
the FLANN behind it, one strobe every cycles_per_sample clocks (with random extra gaps); every
window's displacement code and saturation flag in order, each at the twin's latency after the
window's last strobe (shorter where the divider saturates).  A two-input FLANN's temperature
code is driven with each strobe (``temp_codes``).  The twin's values come in the
configuration, computed in the flann process (the FLANN's twin is rebuilt there from the model
the design keeps)."""

import cocotb
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge, Timer

from flann.verify.benches import CLK_NS, config
from flann.verify.benches.cond_bench import setup, signed
from flann.verify.benches.flann_bench import cycle_now, write_record


async def monitor(dut, got: list) -> None:
    """(cycle, out_data, out_sat) at every out_valid pulse (one a window: a trigger a pulse, not a clock)."""
    while True:
        await RisingEdge(dut.out_valid)
        await ReadOnly()
        got.append((cycle_now(), signed(dut.out_data), int(dut.out_sat.value)))


@cocotb.test()
async def waveform_through_the_whole_chain(dut):
    temps = config().get("temp_codes")
    cfg, spec, r = await setup(dut, ["in_valid", "in_code_a", "in_code_b", "in_offset", "in_tan"]
                               + (["in_temp"] if temps is not None else []))
    a, b = cfg["codes_a"], cfg["codes_b"]
    exp = [tuple(e) for e in cfg["expected"]]
    cps, latencies = int(cfg["cycles_per_sample"]), [int(n) for n in cfg["latencies"]]
    dut.in_offset.value, dut.in_tan.value = cfg["ref"]["offset"], cfg["ref"]["tan"]
    got, last_strobe = [], []
    cocotb.start_soon(monitor(dut, got))
    for k in range(len(a)):
        await FallingEdge(dut.clk)
        dut.in_valid.value = 1
        dut.in_code_a.value = a[k]
        dut.in_code_b.value = b[k]
        if temps is not None:
            dut.in_temp.value = temps[k]
        await RisingEdge(dut.clk)
        if (k + 1) % spec.window == 0:
            last_strobe.append(cycle_now())
        await FallingEdge(dut.clk)
        dut.in_valid.value = 0
        # the rest of the strobe's clocks in one wait (a trigger a clock is the bench's cost), ending
        # inside a clock's high half so that the next falling edge is the one before the strobe
        await Timer((cps - 2 + r.choice((0, 0, 0, 2))) * CLK_NS + 1, unit="ns")
    await Timer((max(latencies) + 4) * CLK_NS, unit="ns")
    bad = 0
    for k, (g, w) in enumerate(zip(got, exp)):
        if g[1:] != w:
            bad += 1
            dut._log.error("window %d: got %s, twin %s", k, g[1:], w)
    delays = [g[0] - s for g, s in zip(got, last_strobe)]
    write_record(cfg, "cond_chain", {"windows": len(exp), "mismatches": bad + abs(len(got) - len(exp)),
                                     "latency_cycles": sorted(set(delays)), "saturated": sum(s for _d, s in exp)})
    assert len(got) == len(exp), f"{len(got)} codes out, {len(exp)} expected"
    assert bad == 0, f"{bad} of {len(exp)} windows differ from the twin"
    assert delays == latencies, f"codes {delays} clocks after each window's last strobe, the twin says {latencies}"
