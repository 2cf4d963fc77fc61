"""``flann paper``: the seed paper's Table 2 (and Fig. 5) reproduced, plus what it did not show."""

from __future__ import annotations

import numpy as np

from ..argtypes import bounded, checked
from ..errors import FlannError
from ..fileio import atomic_directory
from ..golden.metrics import DEFAULT_TOL_PCT_FS
from ..recordings import read_recordings
from ..golden.train import MAX_EPOCHS, fit_lstsq, normalisation, normalisation_kind
from ..golden import paper
from ..hardware.fixed.cost import fixed_point_cost
from .common import add_common, emit_json

HELP = "reproduce the seed paper's tables and figures"



def _only_pngs(directory) -> bool:
    return all(p.suffix == ".png" and p.is_file() for p in directory.iterdir())


def add_arguments(p) -> None:
    p.add_argument("--plot", metavar="DIR", default=None,
                   help="write PNGs equivalent to the paper's Fig. 5 into DIR")
    p.add_argument("--eta", type=bounded(float, 0, lo_open=True), default=paper.DEFAULT_ETA,
                   help="LMS learning rate (the paper gives none; default %(default)g)")
    p.add_argument("--epochs", type=bounded(int, 1, MAX_EPOCHS), default=paper.DEFAULT_EPOCHS,
                   help=f"LMS epochs (the paper gives none; default %(default)d, at most {MAX_EPOCHS})")
    p.add_argument("--tol", type=float, default=DEFAULT_TOL_PCT_FS, metavar="PCT_FS",
                   help="linearity tolerance, %% of full scale (default %(default)g)")
    p.add_argument("--data", default=None,
                   help="recordings CSV instead of the paper's Table 1 (built in)")
    p.add_argument("--normalise", type=checked(normalisation_kind), default="none",
                   help="input normalisation: 'none' = raw volts as the paper (default), "
                        "'range', 'half' or a number f in (0, 1] (the data's range -> [-f, f])")
    p.add_argument("--sensitivity", action="store_true",
                   help="also print Table 2 over a grid of eta and epochs")
    p.add_argument("--dense", action="store_true",
                   help="also run the tool's default (--terms auto) on dense physics-like "
                        "data and print the stroke fraction within +-0.1 %% FS before/after")
    add_common(p, json="Table 2 {raw_linearity_pct, tolerance_pct_fs, rows}")


def _loo_text(loo: np.ndarray, interior: np.ndarray) -> str:
    return f"LOO max {np.max(np.abs(loo)):.3g} mm (interior {np.max(np.abs(loo[interior])):.3g} mm)"


def run(args) -> int:
    if not (args.tol >= 0):
        raise FlannError(f"--tol must be >= 0 % FS, got {args.tol:g}")
    rec = paper.table1() if args.data is None else read_recordings(args.data, announce=not args.quiet)
    if len(rec) < 3:
        raise FlannError(f"{rec.source}: need at least 3 points, got {len(rec)}")
    offset_scale = normalisation(rec.voltage_v, args.normalise)
    out, details = paper.reproduce(rec, args.eta, args.epochs, args.tol, offset_scale)
    if args.plot:
        with atomic_directory(args.plot, _only_pngs, "directory of flann paper plots") as tmp:
            paper.plot_fig5(tmp, rec, details)
    if emit_json(args, out):
        return 0
    _print_report(rec, out, details, args, offset_scale)
    return 0


