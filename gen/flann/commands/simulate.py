"""``flann simulate``: LVDT physics simulator (recordings from a sensor file) and calibration.

    flann simulate [SENSOR.toml] -o recordings.csv [--sweeps N] [--step-mm S] [--noise-v SIGMA]
                   [--seed K] [--temperature-profile SPEC | --temperatures T1,T2,...]
                   [--from-mm A --to-mm B] [--plot P.png]
    flann simulate --fit RECORDINGS.csv [SENSOR.toml] [--params a,b,...] [--write-sensor OUT.toml]
                   [--json [OUT.json]] [--plot P.png]

Without SENSOR.toml the seed paper's LVDT (data/sensors/paper_lvdt.toml) is used.
"""

from __future__ import annotations

import re
import warnings

import numpy as np

from ..argtypes import bounded, png_path
from ..errors import FlannError
from ..fileio import atomic_write_text
from ..physics.effects import EFFECTS, thermal_coefficient_from_copper
from ..physics.fit import DEFAULT_FIT_PARAMS, fit_sensor
from ..physics.lvdt import describe
from ..physics.sensor import default_sensor, format_sensor, load_sensor, spread_unit
from ..physics.simulate import (fold_back_mm, parse_temperatures, simulate_calibration,
                                simulate_recordings)
from ..recordings import read_recordings, write_recordings
from ..recordings.csvio import MAX_ROWS
from .common import add_common, emit_json, info, json_to_stdout, quiet
from .simulate_waveforms import add_waveform_arguments, run_waveforms, waveform_options_used

HELP = "LVDT physics simulator: write recordings from a sensor file"


# "--temperatures -20,0,25" : a value that starts with a minus sign and a digit is a
# value, not an option (argparse only knows single negative numbers)
_NEGATIVE_VALUE = re.compile(r"^-\d[\d.,eE+-]*$")


def add_arguments(p) -> None:
    p._negative_number_matcher = _NEGATIVE_VALUE
    p.add_argument("sensor", nargs="?", default=None,
                   help="sensor TOML (default: the seed paper's LVDT)")
    p.add_argument("--sweeps", type=int, default=1,
                   help="forward+reverse passes (default 1)")
    p.add_argument("--step-mm", type=float, default=1.0, help="actuator step (default 1 mm)")
    p.add_argument("--from-mm", type=bounded(float, -1e6, 1e6), default=None,
                   help="start of travel (default -stroke_mm of the sensor)")
    p.add_argument("--to-mm", type=bounded(float, -1e6, 1e6), default=None,
                   help="end of travel (default +stroke_mm of the sensor)")
    p.add_argument("--step-time-s", type=float, default=1.0,
                   help="time per step (default 1 s)")
    p.add_argument("--noise-v", type=float, default=0.0,
                   help="white Gaussian noise, V rms, before the ADC (default 0)")
    p.add_argument("--seed", type=bounded(int, 0, 2**32 - 1), default=None,
                   help="seed of the noise (--noise-v) and of the unit drawn by --spread (default 0); "
                        "refused without either, where it would change nothing")
    p.add_argument("--spread", type=bounded(float, 0, 0.2), default=0.0, metavar="SIGMA",
                   help="unit-to-unit spread of the construction (windings, core and coil geometry, gain): "
                        "each parameter times (1 + N(0, SIGMA)), the unit drawn by --seed; one seed per "
                        "sensor of a production batch (default 0: the nominal sensor)")
    p.add_argument("--temperature-profile", default="const:20",
                   help="const:T | ramp:T0:T1 (over the run) | sine:MEAN:AMP:PERIOD_S "
                        "(degC; default const:20)")
    p.add_argument("--temperatures", default=None, metavar="T1,T2,...",
                   help="a calibration at several temperatures: the sweeps at each of these "
                        "(degC, e.g. -20,0,25,50,80) in turn, the sensor soaked at each; "
                        "replaces --temperature-profile")
    p.add_argument("--no-effects", action="store_true",
                   help="ignore the sensor file's [effects] (ideal sensor)")
    p.add_argument("--plot", metavar="OUT.png", type=png_path, help="PNG: curve and each enabled effect's contribution "
                                  "(with --fit: calibration and residuals; with --describe: "
                                  "flux along the bore and inductances)")
    p.add_argument("--describe", action="store_true",
                   help="print derived quantities of the sensor (slope, currents, flux density, "
                        "fold-back, copper thermal coefficient) and exit")
    p.add_argument("--list-effects", action="store_true",
                   help="print the catalogue of non-ideal effects ([effects.NAME] tables) and exit")
    p.add_argument("--fit", metavar="RECORDINGS", default=None,
                   help="calibrate the unknown geometry of the sensor to these recordings")
    p.add_argument("--params", default=None,
                   help="with --fit: comma-separated sensor fields to fit (default "
                        "primary_length_mm,secondary_length_mm,secondary_gap_mm,"
                        "demodulator_gain_ratio)")
    p.add_argument("--write-sensor", help="with --fit: write the calibrated sensor TOML")
    add_common(p, output=dict(help="recordings CSV to write (simulation mode)", metavar="OUT.csv"),
               json="the fit report (--fit), the quantities (--describe) or the catalogue (--list-effects)")
    add_waveform_arguments(p)


