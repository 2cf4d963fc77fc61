"""``flann train``: fit a FLANN inverse model to recordings and write model.json."""

from __future__ import annotations

import argparse
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..argtypes import bounded, checked, terms_or_auto
from ..errors import FlannError
from ..recordings import converter_of, converter_step, read_recordings
from ..recordings.csvio import AB_FORMS
from ..golden.model import MAX_TERMS
from ..golden.reading import OUTLIER_MODES, read_usable
from ..golden.verdict import exit_code
from ..golden.train import (MAX_EPOCHS, PAPER_TERMS, check_fit_input, cross_validate,
                            fit_lms, fit_lstsq, normalisation_kind)
from ..errors import SpecError
from ..golden.inverse import MIN_POSITIONS, fit_default
from ..hardware.adc import ADC_BITS, WINDOW_NOISE, check_converter
from ..hardware.fixed.cost import fixed_point_cost
from ..hardware.fixed.spec import derive_spec
from .common import add_common, info, on_terminal, quiet
from .train_thermal import compensation_hint, run_thermal, train_verdict
from .train_waveforms import (add_waveform_arguments, converter_of_ratio, is_waveform, read_conditioned,
                              window_noise_mm)

HELP = "train a FLANN inverse model on recordings"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("recordings", help="recordings CSV (displacement_mm, voltage_v, ...), or a waveform "
                   "recording (time_s, sec_a_v, sec_b_v, displacement_mm: through the conditioner)")
    p.add_argument("--terms", type=terms_or_auto(1, MAX_TERMS), default="auto",
                   help="expansion terms N (paper: %s) or 'auto' (default): the forward curve "
                        "v(x) fitted where the noise is, inverted, and the FLANN (terms, "
                        "normalisation, ridge) fitted to that inverse at the converter; the "
                        "cross-validated direct fit of x(v) when the FLANN cannot follow it"
                        % ", ".join(map(str, PAPER_TERMS)))
    p.add_argument("--method", choices=("lstsq", "lms"), default="lstsq",
                   help="closed-form least squares (default) or the paper's LMS")
    p.add_argument("--eta", type=bounded(float, 0, lo_open=True), default=0.01,
                   help="LMS learning rate (default 0.01)")
    p.add_argument("--epochs", type=bounded(int, 1, MAX_EPOCHS), default=1000,
                   help=f"LMS epochs (default 1000, at most {MAX_EPOCHS})")
    p.add_argument("--ridge", type=bounded(float, 0, 1e6), default=0.0,
                   help="lstsq ridge penalty on mean squared error (default 0)")
    p.add_argument("--normalise", type=checked(normalisation_kind), default=None,
                   help="input normalisation for explicit --terms: 'range' (default: the "
                        "data's voltage range -> [-1, 1]), 'half' (-> [-0.5, 0.5]), a number "
                        "f in (0, 1] (-> [-f, f]) or 'none' (raw volts, as the paper)")
    p.add_argument("--input-offset-v", type=bounded(float, -1e6, 1e6), default=None,
                   help="explicit normalisation offset (V); needs --input-scale-v")
    p.add_argument("--input-scale-v", type=bounded(float, -1e6, 1e6, nonzero_abs=1e-9), default=None,
                   help="explicit normalisation scale (V); needs --input-offset-v")
    p.add_argument("--trim", action="store_true",
                   help="keep only the monotonic span when the voltage folds back (the default: the "
                        "usable stroke kept is said)")
    add_reading_flags(p)
    p.add_argument("--strict", action="store_true",
                   help="exit 1 when the verdict is bad (compensated worse than the straight line)")
    p.add_argument("--temperature", action="store_true",
                   help="a two-input model x(voltage, temperature) from a calibration at several "
                        "temperatures (the temperature_c column; docs/temperature.md); --terms N sets "
                        "each temperature order's expansion (the hardware's size)")
    p.add_argument("--input-bits", type=bounded(int, *ADC_BITS), default=None,
                   help="--terms auto: the converter the model will be generated for (signed code "
                        "width); default: read from the recording's converter grid")
    p.add_argument("--input-lsb-v", type=bounded(float, 0, lo_open=True), default=None,
                   help="--terms auto: volts per code of that converter (default: the grid's step, "
                        "or flann gen's default for --input-bits)")
    add_waveform_arguments(p)
    add_common(p, output=dict(help="model.json to write", metavar="MODEL.json", required=True))


