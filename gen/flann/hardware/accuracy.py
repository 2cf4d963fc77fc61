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
from ..golden.model import FlannModel
from ..numeric.fixed import signed_range
from .registry import read_design
from .fixed.cost import fixed_point_cost
from .fixed.spec import Spec
from .fixed.twin import FlannTop
from .family_thermal.spec import FamilyThermalSpec
from .family_thermal.twin import FlannFamilyThermalTop
from .thermal.spec import ThermalSpec
from .thermal.twin import ThermalTop

# the two-input specs and their top-level twins (process(in_data, in_temp) -> out_data, out_sat)
TWO_INPUT_TWINS = {ThermalSpec: ThermalTop, FamilyThermalSpec: FlannFamilyThermalTop}

# -- a generated design, rebuilt ---------------------------------------------------------
def design_spec(model_path, design_dir) -> Spec:
    """The fixed-point Spec that computes what the design in ``design_dir`` outputs for the
    model file ``model_path``, through the manifest's datapath (its ``eval_spec``): the model
    the design was generated from, or for a family design any sensor whose image it can load.
    A datapath without one is refused in one line saying why."""
    man, dp = read_design(design_dir)
    if dp.eval_spec is None:
        raise FlannError(f"{design_dir}: a {dp.name} design: {dp.why_no_eval}")
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


# -- hardware accuracy against the physical limit ------------------------------------------
def adc_codes(spec: Spec, voltage_v, adc: tuple[int, float] | None = None) -> np.ndarray:
    """Voltages as the design receives them: the converter's nearest code, saturated to its
    range; from a converter wider than the design, its top ``spec.input_bits`` bits (the low
    bits are not wired: a floor, as an arithmetic shift right)."""
    bits, lsb = adc if adc is not None else (spec.input_bits, spec.input_lsb_v)
    drop = bits - spec.input_bits
    if drop < 0:
        raise FlannError(f"ADC of {bits} bits is narrower than the design's {spec.input_bits}-bit input")
    c = np.floor(np.asarray(voltage_v, dtype=float) / lsb + 0.5)
    c = np.clip(c, *signed_range(bits)).astype(np.int64) >> drop
    return np.clip(c, spec.code_min, spec.code_max)


def physical_limit_mm(model: FlannModel, voltage_v, input_lsb_v: float) -> np.ndarray:
    """Half an ADC LSB over the sensor's local slope at each voltage: the error a perfect
    compensator behind this converter still has.  The slope dv/dx is that of the model's
    inverse (its dx/dv, by central differences over the trained range)."""
    vlo, vhi = sorted(model.voltage_range_v)
    grid = np.linspace(vlo, vhi, 4001)
    dxdv = np.abs(np.gradient(model.predict(grid), grid))
    v = np.clip(np.asarray(voltage_v, dtype=float), vlo, vhi)
    return 0.5 * input_lsb_v * np.interp(v, grid, dxdv)


def hardware_accuracy(spec: Spec, rec, *, tol, band, fs_mm, adc: tuple[int, float] | None = None) -> dict:
    """The bit-true twin on the recordings' voltages (as ADC codes) against the displacement.

    ``adc`` = (bits, volts per code) of the converter (:func:`design_adc`; default the design's
    input): the physical limit is that converter's, and when the design drops its low bits
    the error they cost is in the hardware figures.  Returns the ``"hardware"`` block of
    ``flann eval --design --json`` plus per-point arrays (``_points``) for the plot.
    """
    if type(spec) in TWO_INPUT_TWINS:
        return thermal_accuracy(spec, rec, tol=tol, band=band, fs_mm=fs_mm)
    adc_bits, adc_lsb = adc if adc is not None else (spec.input_bits, spec.input_lsb_v)
    x = rec.displacement_mm
    codes = adc_codes(spec, rec.voltage_v, (adc_bits, adc_lsb))
    # the twin once per distinct code: a logger's million rows hold at most 2^16 of them,
    # and the twin's per-term intermediates would otherwise take gigabytes
    distinct, back = np.unique(codes, return_inverse=True)
    out, sat = FlannTop(spec).process(distinct)
    out, sat = out[back], sat[back]
    hw_mm = out * spec.output_lsb_mm
    fl_mm = spec.model.predict(rec.voltage_v)
    limit = physical_limit_mm(spec.model, rec.voltage_v, adc_lsb)
    e_hw, e_fl = hw_mm - x, fl_mm - x
    rep = error_report(hw_mm, x, tol, band, fs_mm, rec.direction)
    lim_max = float(limit.max())
    rep.update({
        "input_bits": spec.input_bits, "input_lsb_v": spec.input_lsb_v,
        "adc_bits": adc_bits, "adc_lsb_v": adc_lsb, "dropped_low_bits": adc_bits - spec.input_bits,
        "output_lsb_mm": spec.output_lsb_mm,
        "points_clamped": int(np.count_nonzero(sat)),
        "max_abs_hardware_minus_float_mm": float(np.max(np.abs(hw_mm - fl_mm))),
        # the datapath's own error: the float model at the same (clamped) ADC codes
        "max_abs_hardware_minus_float_at_codes_mm": float(np.max(np.abs(
            hw_mm - spec.float_reference(distinct)[back]))),
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
    codes = np.clip(np.floor(np.asarray(rec.voltage_v, dtype=float) / spec.input_lsb_v + 0.5),
                    spec.code_min, spec.code_max).astype(np.int64)
    tcodes = np.clip(np.floor(np.asarray(rec.temperature_c, dtype=float) / spec.temp_lsb_c + 0.5),
                     spec.temp_code_min, spec.temp_code_max).astype(np.int64)
    # the twin once per distinct (code, temperature code)
    pairs, back = np.unique(np.stack([codes, tcodes], axis=1), axis=0, return_inverse=True)
    back = back.ravel()
    out, sat = TWO_INPUT_TWINS[type(spec)](spec).process(pairs[:, 0], pairs[:, 1])
    hw_mm = out[back] * spec.output_lsb_mm
    v, t, _ = m.clamp(rec.voltage_v, rec.temperature_c)
    fl_mm = m.predict(v, t)
    vlo, vhi = sorted(m.voltage_range_v)
    h = 0.5 * spec.input_lsb_v
    v1, v2 = np.clip(v - h, vlo, vhi), np.clip(v + h, vlo, vhi)
    slope = np.abs(m.predict(v2, t) - m.predict(v1, t)) / np.maximum(v2 - v1, 1e-300)
    limit = 0.5 * spec.input_lsb_v * slope
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


__all__ = ["fixed_point_cost", "design_spec", "design_adc", "adc_codes", "physical_limit_mm", "hardware_accuracy",
           "plot_errors"]