def _print_report(rec, out, details, args, offset_scale) -> None:  # noqa: C901
    fs = details["fs_mm"]
    norm = ("raw volts" if args.normalise == "none"
            else f"volts normalised '{args.normalise}' (offset {offset_scale[0]:g} V, "
                 f"scale {offset_scale[1]:g} V)")
    print(f"Table 2 reproduced on {rec.source}: LMS on {norm}, weights and bias start at 1, "
          f"eta {args.eta:g}, {args.epochs} epochs (the paper gives neither)")
    print(f"% of linearity range: points within +-{args.tol:g} % FS = +-{args.tol * fs / 100:g} mm "
          f"of the ideal line (FS = {fs:g} mm)")
    print(f"raw sensor vs its least-squares line: {out['raw_linearity_pct']:.2f} %  "
          f"(paper {paper.PAPER_RAW_PCT:.2f} %)")
    print(f"{'terms':>5s} {'linearity %':>12s} {'paper %':>8s} {'LOO max mm':>11s} "
          f"{'LOO max interior mm':>20s} {'final MSE mm^2':>15s}")
    interior = np.ones(len(rec), bool)
    interior[[int(np.argmin(rec.voltage_v)), int(np.argmax(rec.voltage_v))]] = False
    for row in out["rows"]:
        t = row["terms"]
        loo = details["loo"][t][interior]
        print(f"{t:5d} {row['linearity_pct']:12.2f} {row['paper_pct']:8.2f} "
              f"{row['loo_max_error_mm']:11.3g} {np.max(np.abs(loo)):20.3g} "
              f"{details['models'][t].training['mse_per_epoch'][-1]:15.3g}")
    print("LOO: each point held out in turn, same method; 'interior' leaves out the two end "
          "points, whose held-out error is extrapolation.")
    positions = np.unique(rec.displacement_mm).size
    repeats = (f" ({positions} positions: repeated readings averaged per position for the "
               "interpolant)" if positions < len(rec) else "")
    print(f"Between the {len(rec)} points{repeats}: leave-one-out, and a dense sweep of v compared "
          "with the monotone PCHIP interpolant of the points:")
    default = fit_lstsq(rec.voltage_v, rec.displacement_mm, 51, norm="range")
    auto = paper.default_fit(rec, fixed_point_cost)
    designs = (("51 terms, paper LMS", details["models"][51],
                _loo_text(details["loo"][51], interior)),
               ("51 terms, lstsq, range (default design)", default,
                _loo_text(paper.lstsq_loo_errors(rec, 51, "range"), interior)),
               (f"flann train default (--terms auto): {auto.label}", auto.model, auto.loo_text))
    for label, model, loo_text in designs:
        b = paper.between_points(model, rec)
        print(f"  {label}:\n    {loo_text}; max deviation "
              f"{b['max_dev_from_pchip_mm']:.3g} mm "
              f"({b['max_dev_from_pchip_pct_fs']:.3g} % FS) at {b['at_voltage_v']:.3f} V; "
              f"{b['sweep_fraction_within_tol_of_pchip']:.1%} of the sweep within +-{args.tol:g} "
              f"% FS of it; output spans {b['output_range_mm'][0]:.3g} .. "
              f"{b['output_range_mm'][1]:.3g} mm; decreasing on {b['decreasing_fraction']:.1%}")
    if args.sensitivity:
        grid = paper.sensitivity(rec, tol_pct_fs=args.tol)
        etas = sorted({k[1] for k in grid})
        eps = sorted({k[2] for k in grid})
        print("Sensitivity: % of linearity range by (eta, epochs); '-' = LMS diverged")
        print(f"{'terms':>5s} {'eta':>6s} " + " ".join(f"{e:>7d}" for e in eps))
        for t in (11, 25, 51, 61):
            for eta in etas:
                cells = [grid.get((t, eta, e)) for e in eps]
                print(f"{t:5d} {eta:6g} " + " ".join(
                    f"{c:7.2f}" if c is not None else f"{'-':>7s}" for c in cells))
    if args.dense:
        d = paper.dense_demo(cost=fixed_point_cost)
        print(f"flann train default (--terms auto) on dense physics-like data (tanh S-curve, "
              f"{d['noise_v'] * 1e3:g} mV noise; 601 training points, 600 held-out points "
              f"between them): {d['label']}")
        for key, label in (("before", "before (raw, LS line)"), ("after", "after (FLANN)")):
            r = d[key]
            print(f"  {label:22s}: stroke within +-{d['band_pct_fs']:g} % FS "
                  f"{r['stroke_fraction_within_band']:.1%}, max error {r['max_error_mm']:.3g} mm "
                  f"({r['max_error_pct_fs']:.3g} % FS), RMS {r['rms_error_mm']:.3g} mm")