def add_reading_flags(p, outliers: bool = True) -> None:
    """The flags of how a recording is read, the same in train, eval and diagnose."""
    p.add_argument("--sensor-id", "--sensor", dest="sensor_id", metavar="ID", default=None,
                   help="the sensor of that ID in the file's sensor column (a file of several sensors)")
    p.add_argument("--ab", choices=AB_FORMS, default="ratio",
                   help="two secondary amplitude columns A, B as voltage_v: (A-B)/(A+B) (ratio, the "
                        "default) or A-B (difference)")
    if outliers:
        p.add_argument("--outliers", choices=OUTLIER_MODES, default=None,
                       help="gross outliers: drop (leave out, however many), keep (fit every reading), "
                            "refuse; default: left out unless more than 20 %% of the readings")


def converter(args, rec) -> dict | None:
    """The converter buildability is judged at: the user's (--input-bits/--input-lsb-v), else
    the recording's grid (every reading a whole number of one step), else None (the generator's
    default and widest converter, 12 and 16 bits)."""
    if args.input_bits is not None:
        return {"input_bits": args.input_bits, "input_lsb_v": args.input_lsb_v, "from": "--input-bits"}
    if args.input_lsb_v is not None:
        raise FlannError("--input-lsb-v needs --input-bits")
    grid = converter_of(rec.voltage_v)
    if grid is None:
        return None
    return {"input_bits": grid[0], "input_lsb_v": float(f"{grid[1]:.9g}"),
            "from": "the recording's converter grid"}


def _heldout(rec, terms, norm, ridge, explicit) -> tuple[str, float | None]:
    """('; held-out ...', its max error) from the same cross-validation as auto (printed, not
    stored); ('', None) where it cannot be made."""
    if explicit is not None or len(rec) < 4:
        return "", None
    (res,) = cross_validate(rec.voltage_v, rec.displacement_mm, (terms,), (norm,), (ridge,))
    return (f"; held-out (cross-validation): RMS {res.rms_mm:.4g} mm, "
            f"max {res.max_mm:.4g} mm"), float(res.max_mm)


