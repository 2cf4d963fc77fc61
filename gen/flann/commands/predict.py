"""``flann predict``: apply a model to recordings, write voltage_v, displacement_mm, predicted_mm, clamped.

Outside the trained voltage range the model is not extrapolated: like the hardware (which
clamps the ADC code to the trained range), the voltage is clamped to the nearest end of the
range and the row is flagged (``clamped`` = 1).  ``--extrapolate`` evaluates the expansion
there instead (the trigonometric terms are periodic: the result is rarely meaningful), and the
row is flagged ``extrapolated`` = 1: every row says whether it is a figure of the trained range.
A two-input model's displacement is also held at its calibrated limits (a voltage and a
temperature each inside its range, but a pair the sensor never gave), flagged the same way.

A recording with displacements is read as train reads it (:func:`flann.golden.reading.read_usable`,
one warning line for each thing done): the readings at a rail, beyond a turning point and the
gross outliers are left out, and the rows written are the usable stroke's (``--whole`` writes
every row).  Plain voltages (no displacement) cannot show a fold-back or an outlier; a
reading at a rail or past a turning point lies beyond the voltages the model was trained on
(its rail and fold-back readings were left out of training), so it is clamped, flagged and
counted like every voltage outside that range.
"""

from __future__ import annotations

import csv
import io
import warnings

import numpy as np

from ..fileio import atomic_write_text
from ..golden.reading import usable_or_every
from ..golden.thermal import load_any_model
from ..recordings import read_recordings
from .common import add_common, check_model_inputs, info
from .train import add_reading_flags

HELP = "apply a model to recordings"


def add_arguments(p) -> None:
    p.add_argument("model", help="model.json")
    p.add_argument("recordings", help="CSV with voltage_v (displacement_mm copied when given)")
    p.add_argument("--extrapolate", action="store_true",
                   help="evaluate the model outside its trained voltage range instead of clamping "
                        "to it as the hardware does")
    add_reading_flags(p)
    p.add_argument("--whole", action="store_true",
                   help="with displacements: write every row (rails, fold-back and outliers included); "
                        "default: the rows of the usable stroke train keeps, the rest counted")
    add_common(p, output=dict(help="CSV to write", metavar="OUT.csv", required=True))


def outside_range(model, voltage_v, temperature_c=None) -> np.ndarray:
    return model.clamp(voltage_v, temperature_c)[2]


# A model fitted to a forward curve ends its range at the curve's ends, which the noisiest
# readings at the stroke's ends pass by up to a few sigma: those are the stroke's ends, not
# voltages the model never saw, so they are flagged in the output but not warned about.
NOISE_SIGMAS = 4.0


def _past_the_noise(model, voltage_v, temperature_c, outside: np.ndarray) -> np.ndarray:
    noise = model.training.get("noise_v") if isinstance(model.training, dict) else None
    if not isinstance(noise, (int, float)) or not noise > 0:
        return outside
    v = np.asarray(voltage_v, dtype=float)
    lo, hi = sorted(model.voltage_range_v)
    # a reading outside only through its temperature keeps its flag
    near = (v >= lo - NOISE_SIGMAS * noise) & (v <= hi + NOISE_SIGMAS * noise)
    inside_t = ~outside_range(model, np.clip(v, lo, hi), temperature_c)
    return outside & ~(near & inside_t)


def warn_outside_range(model, voltage_v, source: str, extrapolated: bool = True,
                       temperature_c=None) -> None:
    outside = outside_range(model, voltage_v, temperature_c)
    far = _past_the_noise(model, voltage_v, temperature_c, outside)
    if far.any():
        what = "extrapolated" if extrapolated else "clamped to the range as the hardware does (column clamped = 1)"
        where, items = model.trained_range()
        near = int(outside.sum() - far.sum())
        also = (f" ({near} more past its ends by less than {NOISE_SIGMAS:g}x the training noise)"
                if near else "")
        warnings.warn(f"{source}: {int(far.sum())} of {far.size} {items} outside the "
                      f"model's trained range {where}{also}: {what}", stacklevel=2)


