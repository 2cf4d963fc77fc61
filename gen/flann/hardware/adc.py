"""The converter in front of the datapath: what range it covers, how many bits the design takes,
the default output LSB, and why a model cannot be built in fixed point.

Called by :func:`flann.hardware.fixed.spec.derive_spec` before it sizes the datapath, so that
ranges and units that cannot be right are stopped with a message naming the user's option
(``--input-bits``, ``--input-lsb-v``, ``--output-lsb-mm``) or the model's property that caused
them, instead of surfacing as an out-of-range derived width.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SpecError
from ..golden.model import FlannModel

ADC_BITS = (4, 32)           # ADC widths accepted (wider ones give their top MAX_DESIGN_INPUT_BITS)
MAX_DESIGN_INPUT_BITS = 16   # widest ADC code the datapath takes (serial normaliser, guard bits)
# behind the conditioner: the ratio's resolution, which a 16-bit input would cut below the
# conditioner's own (its top 16 of 21 bits: 15.7 bits over the LVDT's stroke against 16.7 of
# noise); every code is verified through the compiled netlist, the VHDL on a sample
CHAIN_INPUT_BITS = 20
# model.json's training record: the output's rms noise (mm) at the conditioner's ratio rate
WINDOW_NOISE = "window_noise_rms_mm"


def max_input_bits(model) -> int:
    """The widest input code a design of ``model`` takes: the ratio's behind a conditioner.  A
    two-input model's keeps 16 (its orders interpolate below them): its sweep runs every code at
    each of some temperature codes, which 20 bits would make sixteen times as long."""
    if getattr(model, "conditioner", None) is None or len(model.inputs) > 1:
        return MAX_DESIGN_INPUT_BITS
    return CHAIN_INPUT_BITS


def top_bits(model, bits: int, lsb: float) -> tuple[int, float, int]:
    """(bits, value per code, low bits dropped) of a ``bits``-bit converter of ``lsb`` as a
    design of ``model`` takes it: its top bits, at most :func:`max_input_bits`."""
    dropped = max(0, bits - max_input_bits(model))
    return bits - dropped, lsb * (1 << dropped), dropped


MIN_TRAINED_CODES = 16       # fewer codes over the trained range cannot carry a calibration
MIN_OUTPUT_CODES = 16        # the same floor on the output: codes over the trained stroke
SMALL_FRACTION = 1 / 16      # the trained range uses less than this of the ADC: said (4 bits lost)
DEFAULT_INPUT_MARGIN = 1.10  # default input LSB: trained range + 10 %


@dataclass(frozen=True)
class AdcPlan:
    """How the ADC's codes enter the design.

    ``adc_bits``/``adc_lsb_v`` are the converter as the user gave it; the design takes its top
    ``input_bits`` bits (``dropped`` low bits discarded), so one design code is ``input_lsb_v``.
    """

    adc_bits: int
    adc_lsb_v: float
    input_bits: int
    input_lsb_v: float
    dropped: int
    notes: tuple[str, ...] = ()


def default_input_lsb(model: FlannModel, bits: int) -> float:
    """Volts per code covering the trained range + 10 %, 3 significant digits (rounded up)."""
    return default_lsb_for_range(model.voltage_range_v, bits)


def default_lsb_for_range(voltage_range_v, bits: int) -> float:
    """:func:`default_input_lsb` of a voltage range (before a model exists: flann train)."""
    vlo, vhi = sorted(voltage_range_v)
    x = max(abs(vlo), abs(vhi), 1e-12) * DEFAULT_INPUT_MARGIN / (1 << (bits - 1))
    e = math.floor(math.log10(x)) - 2
    return float(f"{math.ceil(x / 10.0 ** e) * 10.0 ** e:.12g}")


def _opts(bits, lsb_v, lsb_given: bool) -> str:
    return f"--input-bits {bits}" + (f" --input-lsb-v {lsb_v:g}" if lsb_given else "")


def plan_adc(model: FlannModel, input_bits, input_lsb_v=None, clamp: bool = True) -> AdcPlan:
    """Check the converter against the trained voltage range; drop low bits of wide ADCs.

    * an ADC wider than 16 bits (24-bit sigma-delta conditioners are usual) is accepted: the
      design takes the top 16 bits, the message states the coarser LSB and what it costs in mm;
    * a trained range the ADC cannot represent is an error naming both ranges (a unit mistake:
      millivolts read as volts, or a wrong --input-lsb-v);
    * a trained range holding fewer than 16 codes is an error naming --input-lsb-v;
    * a trained range using under 1/16 of the ADC's range is said (resolution thrown away).
    """
    bits, lsb, lsb_given = check_converter(model.voltage_range_v, input_bits, input_lsb_v, clamp)
    check_output_range(model)
    vlo, vhi = sorted(model.voltage_range_v)
    lo_v, hi_v = -(1 << (bits - 1)) * lsb, ((1 << (bits - 1)) - 1) * lsb
    opts = _opts(bits, lsb, lsb_given)
    notes = []
    used = (vhi - vlo) / (hi_v - lo_v)
    if used < SMALL_FRACTION:
        notes.append(
            f"the trained range {vlo:.6g}..{vhi:.6g} V uses {100 * used:.2g} % of the ADC's "
            f"{lo_v:.6g}..{hi_v:.6g} V ({opts}): about {math.log2(1 / used):.1f} of its bits "
            "carry no signal; check the voltage unit or the conditioner's gain")
    eff_bits, eff_lsb, dropped = top_bits(model, bits, lsb)
    if dropped and getattr(model, "conditioner", None) is not None:
        # the chain top wires the ratio's top bits itself: nothing for the user to wire
        notes.append(
            f"the FLANN takes the ratio's top {eff_bits} of {bits} bits (its input LSB {eff_lsb:.4g}): up "
            f"to {eff_lsb * max_mm_per_v(model):.3g} mm of quantisation error at the steepest point (a "
            f"FLANN input is at most {eff_bits} bits)")
    elif dropped:
        slope = max_mm_per_v(model)
        notes.append(
            f"{bits}-bit ADC: the design takes its top {eff_bits} bits (drops {dropped} low bits; "
            f"wire the ADC's bits {bits - 1}..{dropped} to in_data): input LSB {lsb:.4g} -> "
            f"{eff_lsb:.4g} V, adding up to {eff_lsb * slope:.3g} mm of quantisation error "
            f"at the steepest point (was {0.5 * lsb * slope:.3g} mm; unwired low bits floor the "
            "code: up to one input LSB, half of it on average as an offset)")
    return AdcPlan(bits, lsb, eff_bits, eff_lsb, dropped, tuple(notes))


def wired_codes(codes, adc_bits: int, input_bits: int) -> np.ndarray:
    """A converter's ``adc_bits``-bit codes as a design of ``input_bits`` receives them: its top
    bits (the low ``adc_bits - input_bits`` are not wired: a floor, as an arithmetic shift right)."""
    drop = int(adc_bits) - int(input_bits)
    if drop < 0:
        raise SpecError(f"ADC of {adc_bits} bits is narrower than the design's {input_bits}-bit input")
    return np.asarray(codes, dtype=np.int64) >> drop


def check_converter(voltage_range_v, input_bits, input_lsb_v=None,
                    clamp: bool = True) -> tuple[int, float, bool]:
    """(bits, volts per code, whether the LSB was given) of a converter that can carry the
    trained ``voltage_range_v``; SpecError naming the option otherwise.  The rule of
    :func:`plan_adc`, callable before a model exists (flann train --input-bits)."""
    if isinstance(input_bits, bool) or not isinstance(input_bits, (int, np.integer)) or \
            not ADC_BITS[0] <= int(input_bits) <= ADC_BITS[1]:
        raise SpecError(f"input_bits = {input_bits!r} (--input-bits): must be an integer in "
                        f"{ADC_BITS[0]}..{ADC_BITS[1]} (the design "
                        f"takes at most the top {MAX_DESIGN_INPUT_BITS})")
    bits = int(input_bits)
    lsb_given = input_lsb_v is not None
    if lsb_given and not (isinstance(input_lsb_v, (int, float)) and math.isfinite(input_lsb_v)
                          and input_lsb_v > 0):
        raise SpecError(f"input_lsb_v = {input_lsb_v!r} (--input-lsb-v): must be a positive number of volts")
    lsb = float(input_lsb_v) if lsb_given else default_lsb_for_range(voltage_range_v, bits)
    vlo, vhi = sorted(voltage_range_v)
    lo_v, hi_v = -(1 << (bits - 1)) * lsb, ((1 << (bits - 1)) - 1) * lsb
    opts = _opts(bits, lsb, lsb_given)
    if clamp and (vlo < lo_v - lsb or vhi > hi_v + lsb):
        full = (1 << bits) * lsb
        unipolar = (f"; a unipolar 0..{full:.6g} V converter? the design takes two's-complement "
                    f"codes: train on the voltages minus {full / 2:.6g} V and feed it the codes with "
                    "their top bit inverted") if vlo >= -lsb and vhi <= full else ""
        raise SpecError(
            f"the trained voltage range {vlo:.6g}..{vhi:.6g} V does not fit the ADC's range "
            f"{lo_v:.6g}..{hi_v:.6g} V ({opts}): check the recordings' voltage unit "
            "(millivolts under a voltage_v header? name the column voltage_mv) or the ADC options"
            + unipolar)
    codes = (vhi - vlo) / lsb
    if codes < MIN_TRAINED_CODES and not lsb_given:
        raise SpecError(
            f"input_bits = {bits} (--input-bits): the trained range {vlo:.6g}..{vhi:.6g} V spans only "
            f"{codes:.3g} codes of a {bits}-bit ADC (need >= {MIN_TRAINED_CODES}): use a wider converter")
    if codes < MIN_TRAINED_CODES:
        raise SpecError(
            f"input_lsb_v = {lsb:g} V (--input-lsb-v) gives the trained range {vlo:.6g}..{vhi:.6g} V only "
            f"{codes:.3g} ADC codes (need >= {MIN_TRAINED_CODES}): the input LSB is too coarse "
            "for this sensor (volts per code, not the full scale?)")
    return bits, lsb, lsb_given


def check_output_step(model: FlannModel, output_lsb_mm: float, given: str) -> None:
    """An output LSB so coarse that the trained displacement range holds fewer than
    MIN_OUTPUT_CODES output codes is refused, naming where it came from: ``given`` is
    "lsb" (--output-lsb-mm), "bits" (derived from --output-bits) or "" (the default)."""
    xlo, xhi = sorted(model.displacement_range_mm)
    codes = (xhi - xlo) / output_lsb_mm
    if codes >= MIN_OUTPUT_CODES:
        return
    what = (f"output_lsb_mm = {output_lsb_mm:g} mm (--output-lsb-mm)" if given == "lsb" else
            f"the output LSB {output_lsb_mm:g} mm (from --output-bits)" if given == "bits" else
            f"the default output LSB {output_lsb_mm:g} mm")
    fix = ("the output LSB is too coarse for this stroke (mm per code, not the full scale?)"
           if given == "lsb" else "use more --output-bits" if given == "bits"
           else "give a finer --output-lsb-mm")
    raise SpecError(
        f"{what} gives the trained displacement range {xlo:.6g}..{xhi:.6g} mm only {codes:.3g} "
        f"output codes (need >= {MIN_OUTPUT_CODES}): {fix}")


def check_output_range(model: FlannModel, points: int = 2001) -> None:
    """A model whose output over its own voltage range is far outside its displacement range
    is not a compensator (a file edited by hand, or weights that do not cancel as they should)."""
    vlo, vhi = sorted(model.voltage_range_v)
    y = model.predict(np.linspace(vlo, vhi, points))
    xlo, xhi = sorted(model.displacement_range_mm)
    reach = max(abs(xlo), abs(xhi), xhi - xlo)
    if not np.all(np.isfinite(y)) or float(np.max(np.abs(y))) > 100 * reach:
        raise SpecError(
            f"the model's output reaches {float(np.max(np.abs(y))):.3g} mm over its trained voltage range "
            f"{vlo:.6g}..{vhi:.6g} V, but it was trained on {xlo:.6g}..{xhi:.6g} mm: not a usable model "
            "(over-fitted, or edited by hand); retrain it with `flann train`")


def max_mm_per_v(model: FlannModel, points: int = 2001) -> float:
    """Largest |d displacement / d voltage| of the model over its trained range (mm/V)."""
    vlo, vhi = sorted(model.voltage_range_v)
    v = np.linspace(vlo, vhi, points)
    return float(np.max(np.abs(np.gradient(model.predict(v), v))))


def model_accuracy_mm(model: FlannModel) -> float | None:
    """The model's own held-out RMS error (mm) when its training record has one."""
    for key in ("cv_heldout_rms_error_mm", "heldout_rms_error_mm"):
        val = model.training.get(key) if isinstance(model.training, dict) else None
        if isinstance(val, (int, float)) and math.isfinite(val) and val > 0:
            return float(val)
    return None


