"""Two-input sweep: the VHDL harness flann_sweep.vhd (temp_bits_g > 0) drives every voltage code at each
listed temperature code and writes one line per sample; this bench wakes once, at done, and
checks the whole file against the twin (hardware/thermal/twin.py)."""

from __future__ import annotations

import cocotb
import numpy as np
from cocotb.triggers import RisingEdge

from flann.hardware.thermal.render import rebuild
from flann.hardware.thermal.twin import ThermalTop
from flann.verify.benches import config
from flann.verify.benches.flann_bench import write_record


@cocotb.test()
async def thermal_sweep_vs_twin(dut):
    """Every (voltage code, temperature code) of the sweep, bit-exact vs the twin, fixed latency."""
    cfg = config()
    sweep = cfg["sweep"]
    await RisingEdge(dut.done)
    spec, _ = rebuild(cfg["model"], cfg["manifest"], "thermal sweep")
    got = np.loadtxt(sweep["file"], dtype=np.int64, ndmin=2)
    codes = np.arange(sweep["code_lo"], sweep["code_hi"] + 1, dtype=np.int64)
    temps = np.asarray(sweep["temps"], dtype=np.int64)
    want_c, want_t = np.tile(codes, temps.size), np.repeat(temps, codes.size)
    assert got.shape[0] == want_c.size, f"{got.shape[0]} outputs for {want_c.size} samples"
    assert np.array_equal(got[:, 0], want_c) and np.array_equal(got[:, 1], want_t), "samples out of order"
    out, sat = ThermalTop(spec).process(want_c, want_t)
    bad = (got[:, 2] != out) | (got[:, 3] != sat.astype(np.int64))
    ref = spec.float_reference(want_c, want_t) / spec.output_lsb_mm
    ok = ~(sat & (np.abs(ref) > spec.out_fmt.max_int))
    err = float(np.max(np.abs(got[:, 2] - ref)[ok])) if ok.any() else 0.0
    write_record(cfg, "thermal_sweep", {"mismatches": int(np.count_nonzero(bad)), "samples": int(want_c.size),
                                        "max_err_lsb": err, "latency": sorted(set(got[:, 4].tolist()))})
    for k in np.flatnonzero(bad)[:10]:
        dut._log.error("code %d temp %d: HDL %d sat %d, twin %d sat %d", want_c[k], want_t[k], got[k, 2],
                       got[k, 3], out[k], sat[k])
    assert not bad.any(), f"{int(np.count_nonzero(bad))} mismatches vs the twin"
    lat = set(got[:, 4].tolist())
    assert lat == {spec.latency_cycles}, f"latencies {sorted(lat)} (manifest {spec.latency_cycles})"
