"""Exhaustive sweep: the VHDL harness flann_sweep.vhd drives every code of its range and writes
one line per sample; this bench wakes once, at done, and checks the whole file against the twin."""

from __future__ import annotations

import cocotb
import numpy as np
from cocotb.triggers import RisingEdge

from flann.hardware.fixed.twin import FlannTop
from flann.verify.benches import config
from flann.verify.benches.flann_bench import load_spec, write_record
from flann.verify.shards import read_results


@cocotb.test()
async def sweep_vs_twin(dut):
    """Every code of the shard, bit-exact vs the twin, latency as in the manifest."""
    cfg = config()
    shard = cfg["shard"]
    await RisingEdge(dut.done)
    spec = load_spec(cfg)
    got = read_results(shard["file"])
    want = np.asarray(shard["codes"], dtype=np.int64) if "codes" in shard else \
        np.arange(shard["lo"], shard["hi"] + 1, dtype=np.int64)
    out, sat = FlannTop(spec).process(got["codes"])
    bad = (got["data"] != out) | (got["sat"] != sat)
    write_record(cfg, shard["name"], {"mismatches": int(np.count_nonzero(bad))})
    for k in np.flatnonzero(bad)[:10]:
        dut._log.error("code %d: HDL %d sat %d, twin %d sat %d", got["codes"][k], got["data"][k],
                       got["sat"][k], out[k], sat[k])
    assert np.array_equal(got["codes"], want), f"{got['codes'].size} outputs for {want.size} codes"
    assert not bad.any(), f"{int(np.count_nonzero(bad))} mismatches vs the twin"
    lat = set(got["latency"].tolist())
    assert lat == {spec.latency_cycles}, f"latencies {sorted(lat)} (manifest {spec.latency_cycles})"
