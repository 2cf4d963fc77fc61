"""Family design with temperature: the VHDL harness flann_family_thermal_sweep.vhd loads one
sensor's image through the cfg port and drives every voltage code at each listed temperature
code; this bench wakes once, at done, and checks the whole file against the twin holding that
image (hardware/family_thermal/twin.py)."""

from __future__ import annotations

import cocotb
import numpy as np
from cocotb.triggers import RisingEdge

from flann.hardware.family_thermal.datapath import rebuild
from flann.hardware.family_thermal.twin import FlannFamilyThermalTop
from flann.verify.benches import config
from flann.verify.benches.flann_bench import write_record


@cocotb.test()
async def family_thermal_sweep_vs_twin(dut):
    """Every (voltage code, temperature code) of the sweep, bit-exact vs the twin, fixed latency."""
    cfg = config()
    sweep = cfg["sweep"]
    await RisingEdge(dut.done)
    spec, _ = rebuild(cfg["model"], cfg["manifest"], "family thermal sweep")
    got = np.loadtxt(sweep["file"], dtype=np.int64, ndmin=2)
    codes = np.arange(sweep["code_lo"], sweep["code_hi"] + 1, dtype=np.int64)
    temps = np.asarray(sweep["temps"], dtype=np.int64)
    want_c, want_t = np.tile(codes, temps.size), np.repeat(temps, codes.size)
    assert got.shape[0] == want_c.size, f"{got.shape[0]} outputs for {want_c.size} samples"
    assert np.array_equal(got[:, 0], want_c) and np.array_equal(got[:, 1], want_t), "samples out of order"
    r = FlannFamilyThermalTop(spec, sweep["words"]).process(want_c, want_t)
    bad = (got[:, 2] != r.out_data) | (got[:, 3] != r.out_sat.astype(np.int64))
    write_record(cfg, "family_thermal_sweep", {"mismatches": int(np.count_nonzero(bad)), "samples": int(want_c.size),
                                               "latency": sorted(set(got[:, 4].tolist()))})
    for k in np.flatnonzero(bad)[:10]:
        dut._log.error("code %d temp %d: HDL %d sat %d, twin %d sat %d", want_c[k], want_t[k], got[k, 2],
                       got[k, 3], r.out_data[k], r.out_sat[k])
    assert not bad.any(), f"{int(np.count_nonzero(bad))} mismatches vs the twin"
    lat = set(got[:, 4].tolist())
    assert lat == {spec.latency_cycles}, f"latencies {sorted(lat)} (manifest {spec.latency_cycles})"
