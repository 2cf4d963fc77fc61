"""``flann eval``: accuracy of a model on recordings (compensated vs the raw sensor).

``--design DIR`` adds the generated design's accuracy: its bit-true twin on the recordings'
voltages quantised to the design's ADC codes, against the physical limit of that converter.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..analysis.conditioner_figures import AD598_LINEARITY_PCT_FS, chain_figures, hardware_bits, plot_chain
from ..argtypes import png_path
from ..golden.metrics import (DEFAULT_BAND_PCT_FS, DEFAULT_TOL_PCT_FS, error_report, full_scale_mm,
                       raw_output_mm)
from ..errors import FlannError
from ..golden.thermal import load_any_model
from ..golden.thermal_metrics import temperature_report
from ..hardware.accuracy import adc_codes, design_adc, design_spec, hardware_accuracy, plot_errors, temperature_codes
from ..hardware.datapath import check_design_model
from ..hardware.design import open_directory
from ..hardware.conditioner.chain import window_temperatures
from ..hardware.conditioner.verify import flann_design
from ..hardware.fixed.twin import FlannTop
from ..hardware.thermal.twin import FlannThermalTop
from ..golden.reading import usable_or_every
from ..golden.verdict import Check, against_line, combine, exit_code, hardware_against_float
from ..recordings import read_recordings
from .common import add_common, check_model_inputs, emit_json
from .train import add_reading_flags
from .train_waveforms import is_waveform, read_held_out
from .predict import predict_clamped, warn_outside_range

HELP = "accuracy of a model on recordings"
# (figure name of drift_ppm_fs_per_c, the JSON section whose by_temperature it is)
SECTIONS = (("raw", "raw"), ("float", "compensated"), ("hardware", "hardware"))


def add_arguments(p) -> None:
    p.add_argument("model", help="model.json")
    p.add_argument("recordings", help="recordings CSV with displacement_mm and voltage_v, or a waveform recording "
                                      "held out from a model trained from waveforms (linearity_pct_fs)")
    p.add_argument("--tol", type=float, default=DEFAULT_TOL_PCT_FS, metavar="PCT_FS",
                   help="linearity tolerance in %% of full scale (default %(default)g)")
    p.add_argument("--band", type=float, default=DEFAULT_BAND_PCT_FS, metavar="PCT_FS",
                   help="stroke-fraction band in %% of full scale (default %(default)g)")
    p.add_argument("--full-scale-mm", type=float, default=None,
                   help="full scale (mm); default half the recordings' displacement span")
    p.add_argument("--design", metavar="DIR", default=None,
                   help="also the accuracy of the design `flann gen MODEL -o DIR` wrote: its bit-true "
                        "twin on the voltages as ADC codes, and the physical limit (half an ADC LSB "
                        "over the local slope); with waveforms, the conditioner's ratio codes into the "
                        "FLANN's twin (linearity_pct_fs.hardware)")
    p.add_argument("--plot", metavar="OUT.png", default=None, type=png_path,
                   help="error vs displacement: raw sensor, float model, hardware (needs --design) "
                        "and the physical limit; for a waveform recording: the waveforms, the demodulated "
                        "ratio and the displacement error (the hardware's with --design)")
    add_reading_flags(p)
    p.add_argument("--whole", action="store_true",
                   help="figures over every reading (rails, fold-back and outliers included); default: "
                        "over the usable stroke the shared reading keeps, the rest counted")
    p.add_argument("--strict", action="store_true",
                   help="exit 1 when the verdict is bad (compensated worse than the straight line, or the "
                        "hardware loses the float model's accuracy)")
    add_common(p, json="the figures")


def eval_verdict(res: dict, figures=()):
    """Against the straight line through the same readings; with a design, the hardware against
    the float model (max error, and the drift of a two-input model); a waveform recording's
    data-sheet figures each against its reference."""
    checks = [against_line(res["compensated"]["max_error_mm"], res["raw"]["max_error_mm"])]
    checks += [f.check() for f in figures]
    lin = res.get("linearity_pct_fs")
    for chain in ("float", "hardware") if lin else ():
        if lin[chain] is None:
            continue
        ok = lin[chain] <= lin["reference_pct_fs"]
        what = ("the conditioner's twin and the float FLANN" if chain == "float" else
                "the conditioner's twin and the FLANN's, as the design computes; its output LSB "
                f"{lin['hardware_lsb_pct_fs']:.4f} % FS")
        checks.append(Check(f"linearity_vs_ad598_{chain}", ok,
                            f"linearity {lin[chain]:.4f} % FS ({what}, per dwell) "
                            f"{'within' if ok else 'beyond'} the {lin['reference']} of {lin['reference_pct_fs']:g} % FS",
                            "" if ok else "more positions or a longer dwell in the training waveforms, "
                                          "or --terms auto (the default)"
                            + ("" if chain == "float" else "; a finer --output-lsb-mm")))
    hw = res.get("hardware")
    if hw:
        checks.append(hardware_against_float(hw["max_error_mm"], res["compensated"]["max_error_mm"]))
    # a two-input design's drift, a chain's as a demodulated design's
    drift = res.get("drift_ppm_fs_per_c") or {}
    if drift.get("hardware") is not None and drift.get("float") is not None:
        checks.append(hardware_against_float(drift["hardware"], drift["float"], "drift", "ppm FS/degC",
                                             "generate with more --input-bits and --temp-bits (flann gen "
                                             "warns with the widths that keep it), or a finer --output-lsb-mm"))
    return combine(*checks)


def conditioned_flann(model, design_dir):
    """The FLANN design behind the conditioner in ``design_dir`` (flann gen of ``model``), with its
    twin; one line when the directory holds none or was generated from another model."""
    design = open_directory(design_dir)
    check_design_model(model, design.manifest, design_dir)
    flann = flann_design(design.with_twin())
    if flann is None:
        raise FlannError(f"{design_dir}: holds no FLANN behind a conditioner (flann gen {model} -o DIR writes one)")
    return flann


def chain_window_mm(flann, settings, conditioned, wave) -> np.ndarray:
    """The design's output of each window: its ratio code into the FLANN's twin (its top input
    bits, as wired; a two-input FLANN's with the temperature code at the window's last sample,
    as the chain holds it), in mm."""
    spec = flann.spec
    codes = adc_codes(spec, conditioned.ratio, settings.ratio_converter)
    if not getattr(spec, "temp_bits", None):
        return FlannTop(spec).process(codes).out_data * spec.output_lsb_mm
    temps = window_temperatures(temperature_codes(spec, wave.temperature_c), settings.spec.window, codes.size)
    return FlannThermalTop(spec).process(codes, temps).out_data * spec.output_lsb_mm


def chain_outputs_mm(out, dwells, rec) -> np.ndarray:
    """The design's output per reading of ``rec``: its windows' outputs ``out`` averaged over
    the dwell as the float chain's ratio is."""
    full = dwells.recordings
    per = {(float(x), float(v)): float(np.mean(out[g]))
           for x, v, g in zip(full.displacement_mm, full.voltage_v, dwells.groups)}
    # the readings the shared reading kept: the dwells by their (position, ratio)
    return np.array([per[(float(x), float(v))] for x, v in zip(rec.displacement_mm, rec.voltage_v)])


