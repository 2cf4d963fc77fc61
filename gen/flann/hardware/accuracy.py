"""Hardware in view: what a model costs in fixed point, and how accurate the built design is.

* :func:`fixed_point_cost` (from :mod:`.fixed.cost`) -- what ``flann train`` asks when it
  selects among candidate models: can ``flann gen`` build it, and at what cost.
* :func:`design_spec` -- the :class:`Spec` of a generated design, rebuilt from the model and
  the design's ``manifest.json`` (and checked against it).
* :func:`hardware_accuracy` -- the bit-true twin of that design on recordings (voltages
  quantised to the design's ADC codes) against the true displacement, next to the float
  model and the physical limit of the converter (half an ADC LSB over the local slope).
"""

from __future__ import annotations


import numpy as np

from ..errors import FlannError
from ..fileio import atomic_save_figure
from ..golden.metrics import error_report
from ..numeric.fixed import nearest_codes, signed_range
from .adc import wired_codes
from .registry import read_design
from .fixed.cost import fixed_point_cost
from .fixed.spec import Spec
from .fixed.twin import FlannTop
from .float18.spec import F18Spec, FlannF18Top
from .family_thermal.spec import FamilyThermalSpec
from .family_thermal.twin import FlannFamilyThermalTop
from .thermal.spec import ThermalSpec
from .thermal.twin import FlannThermalTop

# the two-input specs and their top-level twins (process(in_data, in_temp) -> out_data, out_sat)
TWO_INPUT_TWINS = {ThermalSpec: FlannThermalTop, FamilyThermalSpec: FlannFamilyThermalTop}

# -- a generated design, rebuilt ---------------------------------------------------------
def design_spec(model_path, design_dir) -> Spec:
    """The fixed-point Spec that computes what the design in ``design_dir`` outputs for the
    model file ``model_path``, through the manifest's datapath (its ``eval_spec``): the model
    the design was generated from, or for a family design any sensor whose image it can load.
    A datapath without one is refused in one line saying why."""
    man, dp = read_design(design_dir)
    if dp.eval_spec is None:
        raise dp.lacking(design_dir, "twin for flann eval --design")
    return dp.eval_spec(model_path, man, design_dir)


def design_adc(design_dir) -> tuple[int, float]:
    """(bits, volts per code) of the converter the design in ``design_dir`` was generated for.

    Wider than the design's input when ``flann gen`` dropped low bits (manifest ``adc_bits``);
    a manifest without it (older flann) had the design's input as the converter.
    """
    man, _ = read_design(design_dir)
    bits, lsb = man.get("adc_bits", man.get("input_bits")), man.get("adc_lsb_v", man.get("input_lsb_v"))
    if not (isinstance(bits, int) and isinstance(lsb, (int, float)) and lsb > 0):
        raise FlannError(f"{design_dir}/manifest.json: adc_bits/adc_lsb_v malformed "
                         f"({bits!r}, {lsb!r}): regenerate the design")
    return bits, float(lsb)


# -- the converter -----------------------------------------------------------------------
def adc_codes(spec: Spec, voltage_v, adc: tuple[int, float] | None = None) -> np.ndarray:
    """Voltages as the design receives them: the converter's nearest code, saturated to its
    range; from a converter wider than the design, its top ``spec.input_bits`` bits (the low
    bits are not wired: a floor, as an arithmetic shift right)."""
    bits, lsb = adc if adc is not None else (spec.input_bits, spec.input_lsb_v)
    c = wired_codes(nearest_codes(voltage_v, lsb, *signed_range(bits)), bits, spec.input_bits)
    return np.clip(c, spec.code_min, spec.code_max)


def temperature_codes(spec, temperature_c) -> np.ndarray:
    """Temperatures as a two-input design receives them: the temperature converter's nearest
    code, saturated to its range (``spec.temp_lsb_c``, ``temp_code_min..temp_code_max``; the
    design clamps further, to its calibrated codes)."""
    return nearest_codes(temperature_c, spec.temp_lsb_c, spec.temp_code_min, spec.temp_code_max)


