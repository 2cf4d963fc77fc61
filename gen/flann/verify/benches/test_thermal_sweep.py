"""Two-input sweep: the VHDL harness flann_sweep.vhd (temp_bits_g > 0) drives every voltage code at each
listed temperature code and writes one line per sample; this bench wakes once, at done, and
checks the whole file against the twin (hardware/thermal/twin.py)."""

from __future__ import annotations

import cocotb
import numpy as np

from flann.hardware.thermal.render import rebuild
from flann.hardware.thermal.twin import FlannThermalTop
from flann.verify.benches.flann_bench import judge_two_input, two_input_sweep


@cocotb.test()
async def thermal_sweep_vs_twin(dut):
    """Every (voltage code, temperature code) of the sweep, bit-exact vs the twin, fixed latency."""
    cfg, spec, got, want_c, want_t = await two_input_sweep(dut, rebuild, "thermal sweep")
    out, sat = FlannThermalTop(spec).process(want_c, want_t)
    ref = spec.float_reference(want_c, want_t) / spec.output_lsb_mm
    ok = ~(sat & (np.abs(ref) > spec.out_fmt.max_int))
    err = float(np.max(np.abs(got[:, 2] - ref)[ok])) if ok.any() else 0.0
    judge_two_input(dut, cfg, "thermal_sweep", got, out, sat, spec.latency_cycles, {"max_err_lsb": err})