def linearity(res: dict) -> dict:
    """The chain's linearity in a data sheet's terms: the largest deviation of the compensated
    output from the true displacement, % of full scale, against the AD598's limit."""
    return {"float": res["compensated"]["max_error_pct_fs"], "hardware": None,
            "reference_pct_fs": AD598_LINEARITY_PCT_FS, "reference": "AD598's linearity (max)"}


def evaluate(model, rec, tol=DEFAULT_TOL_PCT_FS, band=DEFAULT_BAND_PCT_FS, fs_mm=None) -> dict:
    """Metrics of the compensated output and of the raw sensor (its least-squares line)."""
    if not (tol >= 0 and band >= 0):
        raise FlannError("--tol and --band must be >= 0 (% of full scale)")
    if fs_mm is not None and not fs_mm > 0:
        raise FlannError(f"--full-scale-mm must be > 0, got {fs_mm:g}")
    if len(rec) < 2:
        raise FlannError(f"{rec.source}: need at least 2 rows to evaluate, got {len(rec)}")
    fs = full_scale_mm(rec.displacement_mm, rec.source) if fs_mm is None else float(fs_mm)
    x = rec.displacement_mm
    # outside the trained range the voltage is clamped, as the hardware does
    predicted = predict_clamped(model, rec.voltage_v, rec.temperature_c)[0]
    compensated = error_report(predicted, x, tol, band, fs, rec.direction)
    raw_mm = raw_output_mm(rec.voltage_v, x)
    raw = error_report(raw_mm, x, tol, band, fs, rec.direction)
    res = {"points": len(rec), "full_scale_mm": fs, "tolerance_pct_fs": tol,
           "band_pct_fs": band, "compensated": compensated, "raw": raw}
    if rec.temperature_c is not None:
        res["_errors"] = {"raw": raw_mm - x, "float": predicted - x}
    return res