# -- hardware accuracy against the physical limit ------------------------------------------
def physical_limit_mm(model, voltage_v, lsb_v: float, temperature_c=None) -> np.ndarray:
    """The physical limit at each reading (mm): half an LSB of the converter over the sensor's
    local slope dv/dx, ``0.5 |x(v + lsb/2) - x(v - lsb/2)|`` with ``x(v)`` the model
    (``model.predict``; at the reading's temperature for a two-input model) -- half the
    displacement width of one code's bin.  Every displacement in the bin reads the same code,
    so this is what a perfect compensator behind this converter is still off by; the headline
    ``ratio_to_limit`` of ``flann eval --design`` and of the production certificate is the max
    error over the largest of these, worst over the stroke.

    The bin is kept inside the model's trained voltage range (temperatures are clipped to its
    calibrated range): the model is the only knowledge of the slope and is a fit only there,
    and the designs clamp their codes to that range.  A reading within half an LSB of an end,
    or beyond it, gets the bin that ends at the range's end.  A bin reaching past the end
    took the fit's continuation, which no data pins: a FLANN fitted to a curve's inverse has
    a slope there no sensor has (an erf sensor read with 10 bits: 0.92 mm at the end for one
    model of the same recording, 0.17 mm for another, 0.107 mm from the sensor's formula);
    inside, the slope is taken half an LSB in (1 % lower at the flat end of an S-curve read
    with 8 bits).

    ``model`` is anything with ``predict`` and ``voltage_range_v`` (a benchmark's true sensor
    too); ``lsb_v`` is the converter's LSB (the full ADC's when the design drops low bits)."""
    lo, hi = sorted(model.voltage_range_v)
    h = min(0.5 * lsb_v, 0.5 * (hi - lo))   # a range narrower than an LSB: the slope across it
    v = np.clip(np.asarray(voltage_v, dtype=float), lo + h, hi - h)
    if temperature_c is None:
        dx = model.predict(v + h) - model.predict(v - h)
    else:
        t = np.clip(np.broadcast_to(np.asarray(temperature_c, dtype=float), v.shape),
                    *sorted(model.temperature_range_c))
        dx = model.predict(v + h, t) - model.predict(v - h, t)
    return 0.5 * np.abs(dx) * (lsb_v / (2 * h))


def hardware_accuracy(spec: Spec, rec, *, tol, band, fs_mm, adc: tuple[int, float] | None = None) -> dict:
    """The bit-true twin on the recordings' voltages (as ADC codes) against the displacement.

    ``adc`` = (bits, volts per code) of the converter (:func:`design_adc`; default the design's
    input): the physical limit is that converter's, and when the design drops its low bits
    the error they cost is in the hardware figures.  Returns the ``"hardware"`` block of
    ``flann eval --design --json`` plus per-point arrays (``_points``) for the plot.
    """
    if type(spec) in TWO_INPUT_TWINS:
        return thermal_accuracy(spec, rec, tol=tol, band=band, fs_mm=fs_mm)
    # a float18 design shares the fixed front end (input, clamp, the float reference); its
    # output is a float18 number in mm, with no output LSB
    front = spec.front if isinstance(spec, F18Spec) else spec
    adc_bits, adc_lsb = adc if adc is not None else (front.input_bits, front.input_lsb_v)
    x = rec.displacement_mm
    codes = adc_codes(front, rec.voltage_v, (adc_bits, adc_lsb))
    # the twin once per distinct code: a logger's million rows hold at most 2^16 of them,
    # and the twin's per-term intermediates would otherwise take gigabytes
    distinct, back = np.unique(codes, return_inverse=True)
    if isinstance(spec, F18Spec):
        twin = FlannF18Top(spec)
        out_mm, sat = twin.out_mm(distinct), np.asarray(twin.process(distinct).out_sat)
        output_lsb = None
    else:
        out, sat = FlannTop(spec).process(distinct)
        out_mm, output_lsb = out * spec.output_lsb_mm, spec.output_lsb_mm
    at_codes = out_mm
    hw_mm, sat = out_mm[back], sat[back]
    # the float model as eval's compensated column gives it: clamped to the trained range, as
    # the hardware does (unclamped, its sum beyond the range put 0.045 mm into hardware - float)
    fl_mm = spec.model.predict(spec.model.clamp(rec.voltage_v)[0])
    limit = physical_limit_mm(spec.model, rec.voltage_v, adc_lsb)
    e_hw, e_fl = hw_mm - x, fl_mm - x
    rep = error_report(hw_mm, x, tol, band, fs_mm, rec.direction)
    lim_max = float(limit.max())
    rep.update({
        "input_bits": front.input_bits, "input_lsb_v": front.input_lsb_v,
        "adc_bits": adc_bits, "adc_lsb_v": adc_lsb, "dropped_low_bits": adc_bits - front.input_bits,
        "output_lsb_mm": output_lsb, "number_format": getattr(spec, "number_format", "fixed"),
        "points_clamped": int(np.count_nonzero(sat)),
        "max_abs_hardware_minus_float_mm": float(np.max(np.abs(hw_mm - fl_mm))),
        # the datapath's own error: the float model at the same (clamped) ADC codes
        "max_abs_hardware_minus_float_at_codes_mm": float(np.max(np.abs(
            at_codes - front.float_reference(distinct)))),
        "physical_limit_mm": {"max": lim_max, "median": float(np.median(limit)),
                              "min": float(limit.min())},
        "ratio_to_limit": float(np.max(np.abs(e_hw)) / lim_max),
        "float_ratio_to_limit": float(np.max(np.abs(e_fl)) / lim_max),
        "worst_pointwise_ratio": float(np.max(np.abs(e_hw) / limit)),
    })
    rep["_points"] = {"x": x, "hardware": e_hw, "float": e_fl, "limit": limit}
    return rep


