"""Whether a two-input design's widths keep the model's accuracy.

The hardware reads a voltage code and a temperature code: a reading between two codes is off by
up to half a step in each, which moves the displacement by half a step times the model's slope
in that input; the design then adds its own error (its stated bound, ``pre_rounding_lsb`` + 1/2
output LSB).  That sum, the worst over the calibrated voltages and temperatures, is what the
hardware may lose on top of the float model.  The reference is the float model's own error level
(the smaller of its held-out max error and 3x its training RMS): the hardware may add at most half
of it (``HARDWARE_FACTOR`` 1.5 in all), or ``flann gen`` warns and names the widths that keep it.

The drift (ppm of full scale per degC, :mod:`flann.golden.thermal_metrics`) is judged the same
way.  At one position the voltage moves with temperature across the voltage codes, and the
temperature crosses its own codes: each reading's rounding sweeps a whole step in each input,
and the design's own error both ways, so the hardware's error at that position may spread by
up to a step times each slope plus twice its own bound over the calibrated temperatures.  That
spread per degC of the calibrated span, in ppm of full scale (half the displacement range), is
what the hardware may add to the float model's drift; the float model's own drift level is its
error level over the same span.  The hardware may add at most half of it, as for the max error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...errors import FlannError
from ...golden.verdict import HARDWARE_FACTOR
from .spec import derive_thermal_spec

GRID_VOLTAGES, GRID_TEMPERATURES = 401, 41
FINEST_TEMP_LSB_C = 0.1   # the finest temperature step gen proposes (a sensor's own resolution)


def reference_error_mm(model) -> float | None:
    """The float model's own error level: the smaller of its held-out max error and three times
    its training RMS error (recordings at other temperatures see about that), or None."""
    t = model.training or {}
    found = [float(t[k]) * f for k, f in (("cv_max_error_mm", 1.0), ("train_rms_error_mm", 3.0))
             if isinstance(t.get(k), (int, float)) and t[k] > 0]
    return min(found) if found else None


@dataclass(frozen=True)
class Slopes:
    """|dx/dv| (mm/V) and |dx/dT| (mm/degC) of a two-input model over its calibrated voltages
    and temperatures, on a grid; the temperature span and full scale its drift is judged in."""

    v: np.ndarray
    t: np.ndarray
    span_c: float
    fs_mm: float

    @classmethod
    def of(cls, model) -> Slopes:
        v = np.linspace(*sorted(model.voltage_range_v), GRID_VOLTAGES)
        t = np.linspace(*sorted(model.temperature_range_c), GRID_TEMPERATURES)
        vv, tt = np.meshgrid(v, t)
        dv, dt = 1e-3 * (v[-1] - v[0]), 1e-3 * max(t[-1] - t[0], 1.0)
        slope_v = (model.predict(vv + dv, tt) - model.predict(vv - dv, tt)) / (2 * dv)
        slope_t = (model.predict(vv, tt + dt) - model.predict(vv, tt - dt)) / (2 * dt)
        lo, hi = sorted(model.displacement_range_mm)
        return cls(np.abs(slope_v), np.abs(slope_t), max(t[-1] - t[0], 1.0), max(0.5 * (hi - lo), 1e-12))

    def steps_mm(self, lsb_v: float, lsb_c: float) -> float:
        """The worst over the grid of one step in each input times the model's slope there."""
        return float(np.max(lsb_v * self.v + lsb_c * self.t))

    def ppm(self, spread_mm: float) -> float:
        """A spread of the error over the calibrated temperatures, as ppm FS/degC."""
        return spread_mm / self.span_c / self.fs_mm * 1e6


def quantisation_mm(model, lsb_v: float, lsb_c: float, slopes: Slopes | None = None) -> float:
    """The worst displacement error of reading the voltage and temperature to the nearest code
    (half a step in each, times the model's slope there) over the calibrated range."""
    return 0.5 * (slopes or Slopes.of(model)).steps_mm(lsb_v, lsb_c)


@dataclass(frozen=True)
class Loss:
    """What a design's widths may add to the float model: max error (mm) and drift (ppm FS/degC)."""

    error_mm: float
    drift_ppm: float