def _sensor(args):

    return load_sensor(args.sensor) if args.sensor else default_sensor()


def _list_effects(args) -> int:
    if emit_json(args, [{"name": e.name, "stage": e.stage, "description": e.description, "formula": e.formula,
                         "params": [{"name": p.name, "default": p.default, "description": p.description,
                                     "unit": p.unit, "lower": p.lower, "upper": p.upper, "neutral": p.neutral}
                                    for p in e.params]} for e in EFFECTS.values()]):
        return 0
    for e in EFFECTS.values():
        print(f"[effects.{e.name}]  ({e.stage} stage) {e.description}")
        print(f"    {e.formula}")
        for p in e.params:
            print(f"    {p.name} = {p.default:g}   # {p.description}; {p.unit}, "
                  f"range {p.lower:g}..{p.upper:g}, no effect at {p.neutral:g}")
    return 0


def _describe(args) -> int:

    s = _sensor(args)
    quantities = describe(s)
    fold = fold_back_mm(s, (-3 * s.stroke_mm, 3 * s.stroke_mm), n=4001)
    copper = thermal_coefficient_from_copper(s)
    obj = {"sensor": s.name, "description": s.description, **{k: float(v) for k, v in quantities.items()},
           "output_fold_back_mm": None if fold is None else float(fold),   # null: none within 3 x stroke
           "copper_thermal_coefficient_per_c": float(copper)}
    if not emit_json(args, obj):
        print(f"{s.name}: {s.description}" if s.description else s.name)
        for k, v in quantities.items():
            print(f"  {k} = {v:.4g}")
        print(f"  output_fold_back_mm = {fold:.4g}" if fold is not None else
              "  output_fold_back_mm = none within 3 x stroke")
        print(f"  copper_thermal_coefficient_per_c = {copper:.3g}")
    if args.plot:
        from ..physics.plots import plot_anatomy  # matplotlib: loaded only to plot

        plot_anatomy(s, args.plot)
    return 0


def run(args) -> int:
    if args.list_effects:
        return _list_effects(args)
    if args.describe:
        return _describe(args)
    if args.fit:
        return _run_fit(args)
    if not args.output:
        raise FlannError("simulate: give -o RECORDINGS.csv (or --fit RECORDINGS.csv)")
    for opt in ("params", "write_sensor"):
        if getattr(args, opt):
            raise FlannError(f"simulate: --{opt.replace('_', '-')} needs --fit")
    if args.json:
        raise FlannError("simulate: --json is the report of --fit, --describe or --list-effects (a simulation "
                         "writes its recordings to -o)")


    if args.seed is not None and not args.noise_v and not args.spread:
        raise FlannError("simulate: --seed draws the noise (--noise-v) or the unit (--spread); without "
                         "either every seed writes the same rows")
    seed = 0 if args.seed is None else args.seed
    s = _sensor(args)
    if args.no_effects:
        s = s.without_effects()
    drawn = ""
    if args.spread:
        s, factors = spread_unit(s, args.spread, seed)
        drawn = ", ".join(f"{k} x{v:.4f}" for k, v in factors.items())
    lo = -s.stroke_mm if args.from_mm is None else args.from_mm
    hi = s.stroke_mm if args.to_mm is None else args.to_mm
    if args.temperatures is not None and args.temperature_profile != "const:20":
        raise FlannError("simulate: give either --temperatures or --temperature-profile")
    if args.waveforms:
        return run_waveforms(args, s, (lo, hi))
    if waveform_options_used(args):
        raise FlannError("simulate: --carrier-hz, --sample-rate-hz, --adc-*, --trajectory, --excitation-drift-pct "
                         "and --harmonic-pct need --waveforms")
    if not args.step_mm > 0:
        raise FlannError(f"simulate: --step-mm must be > 0, got {args.step_mm:g}")
    per_sweep = 2 * (abs(hi - lo) / args.step_mm) + 1   # a sweep goes out and back
    n_temps = len(parse_temperatures(args.temperatures)) if args.temperatures is not None else 1
    if per_sweep * max(args.sweeps, 1) * n_temps > MAX_ROWS:
        raise FlannError(f"simulate: {abs(hi - lo):g} mm at --step-mm {args.step_mm:g}, {args.sweeps} sweep(s)"
                         f"{f', {n_temps} temperatures' if n_temps > 1 else ''} is about "
                         f"{per_sweep * max(args.sweeps, 1) * n_temps:,.0f} rows, more than flann reads "
                         f"({MAX_ROWS:,}): use a larger --step-mm")
    if args.temperatures is not None:
        temps = parse_temperatures(args.temperatures)
        rec = simulate_calibration(s, temps, sweeps=args.sweeps, step_mm=args.step_mm,
                                   noise_v=args.noise_v, seed=seed, travel_mm=(lo, hi),
                                   step_time_s=args.step_time_s, progress=not quiet(args))
        temperature = "calibration at " + ", ".join(f"{t:g}" for t in temps) + " degC"
    else:
        rec = simulate_recordings(s, sweeps=args.sweeps, step_mm=args.step_mm, noise_v=args.noise_v,
                                  seed=seed, temperature_profile=args.temperature_profile,
                                  travel_mm=(lo, hi), step_time_s=args.step_time_s, progress=not quiet(args))
        temperature = args.temperature_profile
    fold = fold_back_mm(s, (lo, hi))
    if fold is not None:
        warnings.warn(f"travel {lo:g}..{hi:g} mm goes past |x| = {fold:.1f} mm where the output "
                      "folds back (core end leaving a secondary)")
    effects = "; ".join(f"{n}(" + ", ".join(f"{k}={v:g}" for k, v in p.items()) + ")"
                        for n, p in s.effects.items()) or "none"
    comments = (
        f"simulated by flann simulate: sensor {s.name} ({args.sensor or 'default'})",
        f"travel {lo:g}..{hi:g} mm, step {args.step_mm:g} mm, sweeps {args.sweeps}, "
        f"step time {args.step_time_s:g} s, noise {args.noise_v:g} V rms, seed {seed}, "
        f"temperature {temperature}",
        f"effects: {effects}",
    ) + ((f"unit drawn with --spread {args.spread:g}, seed {seed}: {drawn}",) if drawn else ())
    if args.plot:
        from ..physics.plots import plot_simulation  # matplotlib: loaded only to plot

        plot_simulation(s, rec, args.plot)
    write_recordings(args.output, rec, comments=comments)
    info(args, f"wrote {args.output}: {len(rec)} rows, effects: {effects}")
    return 0