def warn_outside_stroke(model, rec) -> None:
    """Positions beyond the trained displacement range are said: the model has never seen them,
    so its error there (and in the figures) is the extrapolation's, not the compensation's."""
    lo, hi = sorted(model.displacement_range_mm)
    tol = 1e-9 * max(abs(lo), abs(hi), hi - lo, 1.0)   # a range's end printed and read back
    x = np.asarray(rec.displacement_mm, dtype=float)
    n = int(np.count_nonzero((x < lo - tol) | (x > hi + tol)))
    if n:
        warnings.warn(f"{rec.source}: {n} of {x.size} points lie outside the model's trained "
                      f"displacement range [{lo:g}, {hi:g}] mm: the model was not fitted there, "
                      "the figures include them", stacklevel=2)


def hardware_vs_float(hw: dict) -> str:
    """Both |hardware - float| figures, each saying what it includes: at the readings (the ADC's
    quantisation of the voltages too) and at their ADC codes (the datapath alone, what flann sim
    measures over every code)."""
    return (f"|hardware - float| <= {hw['max_abs_hardware_minus_float_mm']:.4g} mm at the readings "
            f"(ADC quantisation included), {hw['max_abs_hardware_minus_float_at_codes_mm']:.4g} mm at the "
            "readings' ADC codes")