def _loss(slopes: Slopes, lsb_v: float, lsb_c: float, own_mm: float) -> Loss:
    steps = slopes.steps_mm(lsb_v, lsb_c)
    return Loss(0.5 * steps + own_mm, slopes.ppm(steps + 2.0 * own_mm))


def _own_mm(spec) -> float:
    """The design's own error bound (mm): its rounding before the output and half an output LSB."""
    return (spec.analysis["pre_rounding_lsb"] + 0.5) * spec.output_lsb_mm


def widths_warning(spec) -> str | None:
    """A warning when ``spec``'s widths lose more than the model's accuracy allows (max error or
    drift), naming the input and temperature widths (same ranges) that keep both; None when they
    keep it."""
    model = spec.model
    ref = reference_error_mm(model)
    if ref is None:
        return None
    slopes = Slopes.of(model)
    ref_drift = slopes.ppm(ref)
    allowed = Loss((HARDWARE_FACTOR - 1.0) * ref, (HARDWARE_FACTOR - 1.0) * ref_drift)

    def kept(loss: Loss) -> bool:
        return loss.error_mm <= allowed.error_mm and loss.drift_ppm <= allowed.drift_ppm

    own = _own_mm(spec)
    lost = _loss(slopes, spec.input_lsb_v, spec.temp_lsb_c, own)
    if kept(lost):
        return None
    beyond = []
    if lost.error_mm > allowed.error_mm:
        beyond.append(f"lose up to {lost.error_mm:.3g} mm to the code steps and the design's rounding, more than "
                      f"{HARDWARE_FACTOR - 1:g}x the model's own max error {ref:.3g} mm")
    if lost.drift_ppm > allowed.drift_ppm:
        beyond.append(f"add up to {lost.drift_ppm:.3g} ppm FS/degC of drift (a step of each code at one position "
                      f"over the calibrated {slopes.span_c:g} degC), more than {HARDWARE_FACTOR - 1:g}x the model's "
                      f"own drift level {ref_drift:.3g} ppm FS/degC")
    said = (f"--input-bits {spec.input_bits} x {spec.input_lsb_v:.4g} V and --temp-bits {spec.temp_bits} x "
            f"{spec.temp_lsb_c:g} degC {' and '.join(beyond)} (the hardware would exceed "
            f"{HARDWARE_FACTOR:g}x the float model)")
    for bits, tbits, tlsb in _wider(spec):
        lsb = spec.input_lsb_v * 2.0 ** (spec.input_bits - bits)
        # the output LSB follows the input's: the design's own error scales with it
        if not kept(_loss(slopes, lsb, tlsb, own * 2.0 ** (spec.input_bits - bits))):
            continue
        try:
            wider = derive_thermal_spec(model, input_bits=bits, input_lsb_v=lsb, temp_bits=tbits, temp_lsb_c=tlsb)
        except FlannError:
            continue
        if kept(_loss(slopes, wider.input_lsb_v, wider.temp_lsb_c, _own_mm(wider))):
            return (f"{said}: --input-bits {bits} --temp-bits {tbits} --temp-lsb-c {tlsb:g} keep it "
                    "(max error and drift)")
    return f"{said}: no converter up to 16 bits and {FINEST_TEMP_LSB_C:g} degC keeps it"


def _wider(spec):
    """(input bits, temperature bits, temperature LSB) over the same ranges, the fewest bits first."""
    tspan = spec.temp_lsb_c * 2 ** spec.temp_bits
    options = []
    # the asked temperature step halved, and the finest step named (0.1 degC)
    steps = [spec.temp_lsb_c / 2 ** k for k in range(8) if spec.temp_lsb_c / 2 ** k >= FINEST_TEMP_LSB_C]
    if not steps or steps[-1] > FINEST_TEMP_LSB_C:
        steps.append(FINEST_TEMP_LSB_C)
    for bits in range(spec.input_bits, 17):
        for tlsb in steps:
            tbits = max(spec.temp_bits, math.ceil(math.log2(tspan / tlsb)))
            if tbits <= 16:
                options.append((bits + tbits, bits, tbits, tlsb))
    return [(b, tb, tl) for _, b, tb, tl in sorted(options)]


__all__ = ["widths_warning", "quantisation_mm", "reference_error_mm"]