def _run_fit(args) -> int:
    if args.output:
        raise FlannError("simulate --fit: -o is for simulation; use --write-sensor OUT.toml")

    s = _sensor(args)
    rec = read_recordings(args.fit, announce=not args.quiet)
    params = DEFAULT_FIT_PARAMS
    if args.params:
        params = tuple(p.strip() for p in args.params.split(",") if p.strip())
    if not float(np.ptp(rec.voltage_v)) > 0:
        raise FlannError(f"{args.fit}: the voltage is the same on every row: no sensor to calibrate")
    fit = fit_sensor(rec, sensor=s, params=params)
    if not all(np.isfinite(v) for v in (*fit.values.values(), fit.rms_v, fit.noise_v)):
        raise FlannError(f"{args.fit}: the fit did not converge to finite values (a recording with no "
                         "usable slope?): nothing written")
    if not json_to_stdout(args):
        print(f"calibrated {s.name} to {args.fit} ({len(rec)} points, ideal model, no effects):")
        for line in fit.summary_lines():
            print(f"  {line}")
        for row in fit.excluded_rows:
            print(f"  excluded row {row}: {rec.displacement_mm[row]:g} mm, {rec.voltage_v[row]:g} V "
                  f"is {fit.residual_v[row]:+.3f} V off the curve "
                  f"({abs(fit.residual_v[row]) / fit.noise_v:.0f} x the robust noise "
                  f"{fit.noise_v * 1e3:.0f} mV): outlier, not fitted")
    if args.write_sensor:
        atomic_write_text(args.write_sensor, format_sensor(
            fit.sensor, comments=(f"calibrated by: flann simulate --fit {args.fit}",
                                  f"rms residual {fit.rms_v * 1e3:.1f} mV")))
    if args.json:
        emit_json(args, {
            "recordings": str(args.fit),
            "params": fit.values,
            "stderr": fit.stderr,
            "rms_v": fit.rms_v,
            "noise_v": fit.noise_v,
            "even_part_rms_v": None if fit.asymmetry_floor_v != fit.asymmetry_floor_v
            else fit.asymmetry_floor_v,
            "points_used": int(fit.used.sum()),
            "residuals": [{"row": i, "displacement_mm": float(x), "residual_v": float(r),
                           "used": bool(u)}
                          for i, (x, r, u) in enumerate(zip(rec.displacement_mm, fit.residual_v,
                                                            fit.used))],
            "excluded": [{"row": r, "displacement_mm": float(rec.displacement_mm[r]),
                          "voltage_v": float(rec.voltage_v[r]),
                          "residual_v": float(fit.residual_v[r])} for r in fit.excluded_rows],
        })
    if args.plot:
        from ..physics.plots import plot_fit  # matplotlib: loaded only to plot

        plot_fit(rec, fit, args.plot)
    return 0