def _check_generatable(model) -> None:
    """A model `flann gen` would refuse at its defaults is not written: it could only mislead."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            derive_spec(model)
    except SpecError as exc:
        raise FlannError(f"the fitted model cannot be generated as hardware ({exc}); nothing written: "
                         "use fewer --terms, a --ridge, or --terms auto (the default)") from None


def _stager(args):
    """What --terms auto is doing, on a terminal only (a logger's file takes it a minute)."""
    def stage(text: str) -> None:
        if on_terminal(args):
            print(f"train: {text}", file=sys.stderr, flush=True)

    return stage


class _Verdict(str):
    """A line of the fit's summary that judges the model: said under --quiet too."""


def _train_auto(args, rec, provenance: dict, settings=None) -> tuple:
    """(model, lines to print) of --terms auto: the FLANN fitted to the inverse of the forward
    curve (:mod:`flann.golden.inverse`), or the direct fit's cross-validated choice."""
    said = []
    _stage = _stager(args)
    check_fit_input(rec.voltage_v, rec.displacement_mm, 1, rec.source)
    positions = int(np.unique(rec.displacement_mm).size)
    if positions < MIN_POSITIONS:
        # four: two folds each hold out one interior position, near the null, where a line shrunk
        # by the ridge is still right: 0.026 mm held out for a model 1.6 mm off at the ends
        raise FlannError(f"{rec.source}: {positions} distinct positions are too few for --terms auto "
                         f"(the spline through them and its check by leaving each out need at least "
                         f"{MIN_POSITIONS}): give --terms 1 (a line) or --terms 2")
    # the readings the shared reading kept (a glitch is on no converter's grid)
    _stage(f"{len(rec)} readings at {positions} positions kept by the screen (rails, fold-back, gross outliers)")
    conv = converter(args, rec) if settings is None else converter_of_ratio(settings)
    # readings on a converter's grid differ by whole steps: the noise is at least its quantisation
    step_v = converter_step(rec.voltage_v)
    if args.input_bits is not None:
        # the user's converter, by gen's own rule, before any fit: one it cannot carry would
        # otherwise surface as "no candidate builds" or a derived width out of range
        check_converter((float(rec.voltage_v.min()), float(rec.voltage_v.max())),
                        conv["input_bits"], conv["input_lsb_v"])
    if conv is not None:
        provenance["converter"] = conv
    adc = None if conv is None else (conv["input_bits"], conv["input_lsb_v"])

    def cost(m):
        return fixed_point_cost(m, adc)

    model, choice, from_curve = fit_default(rec.displacement_mm, rec.voltage_v, cost, provenance, step_v,
                                            stage=_stage)
    t = model.training
    direct_text = (f"held-out error (cross-validation, {t['cv_folds']} folds"
                   + (f", chosen on {t['cv_points']} of {len(rec)} points" if "cv_points" in t else "")
                   + f"): RMS {choice.rms_mm:.4g} mm, max {choice.max_mm:.4g} mm")
    if not from_curve:
        said.append(f"auto: {choice.terms} terms, normalisation {choice.norm}, ridge {choice.ridge:g}; "
                    + direct_text)
    else:
        loo, own = t.get("leave_one_out"), t["forward_model"].get("heldout")
        if loo:
            heldout = (f"left-out positions RMS {loo['rms_error_mm']:.4g} mm (direct fit "
                       f"{loo['direct_rms_error_mm']:.4g} mm)")
        else:
            heldout = f"the direct fit x(v)'s {direct_text}"
            if own:
                heldout = (f"the curve's held-out error (the same {own['folds']} folds): RMS "
                           f"{own['rms_error_mm']:.4g} mm, max {own['max_error_mm']:.4g} mm; " + heldout)
        said.append(f"auto: {t['selected_by']}; {model.terms} terms, normalisation {t['normalisation']}, "
                    f"ridge {t['ridge']:g}, within {t['teacher_max_deviation_mm']:.3g} mm of the curve's "
                    f"inverse; {heldout}")
        odd = t["forward_model"].get("odd_about_null")
        if odd and odd["weight"] >= 0.5:
            said.append(f"auto: the curve is odd about a null at {odd['null_mm']:.4g} mm, its slope "
                        f"above the null {odd['slope_above_over_below']:.4g}x that below (weight "
                        f"{odd['weight']:.2f} of the average)")
    if conv is not None:
        said.append(f"auto: judged buildable at a {conv['input_bits']}-bit"
                    + (f" x {conv['input_lsb_v']:.6g} V" if conv["input_lsb_v"] is not None else "")
                    + f" converter ({conv['from']}); positions used {t.get('positions_used')}")
    if "traded" in t:
        said.append(f"auto: {t['selected_by']}: {t['traded']}")
    elif "hardware_why" in t:
        said.append(_Verdict(f"auto: no candidate builds in fixed point ({t['hardware_why']})"))
    return model, said, choice.max_mm


def run(args) -> int:
    settings = dwells = None
    if is_waveform(args):
        dwells, settings, conditioned = read_conditioned(args)
        rec = dwells.recordings
    else:
        rec = read_recordings(args.recordings, announce=not args.quiet, sensor=args.sensor_id, ab=args.ab)
    if args.temperature:
        return run_thermal(args, rec, settings)
    hint = compensation_hint(rec)
    if hint:   # before the checks: a multi-temperature recording may not pass them as one
        info(args, hint)
    reading = read_usable(rec, args.outliers)
    for line in reading.said:
        warnings.warn(line)
    rec = reading.rec
    explicit = None
    if (args.input_offset_v is None) != (args.input_scale_v is None):
        raise FlannError("--input-offset-v and --input-scale-v must be given together")
    if args.input_scale_v is not None:
        if args.input_scale_v == 0:
            raise FlannError("--input-scale-v must not be 0")
        if args.normalise is not None:
            raise FlannError("give either --normalise or --input-offset-v/--input-scale-v")
        explicit = (args.input_offset_v, args.input_scale_v)
    provenance = {"data_file": Path(args.recordings).name,
                  "data_sha256": rec.sha256}
    if rec.comments:
        provenance["data_provenance"] = rec.comments[0]
    if rec.sensor_id:
        provenance["sensor_id"] = rec.sensor_id
    provenance.update(reading.record)
    said = []   # printed once the model is known to be writable
    heldout_max = None
    if args.terms == "auto":
        if args.method != "lstsq" or explicit is not None or args.normalise or args.ridge:
            raise FlannError("--terms auto chooses normalisation and ridge itself (lstsq); "
                             "give --terms N to set --method/--normalise/--ridge")
        model, said, heldout_max = _train_auto(args, rec, provenance, settings)
    else:
        if args.input_bits is not None or args.input_lsb_v is not None:
            raise FlannError("--input-bits/--input-lsb-v choose among --terms auto's candidates; "
                             "with --terms N give them to flann gen")
        norm = args.normalise or "range"
        check_fit_input(rec.voltage_v, rec.displacement_mm, args.terms, rec.source)
        if args.method == "lms":
            model = fit_lms(rec.voltage_v, rec.displacement_mm, args.terms, eta=args.eta,
                            epochs=args.epochs, norm=norm, offset_scale=explicit,
                            training=provenance)
            said.append(f"lms: {args.terms} terms, eta {args.eta:g}, {args.epochs} epochs, final "
                        f"epoch MSE {model.training['mse_per_epoch'][-1]:.4g} mm^2 (training error)")
        else:
            model = fit_lstsq(rec.voltage_v, rec.displacement_mm, args.terms, norm=norm,
                              offset_scale=explicit, ridge=args.ridge, training=provenance)
            heldout, heldout_max = _heldout(rec, args.terms, norm, args.ridge, explicit)
            said.append(f"lstsq: {args.terms} terms, ridge {args.ridge:g}, training RMS error "
                        f"{model.training['train_rms_error_mm']:.4g} mm (not a held-out figure)" + heldout)
    if settings is not None:
        model = replace(model, conditioner=settings.to_dict())
        # the words flann gen sizes by default carry the resolution, not only the accuracy
        noise = window_noise_mm(model, dwells, conditioned)
        if noise is not None:
            model.training[WINDOW_NOISE] = noise
    _check_generatable(model)
    verdict = train_verdict(model, rec, heldout_max)
    model.training["verdict"] = verdict.to_json()
    model.save(args.output)   # first: the summary's reader (`| head`) may be gone
    for line in said:
        if isinstance(line, _Verdict) or not quiet(args):
            print(line, file=sys.stderr)
    if args.terms != "auto":
        hw = fixed_point_cost(model)
        if not hw["buildable"]:
            warnings.warn(f"this model cannot be built in fixed point ({hw['why']}); "
                          "--terms auto selects a buildable one")
    lo, hi = reading.stroke_mm
    print(f"{verdict.line()}; usable stroke {lo:g}..{hi:g} mm", file=sys.stderr)
    return exit_code(verdict, args.strict)
