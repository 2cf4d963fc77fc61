"""``flann train --temperature``: the two-input model x(v, T) (called by :mod:`.train`)."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import FlannError
from ..golden.thermal_train import MIN_TEMPERATURES, compensable, fit_thermal_auto
from ..golden.metrics import raw_output_mm
from ..golden.thermal import temperature_groups
from ..golden.verdict import against_line, combine, exit_code
from ..recordings import MIN_FIT_POINTS, prepare_for_fit
from ..recordings.checks import TEMPERATURE_RESOLUTION_C
from .common import info


def compensation_hint(rec) -> str | None:
    """One line when a recording spans 3 or more temperatures (and no --temperature)."""
    temps = compensable(rec.temperature_c)
    if len(temps) < 3:
        return None
    return (f"note: {rec.source} holds a calibration at {len(temps)} temperatures "
            f"({', '.join(f'{t:g}' for t in temps)} degC): it could be compensated for "
            "temperature with flann train --temperature")


def _prepare(rec, trim: bool):
    """The fit's checks (span, duplicates, fold-back) at each temperature on its own."""
    levels, labels = temperature_groups(rec.temperature_c)
    counts = np.bincount(labels, minlength=levels.size)
    few = np.flatnonzero(counts < MIN_FIT_POINTS)
    if few.size:
        g = int(few[0])
        raise FlannError(
            f"{rec.source}: {few.size} of {levels.size} temperatures (to {TEMPERATURE_RESOLUTION_C:g} degC) hold "
            f"fewer than {MIN_FIT_POINTS} readings, e.g. {int(counts[g])} at {levels[g]:g} degC of {len(rec)} rows: "
            "a calibration at several temperatures holds a sweep at each; a temperature that changes on "
            "every row is a drift, not a calibration (round the temperature_c column to the soak's setting)")
    parts = [prepare_for_fit(rec.subset(labels == g), trim=trim) for g in range(levels.size)]
    cat = np.concatenate
    return (cat([p.voltage_v for p in parts]), cat([p.temperature_c for p in parts]),
            cat([p.displacement_mm for p in parts]))


def train_verdict(model, rec, heldout_max_mm: float | None):
    """The model's error against the straight line through the same readings (a two-input
    model's: through every temperature's, as an uncompensated sensor reads them): held out when
    cross-validated (a model that only follows its training points is judged as it generalises),
    else at the training readings."""
    line = float(np.max(np.abs(raw_output_mm(rec.voltage_v, rec.displacement_mm) - rec.displacement_mm)))
    if heldout_max_mm is not None:
        return combine(against_line(heldout_max_mm, line, "held-out max error"))
    own = float(np.max(np.abs(model.predict_at(rec.voltage_v, rec.temperature_c) - rec.displacement_mm)))
    return combine(against_line(own, line, "max error"))


def run_thermal(args, rec, settings=None) -> int:
    """The two-input model of ``rec``; ``settings``: the conditioner whose ratio ``rec`` holds
    (a waveform recording's dwells), kept in the model."""
    if args.method != "lstsq" or args.ridge or args.normalise \
            or args.input_scale_v is not None or args.input_offset_v is not None:
        raise FlannError("--temperature chooses normalisation and ridge by cross-validation (and the terms, "
                         "unless --terms N sets them per temperature order): give none of "
                         "--method/--ridge/--normalise/--input-*")
    if rec.temperature_c is None:
        raise FlannError(f"{rec.source}: --temperature needs a temperature_c column")
    if len(compensable(rec.temperature_c)) < MIN_TEMPERATURES:
        raise FlannError(f"{rec.source}: --temperature needs a calibration at {MIN_TEMPERATURES} or "
                         "more temperatures (4 or more rows each)")
    v, t, x = _prepare(rec, args.trim)
    provenance = {"data_file": Path(args.recordings).name, "data_sha256": rec.sha256}
    if rec.comments:
        provenance["data_provenance"] = rec.comments[0]
    terms = None if args.terms == "auto" else (int(args.terms),)   # the hardware's size, when it must fit a part
    model, choice = fit_thermal_auto(v, t, x, training=provenance, source=rec.source, terms=terms)
    if settings is not None:
        model = replace(model, conditioner=settings.to_dict())
    verdict = train_verdict(model, rec, choice.max_mm)
    model.training["verdict"] = verdict.to_json()
    model.save(args.output)
    tr = model.training
    info(args, f"temperature: terms per temperature order {list(model.terms)} ({model.coefficients} "
               f"coefficients; the smallest weights of {tr['as_good_candidates']} as good), "
               f"normalisation {choice.norm}, "
               f"ridge {choice.ridge:g}; held-out error (cross-validation over "
               f"{tr['cv_position_folds']} position folds and {tr['cv_temperature_folds']} held-out "
               f"temperatures): RMS {choice.rms_mm:.4g} mm, max {choice.max_mm:.4g} mm")
    print(verdict.line(), file=sys.stderr)
    return exit_code(verdict, args.strict)