def warn_plain_voltages(model, voltage_v, source: str) -> None:
    """Plain voltages of a sensor whose training left out rails or a fold-back: what can still
    be judged against the trained stroke, one line each (the readings at a rail are counted; a
    reading past a turning point cannot be told from one inside the stroke)."""
    tr = model.training if isinstance(model.training, dict) else {}
    stroke = tr.get("usable_stroke_mm")
    within = (f"the trained stroke {stroke[0]:g}..{stroke[1]:g} mm"
              if isinstance(stroke, list) and len(stroke) == 2 and all(isinstance(e, (int, float)) for e in stroke)
              else "the trained stroke")
    v = np.asarray(voltage_v, dtype=float)
    for rail in tr.get("rails") or ():
        if not isinstance(rail, dict) or not isinstance(rail.get("level_v"), (int, float)):
            continue
        level, side = float(rail["level_v"]), rail.get("side")
        at = v >= level if side == "high" else v <= level
        if at.any():
            warnings.warn(f"{source}: {int(at.sum())} of {v.size} voltages at or past the {side} rail {level:g} V "
                          f"the model's training left out (clipped readings): beyond {within}, clamped and "
                          "flagged (column clamped = 1)", stacklevel=2)
    if tr.get("fold_back"):
        warnings.warn(f"{source}: no displacements: a reading past the turning point the model's training left "
                      f"out reads as one inside {within} and cannot be told apart here (flann eval with "
                      "displacements can)", stacklevel=2)


def predict_clamped(model, voltage_v, temperature_c=None) -> tuple[np.ndarray, np.ndarray]:
    """(displacement mm, clamped flags): the voltage (and a two-input model's temperature)
    clamped to the trained range first."""
    v, t, outside = model.clamp(voltage_v, temperature_c)
    # a (voltage, temperature) pair inside both ranges the sensor never gave: held at the
    # calibrated displacement limits, as the hardware's output is
    x, beyond = model.saturate(model.predict_at(v, t))
    return x, outside | beyond


def run(args) -> int:
    model = load_any_model(args.model)
    rec = read_recordings(args.recordings, required=("voltage_v",), announce=not args.quiet,
                          sensor=args.sensor_id, ab=args.ab)
    check_model_inputs(model, rec, args.model)
    if rec.displacement_mm is not None and not args.whole and model.single_curve:
        # the readings train would use; the rest counted, not predicted
        n = len(rec)
        rec, left = usable_or_every(rec, args.outliers, "every reading predicted")
        if left:
            info(args, f"{rec.source}: predicted {len(rec)} of {n} readings ({left} left out as train "
                       "does, --whole keeps them)")
    elif rec.displacement_mm is None and model.single_curve:
        warn_plain_voltages(model, rec.voltage_v, rec.source)
    temp = rec.temperature_c
    warn_outside_range(model, rec.voltage_v, rec.source, extrapolated=args.extrapolate,
                       temperature_c=temp)
    cols = {name: getattr(rec, name) for name in model.inputs}
    if rec.displacement_mm is not None:
        cols["displacement_mm"] = rec.displacement_mm
    if args.extrapolate:
        cols["predicted_mm"] = model.predict_at(rec.voltage_v, temp)
        flag, flags = "extrapolated", outside_range(model, rec.voltage_v, temp)
    else:
        cols["predicted_mm"], flags = predict_clamped(model, rec.voltage_v, temp)
        flag = "clamped"
        held = flags & ~outside_range(model, rec.voltage_v, temp)
        if held.any():
            lo, hi = model.output_limits_mm()
            warnings.warn(f"{rec.source}: {int(held.sum())} of {held.size} readings inside the calibrated voltages "
                          f"and temperatures give a displacement beyond the calibrated {lo:.6g}..{hi:.6g} mm (a pair "
                          "the sensor never gave): held there as the hardware does (column clamped = 1)")
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow([*cols, flag])
    for i, row in enumerate(zip(*cols.values())):
        w.writerow([f"{c:.9g}" for c in row] + [int(flags[i])])
    atomic_write_text(args.output, out.getvalue())
    return 0
