"""Family design with temperature: the VHDL harness flann_sweep.vhd (addr_bits_g > 0) loads one
sensor's image through the cfg port and drives every voltage code at each listed temperature
code; this bench wakes once, at done, and checks the whole file against the twin holding that
image (hardware/family_thermal/twin.py)."""

from __future__ import annotations

import cocotb

from flann.hardware.family_thermal.datapath import rebuild
from flann.hardware.family_thermal.twin import FlannFamilyThermalTop
from flann.verify.benches.flann_bench import judge_two_input, two_input_sweep


@cocotb.test()
async def family_thermal_sweep_vs_twin(dut):
    """Every (voltage code, temperature code) of the sweep, bit-exact vs the twin, fixed latency."""
    cfg, spec, got, want_c, want_t = await two_input_sweep(dut, rebuild, "family thermal sweep")
    r = FlannFamilyThermalTop(spec, cfg["sweep"]["words"]).process(want_c, want_t)
    judge_two_input(dut, cfg, "family_thermal_sweep", got, r.out_data, r.out_sat, spec.latency_cycles, {})
