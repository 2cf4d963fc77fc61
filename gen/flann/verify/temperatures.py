"""The temperature codes a two-input design's sweeps run (the RTL benches, the mapped netlist,
``flann trace``): one choice for every sweep of a design with temperature."""

from __future__ import annotations

import numpy as np

# a two-input sweep over every voltage code at every temperature code up to this many samples;
# above it, every voltage code at THERMAL_TEMPS temperature codes (both ends of the code range,
# both ends of the calibrated range, evenly spaced codes between)
THERMAL_MAX_SAMPLES = 2_000_000
THERMAL_TEMPS = 17
# the family design with temperature: every voltage code at both ends of the temperature code range
# and this many codes evenly spaced over the calibrated range (its ends included)
FAMILY_THERMAL_TEMPS = 7


def thermal_temperature_codes(spec, max_samples: int = THERMAL_MAX_SAMPLES) -> tuple[list[int], bool]:
    """(temperature codes the sweep runs, every code?)."""
    every = list(range(spec.temp_code_min, spec.temp_code_max + 1))
    if len(every) * (spec.code_max - spec.code_min + 1) <= max_samples:
        return every, True
    inner = np.linspace(spec.temp_lo, spec.temp_hi, THERMAL_TEMPS - 2).round().astype(int).tolist()
    return sorted({spec.temp_code_min, spec.temp_code_max, *inner}), False


def family_thermal_temperature_codes(spec) -> list[int]:
    """The temperature codes the family-with-temperature sweep runs: both ends of the code range
    (clamped), FAMILY_THERMAL_TEMPS evenly spaced codes over the calibrated range (its ends included)."""
    inner = np.linspace(spec.temp_lo, spec.temp_hi, FAMILY_THERMAL_TEMPS).round().astype(int).tolist()
    return sorted({spec.temp_code_min, spec.temp_code_max, *inner})


__all__ = ["THERMAL_MAX_SAMPLES", "THERMAL_TEMPS", "FAMILY_THERMAL_TEMPS", "thermal_temperature_codes",
           "family_thermal_temperature_codes"]