def thermal_accuracy(spec: ThermalSpec | FamilyThermalSpec, rec, *, tol, band, fs_mm) -> dict:
    """:func:`hardware_accuracy` of a two-input design: its twin at the recordings' voltages and
    temperatures as the design's codes (nearest code, saturated to the code range; the design
    clamps both to the calibrated codes), the float model at the recorded (clamped) values, and
    the physical limit (half an ADC LSB over the model's local slope at each reading's temperature)."""
    if rec.temperature_c is None:
        raise FlannError(f"{rec.source}: a two-input design needs a temperature_c column")
    m, x = spec.model, rec.displacement_mm
    codes = adc_codes(spec, rec.voltage_v)
    tcodes = temperature_codes(spec, rec.temperature_c)
    # the twin once per distinct (code, temperature code)
    pairs, back = np.unique(np.stack([codes, tcodes], axis=1), axis=0, return_inverse=True)
    back = back.ravel()
    out, sat = TWO_INPUT_TWINS[type(spec)](spec).process(pairs[:, 0], pairs[:, 1])
    hw_mm = out[back] * spec.output_lsb_mm
    v, t, _ = m.clamp(rec.voltage_v, rec.temperature_c)
    fl_mm = m.predict(v, t)
    limit = physical_limit_mm(m, rec.voltage_v, spec.input_lsb_v, rec.temperature_c)
    e_hw, e_fl = hw_mm - x, fl_mm - x
    rep = error_report(hw_mm, x, tol, band, fs_mm, rec.direction)
    lim_max = float(limit.max())
    rep.update({
        "input_bits": spec.input_bits, "input_lsb_v": spec.input_lsb_v,
        "adc_bits": spec.input_bits, "adc_lsb_v": spec.input_lsb_v, "dropped_low_bits": 0,
        "temp_bits": spec.temp_bits, "temp_lsb_c": spec.temp_lsb_c,
        **({"weight_image": spec.image} if isinstance(spec, FamilyThermalSpec) else {}),
        "output_lsb_mm": spec.output_lsb_mm,
        "points_clamped": int(np.count_nonzero(sat[back])),
        "max_abs_hardware_minus_float_mm": float(np.max(np.abs(hw_mm - fl_mm))),
        "max_abs_hardware_minus_float_at_codes_mm": float(np.max(np.abs(
            out * spec.output_lsb_mm - spec.float_reference(pairs[:, 0], pairs[:, 1])))),
        "physical_limit_mm": {"max": lim_max, "median": float(np.median(limit)),
                              "min": float(limit.min())},
        "ratio_to_limit": float(np.max(np.abs(e_hw)) / lim_max),
        "float_ratio_to_limit": float(np.max(np.abs(e_fl)) / lim_max),
        "worst_pointwise_ratio": float(np.max(np.abs(e_hw) / np.maximum(limit, 1e-300))),
    })
    rep["_points"] = {"x": x, "hardware": e_hw, "float": e_fl, "limit": limit}
    return rep


def plot_errors(path, x, raw_err, float_err, hw_err, limit, title: str = "") -> None:
    """Error vs displacement: raw sensor, float model, hardware, +- the physical limit (PNG)."""
    import matplotlib  # lazy: plotting is optional and slow to import

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    order = np.argsort(x, kind="stable")
    xs = np.asarray(x)[order]
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True,
                                 gridspec_kw={"height_ratios": [1, 2]})
    a1.plot(xs, np.asarray(raw_err)[order], ".", ms=2, color="0.5", label="raw sensor (least-squares line)")
    a1.set_ylabel("error (mm)")
    a1.legend(loc="best", fontsize=8)
    a1.set_title(title or "error vs displacement")
    lim = np.asarray(limit)[order]
    a2.fill_between(xs, -lim, lim, color="C2", alpha=0.2, lw=0, label="physical limit (½ ADC LSB / slope)")
    a2.plot(xs, np.asarray(float_err)[order], ".", ms=2.5, color="C0", label="float model")
    a2.plot(xs, np.asarray(hw_err)[order], ".", ms=2, color="C3", label="hardware (bit-true twin, ADC codes)")
    a2.set_ylabel("error (mm)")
    a2.set_xlabel("displacement (mm)")
    a2.legend(loc="best", fontsize=8)
    fig.tight_layout()
    try:
        atomic_save_figure(fig, path, dpi=120)
    finally:
        plt.close(fig)


__all__ = ["fixed_point_cost", "design_spec", "design_adc", "adc_codes", "temperature_codes",
           "physical_limit_mm", "hardware_accuracy", "plot_errors"]