def run(args) -> int:
    waveform = is_waveform(args)
    if args.plot and not args.design and not waveform:
        raise FlannError("--plot draws the hardware's error too: give --design DIR")
    model = load_any_model(args.model)
    settings = None
    if waveform:
        dwells, settings, conditioned, wave = read_held_out(args, model)
        rec = dwells.recordings
    elif getattr(model, "conditioner", None) is not None:
        raise FlannError(f"{args.recordings}: demodulated readings, but {args.model} was trained from waveforms "
                         "(its input is the conditioner's ratio): evaluate it on a waveform recording")
    else:
        rec = read_recordings(args.recordings, announce=not args.quiet, sensor=args.sensor_id, ab=args.ab)
    check_model_inputs(model, rec, args.model)
    outside = None
    if not args.whole and model.single_curve:
        # the same reading train made: figures over the usable stroke, the rest counted
        rec, outside = usable_or_every(rec, args.outliers, "the figures are over every reading")
    # a design eval cannot judge is refused before any warning about the recording
    chain = conditioned_flann(args.model, args.design) if args.design and settings is not None else None
    spec = design_spec(args.model, args.design) if args.design and chain is None else None
    warn_outside_range(model, rec.voltage_v, rec.source, extrapolated=False,
                       temperature_c=rec.temperature_c)
    warn_outside_stroke(model, rec)
    res = evaluate(model, rec, args.tol, args.band, args.full_scale_mm)
    errors = res.pop("_errors", None)
    if chain is not None:
        window_mm = chain_window_mm(chain, settings, conditioned, wave)
        hardware_mm = chain_outputs_mm(window_mm, dwells, rec)
        if errors is not None:
            errors["hardware"] = hardware_mm - rec.displacement_mm
    elif args.design:
        hw = hardware_accuracy(spec, rec, tol=args.tol, band=args.band, fs_mm=res["full_scale_mm"],
                               adc=design_adc(args.design))
        pts = hw.pop("_points")
        res["hardware"] = hw
        if errors is not None:
            errors["hardware"] = pts["hardware"]
        if args.plot:
            raw = raw_output_mm(rec.voltage_v, rec.displacement_mm) - rec.displacement_mm
            plot_errors(args.plot, pts["x"], raw, pts["float"], pts["hardware"], pts["limit"],
                        title=f"{rec.source}: error vs displacement ({hw['input_bits']}-bit ADC, "
                              + (f"{hw['output_lsb_mm']:g} mm output LSB)" if hw.get("output_lsb_mm")
                                 else f"{hw.get('number_format', 'float18')} output)"))
    if errors is not None:
        errors.setdefault("hardware", None)
        report = temperature_report(errors, rec.displacement_mm, rec.temperature_c, res["full_scale_mm"])
        # by_temperature lives in each figure's own section (raw; compensated = the float model;
        # hardware), drift_ppm_fs_per_c once, keyed by figure (raw, float, hardware)
        for name, section in SECTIONS:
            if report["by_temperature"][name] is not None and section in res:
                res[section]["by_temperature"] = report["by_temperature"][name]
        res["drift_ppm_fs_per_c"] = report["drift_ppm_fs_per_c"]
    if outside is not None:
        res["readings_left_out"] = outside
    figures = ()
    if settings is not None:
        res["linearity_pct_fs"] = linearity(res)
        if chain is not None:
            res["linearity_pct_fs"]["hardware"] = float(100 * np.max(np.abs(hardware_mm - rec.displacement_mm))
                                                        / res["full_scale_mm"])
            # a dwell whose codes do not toggle is exact to within half of it: the figure's resolution
            res["linearity_pct_fs"]["hardware_lsb_pct_fs"] = 100 * chain.spec.output_lsb_mm / res["full_scale_mm"]
        # a two-input model at each dwell's or window's temperature, else the recording's (median);
        # a one-input model takes none
        median = None if rec.temperature_c is None else float(np.median(rec.temperature_c))

        def to_mm(ratio, temperature_c=None):
            return predict_clamped(model, ratio, median if temperature_c is None else temperature_c)[0]

        figures = chain_figures(settings, wave, dwells, to_mm, res["full_scale_mm"])
        for f in figures:
            res[f.name] = f.to_json()
        if chain is not None:
            # the figures are the conditioner's (the FLANN in float); the design's output word
            # holds log2(span / LSB) bits of them
            res["effective_bits"]["hardware_output_bits"] = math.log2(2 * res["full_scale_mm"]
                                                                      / chain.spec.output_lsb_mm)
            res["effective_bits"]["hardware_bits"] = hardware_bits(window_mm, dwells.groups, 2 * res["full_scale_mm"],
                                                                   chain.spec.output_lsb_mm)
        if args.plot:
            plot_chain(args.plot, settings, wave, conditioned, dwells, to_mm, res["full_scale_mm"],
                       hardware_mm if chain is not None else None)
    verdict = eval_verdict(res, figures)
    res["verdict"] = verdict.to_json()
    if emit_json(args, res):
        return exit_code(verdict, args.strict)
    fs = res["full_scale_mm"]
    left = (f" ({outside} reading(s) left out as train does, --whole keeps them)"
            if outside else "")
    print(f"{rec.source}: {res['points']} points{left}, full scale {fs:g} mm "
          f"(linearity tol +-{args.tol:g} % FS = {args.tol * fs / 100:g} mm, "
          f"band +-{args.band:g} % FS = {args.band * fs / 100:g} mm)")
    rows = [("max error (mm)", "max_error_mm", "{:.4g}"),
            ("RMS error (mm)", "rms_error_mm", "{:.4g}"),
            ("max error (% FS)", "max_error_pct_fs", "{:.4g}"),
            ("RMS error (% FS)", "rms_error_pct_fs", "{:.4g}"),
            ("% of linearity range", "linearity_pct", "{:.2f}"),
            (f"stroke within +-{args.band:g} % FS", "stroke_fraction_within_band", "{:.2%}")]
    hw = res.get("hardware")
    if hw:
        print(f"{'':28s}{'compensated':>14s}{'raw (LS line)':>16s}{'hardware':>12s}")
    else:
        print(f"{'':28s}{'compensated':>14s}{'raw (LS line)':>16s}")
    for label, key, fmt in rows:
        print(f"{label:28s}{fmt.format(res['compensated'][key]):>14s}"
              f"{fmt.format(res['raw'][key]):>16s}" + (f"{fmt.format(hw[key]):>12s}" if hw else ""))
    if hw:
        lim = hw["physical_limit_mm"]
        dropped = (f" (a {hw['adc_bits']}-bit ADC x {hw['adc_lsb_v']:g} V, {hw['dropped_low_bits']} low bits "
                   "dropped)" if hw["dropped_low_bits"] else "")
        temp = (f", {hw['temp_bits']}-bit temperature x {hw['temp_lsb_c']:g} degC" if "temp_bits" in hw else "")
        out = (f"output LSB {hw['output_lsb_mm']:g} mm" if hw.get("output_lsb_mm") is not None
               else f"{hw.get('number_format', 'float18')} output")
        print(f"hardware: {hw['input_bits']}-bit ADC x {hw['input_lsb_v']:g} V{dropped}{temp}, {out}, "
              f"{hw['points_clamped']} point(s) clamped; {hardware_vs_float(hw)}")
        if "weight_image" in hw:
            print(f"hardware weight memories: {hw['weight_image']}")
        print(f"physical limit (1/2 ADC LSB / slope): {lim['min']:.3g} .. {lim['max']:.3g} mm; "
              f"max error / limit: hardware {hw['ratio_to_limit']:.2f}, float "
              f"{hw['float_ratio_to_limit']:.2f}")
    if errors is not None and len(res["raw"]["by_temperature"]) > 1:
        drift = res["drift_ppm_fs_per_c"]
        rows = zip(res["raw"]["by_temperature"], res["compensated"]["by_temperature"],
                   (hw or {}).get("by_temperature") or [None] * len(res["raw"]["by_temperature"]))
        print("by temperature (max error mm): " + "; ".join(
            f"{r['temperature_c']:g} degC raw {r['max_error_mm']:.4g}, compensated {c['max_error_mm']:.4g}"
            + (f", hardware {h['max_error_mm']:.4g}" if h else "") for r, c, h in rows))
        print("drift (ppm FS/degC): " + ", ".join(
            f"{k} {v:.3g}" for k, v in drift.items() if v is not None))
    lin = res.get("linearity_pct_fs")
    if lin:
        def judged(value):
            return f"{'within' if value <= lin['reference_pct_fs'] else 'beyond'} the {lin['reference']} " \
                   f"of {lin['reference_pct_fs']:g}"

        print(f"linearity_pct_fs        {lin['float']:.4f} (float chain: the conditioner's twin, the FLANN in "
              f"float): {judged(lin['float'])}")
        if lin["hardware"] is not None:
            print(f"linearity_pct_fs        {lin['hardware']:.4f} (hardware: the conditioner's twin, the FLANN's twin "
                  f"of {args.design}): {judged(lin['hardware'])}")
    for f in figures:
        print(f"{f.text()}\n    from {f.source}")
    enob = res.get("effective_bits") or {}
    if enob.get("hardware_output_bits") is not None and enob.get("value") is not None:
        held, lsb = enob["hardware_output_bits"], chain.spec.output_lsb_mm
        enough = held >= enob["value"]
        print(f"the design's output LSB {lsb:g} mm holds {held:.1f} bits of the {2 * fs:g} mm span: "
              f"{'enough for' if enough else 'fewer than'} the {enob['value']:.1f} effective bits"
              + ("" if enough else f" (flann gen --output-lsb-mm {2 * fs / 2 ** math.ceil(enob['value']):.2g} keeps them)")
              + (f"; its words measure {enob['hardware_bits']:.1f} effective bits (their noise and rounding)"
                 if enob.get("hardware_bits") is not None else ""))
    if args.plot:
        print(f"plot: {args.plot}")
    print(verdict.line())
    return exit_code(verdict, args.strict)
