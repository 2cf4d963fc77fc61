"""What a model costs in fixed point at the generator's defaults, and whether it builds:
asked by training (``--terms auto``), the family's term choice and the production line.
Kept apart from :mod:`flann.hardware.accuracy` (which reads designs through the registry) so
the datapaths can ask it without an import cycle."""

from __future__ import annotations

import math
import warnings

from ...errors import SpecError
from ...golden.model import FlannModel
from ..adc import MAX_DESIGN_INPUT_BITS
from ..options import default
from .spec import derive_spec

COST_BITS = (MAX_DESIGN_INPUT_BITS, default("input_bits"))   # a model must build at the default and the widest ADC
MAX_BOUND_LSB = 1.0   # worst-case |hardware - float model| at the default widths, output LSB


def fixed_point_cost(model: FlannModel, adc: tuple[int, float | None] | None = None) -> dict:
    """Cost of the model in fixed point at the generator's defaults, and whether it builds.

    ``cost`` is the estimated LUT4 count + the weight ROM in LUT4 equivalents (16 bits each)
    + 64 per block RAM: it grows with the weights' dynamic range (weight and term widths)
    and with the number of terms.  ``buildable`` is False when ``flann gen`` would refuse the
    model at 16 or at 12 input bits, or when the widths it allows cannot hold the hardware
    within one output LSB of the float model (capped table or term widths: the model's
    accuracy would be lost in the datapath); the reason is in ``why``.  ``adc`` = (bits, volts
    per code or None for the default): judged at that converter only (the user's).
    """
    spec = None
    for bits, lsb in ([adc] if adc is not None else [(b, None) for b in COST_BITS]):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                spec = derive_spec(model, input_bits=bits, input_lsb_v=lsb)
        except SpecError as exc:
            return {"buildable": False, "why": f"{bits}-bit input: {exc}", "cost": math.inf}
        if spec.analysis["bound_total_lsb"] > MAX_BOUND_LSB:
            return {"buildable": False, "cost": math.inf,
                    "why": f"{bits}-bit input: the default widths bound |hardware - float model| by "
                           f"{spec.analysis['bound_total_lsb']:.3g} output LSB (> {MAX_BOUND_LSB:g})"}
    est = spec.analysis["estimate"]
    rom_luts = math.ceil(spec.steps * spec.weight_fmt.width / 16)
    return {"buildable": True, "why": "",
            "cost": float(est["luts"] + rom_luts + 64 * est["brams"]), "luts": est["luts"],
            "brams": est["brams"], "weight_bits": spec.weight_fmt.width,
            "term_bits": spec.term_fmt.width, "phase_bits": spec.phase_bits,
            "output_lsb_mm": spec.output_lsb_mm, "cycles_per_sample": spec.cycles_per_sample}


__all__ = ["COST_BITS", "MAX_BOUND_LSB", "fixed_point_cost"]
