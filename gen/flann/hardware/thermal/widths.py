"""Whether a two-input design's widths keep the model's accuracy.

The hardware reads a voltage code and a temperature code: a reading between two codes is off by
up to half a step in each, which moves the displacement by half a step times the model's slope
in that input; the design then adds its own error (its stated bound, ``pre_rounding_lsb`` + 1/2
output LSB).  That sum, the worst over the calibrated voltages and temperatures, is what the
hardware may lose on top of the float model.  The reference is the float model's own error level
(the smaller of its held-out max error and 3x its training RMS): the hardware may add at most half
of it (``HARDWARE_FACTOR`` 1.5 in all), or ``flann gen`` warns and names the widths that keep it.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import FlannError
from ...golden.verdict import HARDWARE_FACTOR
from .spec import derive_thermal_spec

GRID_VOLTAGES, GRID_TEMPERATURES = 401, 41


def reference_error_mm(model) -> float | None:
    """The float model's own error level: the smaller of its held-out max error and three times
    its training RMS error (recordings at other temperatures see about that), or None."""
    t = model.training or {}
    found = [float(t[k]) * f for k, f in (("cv_max_error_mm", 1.0), ("train_rms_error_mm", 3.0))
             if isinstance(t.get(k), (int, float)) and t[k] > 0]
    return min(found) if found else None


def quantisation_mm(model, lsb_v: float, lsb_c: float) -> float:
    """The worst displacement error of reading the voltage and temperature to the nearest code
    (half a step in each, times the model's slope there) over the calibrated range."""
    v = np.linspace(*sorted(model.voltage_range_v), GRID_VOLTAGES)
    t = np.linspace(*sorted(model.temperature_range_c), GRID_TEMPERATURES)
    vv, tt = np.meshgrid(v, t)
    dv, dt = 1e-3 * (v[-1] - v[0]), 1e-3 * max(t[-1] - t[0], 1.0)
    slope_v = (model.predict(vv + dv, tt) - model.predict(vv - dv, tt)) / (2 * dv)
    slope_t = (model.predict(vv, tt + dt) - model.predict(vv, tt - dt)) / (2 * dt)
    return float(np.max(0.5 * lsb_v * np.abs(slope_v) + 0.5 * lsb_c * np.abs(slope_t)))


def widths_warning(spec) -> str | None:
    """A warning when ``spec``'s widths lose more than the model's accuracy allows, naming the
    input and temperature widths (same ranges) that keep it; None when they keep it."""
    model = spec.model
    ref = reference_error_mm(model)
    if ref is None:
        return None
    allowed = (HARDWARE_FACTOR - 1.0) * ref
    own = (spec.analysis["pre_rounding_lsb"] + 0.5) * spec.output_lsb_mm
    lost = _lost_mm(spec)
    if lost <= allowed:
        return None
    said = (f"--input-bits {spec.input_bits} x {spec.input_lsb_v:.4g} V and --temp-bits {spec.temp_bits} x "
            f"{spec.temp_lsb_c:g} degC lose up to {lost:.3g} mm to the code steps and the design's rounding, more than "
            f"{HARDWARE_FACTOR - 1:g}x the model's own max error {ref:.3g} mm (the hardware would exceed "
            f"{HARDWARE_FACTOR:g}x the float model)")
    for bits, tbits, tlsb in _wider(spec):
        lsb = spec.input_lsb_v * 2.0 ** (spec.input_bits - bits)
        # the output LSB follows the input's: the design's own error scales with it
        if quantisation_mm(model, lsb, tlsb) + own * 2.0 ** (spec.input_bits - bits) > allowed:
            continue
        try:
            wider = derive_thermal_spec(model, input_bits=bits, input_lsb_v=lsb, temp_bits=tbits, temp_lsb_c=tlsb)
        except FlannError:
            continue
        if _lost_mm(wider) <= allowed:
            return f"{said}: --input-bits {bits} --temp-bits {tbits} --temp-lsb-c {tlsb:g} keep it"
    return f"{said}: no converter up to 16 bits and 0.1 degC keeps it"


def _lost_mm(spec) -> float:
    """What the hardware may add to the float model's error: the code steps and its own bound."""
    own = (spec.analysis["pre_rounding_lsb"] + 0.5) * spec.output_lsb_mm
    return quantisation_mm(spec.model, spec.input_lsb_v, spec.temp_lsb_c) + own


def _wider(spec):
    """(input bits, temperature bits, temperature LSB) over the same ranges, the fewest bits first."""
    tspan = spec.temp_lsb_c * 2 ** spec.temp_bits
    options = []
    for bits in range(spec.input_bits, 17):
        for halvings in range(0, 8):
            tlsb = spec.temp_lsb_c / 2 ** halvings
            if tlsb < 0.1:
                break
            tbits = max(spec.temp_bits, math.ceil(math.log2(tspan / tlsb)))
            if tbits <= 16:
                options.append((bits + tbits, bits, tbits, tlsb))
    return [(b, tb, tl) for _, b, tb, tl in sorted(options)]


__all__ = ["widths_warning", "quantisation_mm", "reference_error_mm"]