def default_output_step_mm(model: FlannModel, code_step_mm: float) -> float:
    """What the default output LSB must resolve: a quarter of the output change per input
    code, but no finer than a quarter of the model's own held-out RMS error (bits below the
    model's accuracy only widen the datapath).  Behind a conditioner, whose ratio comes
    averaged over a window, the floor is the output's noise at that rate as training measured
    it instead (``WINDOW_NOISE``): an LSB at the noise rounds off 0.06 bits of its resolution,
    where one at the accuracy would round off bits the conditioner resolves."""
    training = model.training if isinstance(model.training, dict) else {}
    noise = training.get(WINDOW_NOISE)
    if getattr(model, "conditioner", None) is not None and isinstance(noise, (int, float)) \
            and math.isfinite(noise) and noise > 0:
        return max(code_step_mm / 4, float(noise))
    acc = model_accuracy_mm(model)
    return max(code_step_mm, acc if acc is not None else 0.0) / 4


def weight_range_text(model: FlannModel, output_lsb_mm: float) -> str:
    """'sum |w| = ... output LSB, largest |w| ...': the model property that sizes the datapath."""
    w = np.abs(np.asarray(model.weights[1:], dtype=float))
    return (f"the model's sin/cos weights sum to {w.sum():.3g} mm (largest {w.max():.3g} mm, "
            f"{w.sum() / output_lsb_mm:.3g} output LSB of {output_lsb_mm:g} mm)")


def pathological_hint(model: FlannModel, output_lsb_mm: float) -> str:
    """Why a derived width is out of range for this model and what to do, one clause."""
    return (f"{weight_range_text(model, output_lsb_mm)}: nearly collinear terms cancelling each "
            "other; retrain with `flann train` (default auto keeps the weights buildable) or a "
            "larger --ridge, or give a coarser --output-lsb-mm")


__all__ = ["ADC_BITS", "AdcPlan", "plan_adc", "check_converter", "check_output_step", "default_input_lsb",
           "default_lsb_for_range", "default_output_step_mm",
           "max_mm_per_v", "model_accuracy_mm", "wired_codes", "pathological_hint", "weight_range_text",
           "CHAIN_INPUT_BITS", "WINDOW_NOISE", "MAX_DESIGN_INPUT_BITS", "max_input_bits", "top_bits", "MIN_OUTPUT_CODES", "MIN_TRAINED_CODES"]
