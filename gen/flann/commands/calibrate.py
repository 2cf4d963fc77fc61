"""``flann calibrate REC.csv... -o OUTDIR --design DIR [-j N]``: per-sensor weights and certificates."""

from __future__ import annotations

import sys

from ..argtypes import bounded
from ..production.calibrate import DIAGNOSIS_POINTS, SUMMARY, calibrate_batch

HELP = "calibrate sensors for a family design: weight images and certificates"


def add_arguments(p) -> None:
    p.add_argument("recordings", nargs="+", metavar="REC.csv", help="one recordings CSV per sensor (name = file stem)")
    p.add_argument("-o", "--out", required=True, metavar="OUTDIR", help="OUTDIR/<sensor>/ and OUTDIR/summary.csv")
    p.add_argument("--design", required=True, metavar="DIR", help="family design from `flann gen --family`")
    p.add_argument("-j", "--jobs", type=int, default=None, metavar="N", help="parallel workers (default: all cores)")
    p.add_argument("--sensor", metavar="TOML", default=None,
                   help="nominal sensor description for the diagnosis (geometry known: faster)")
    p.add_argument("--diagnosis-points", type=int, default=DIAGNOSIS_POINTS, metavar="N",
                   help="the diagnosis sees at most N bin means of the recording (0 = every point; "
                        f"default {DIAGNOSIS_POINTS})")
    p.add_argument("--max-error-mm", type=bounded(float, 0, lo_open=True), default=None,
                   help="fail a sensor whose hardware max error on its recording exceeds this")


def run(args) -> int:
    results = calibrate_batch(args.recordings, args.out, args.design, jobs=args.jobs, sensor_toml=args.sensor,
                              max_error_mm=args.max_error_mm, diagnosis_points=args.diagnosis_points)
    bad = [r for r in results if r.status != "ok"]
    for r in bad:
        print(f"error: {r.sensor}: {r.reason}", file=sys.stderr)
    print(f"{len(results) - len(bad)} of {len(results)} sensor(s) calibrated; summary {args.out}/{SUMMARY}")
    return 2 if bad else 0
