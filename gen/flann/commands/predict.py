"""``flann predict``: apply a model to recordings, write voltage_v, displacement_mm, predicted_mm."""

from __future__ import annotations

import csv
import io
import warnings

from ..fileio import atomic_write_text
from ..golden.model import load_model
from ..recordings import read_recordings

HELP = "apply a model to recordings"


def add_arguments(p) -> None:
    p.add_argument("model", help="model.json")
    p.add_argument("recordings", help="CSV with voltage_v (displacement_mm copied when given)")
    p.add_argument("-o", "--output", required=True, help="CSV to write")


def warn_outside_range(model, voltage_v, source: str) -> None:
    lo, hi = model.voltage_range_v
    outside = (voltage_v < lo) | (voltage_v > hi)
    if outside.any():
        warnings.warn(f"{source}: {int(outside.sum())} of {voltage_v.size} voltages outside the "
                      f"model's trained range [{lo:g}, {hi:g}] V: extrapolated", stacklevel=2)


def run(args) -> int:
    model = load_model(args.model)
    rec = read_recordings(args.recordings, required=("voltage_v",))
    warn_outside_range(model, rec.voltage_v, rec.source)
    cols = {"voltage_v": rec.voltage_v}
    if rec.displacement_mm is not None:
        cols["displacement_mm"] = rec.displacement_mm
    cols["predicted_mm"] = model.predict(rec.voltage_v)
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(list(cols))
    for row in zip(*cols.values()):
        w.writerow([f"{c:.9g}" for c in row])
    atomic_write_text(args.output, out.getvalue())
    return 0
