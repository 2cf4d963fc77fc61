"""``flann calibrate REC.csv... -o OUTDIR --design DIR [-j N] [--spec SPEC.toml]``: per-sensor
weights, certificates with a PASS/FAIL verdict (NOT JUDGED without a specification), and a summary."""

from __future__ import annotations

import sys

from ..argtypes import bounded
from ..errors import one_line
from ..production.calibrate import DIAGNOSIS_POINTS, calibrate_batch, summary_path
from ..production.spec import build_spec
from ..production.traceability import Station, parse_due
from ..production.verdict import NOT_JUDGED
from .common import add_common, quiet

HELP = "calibrate sensors for a family design: weight images and certificates"


def add_arguments(p) -> None:
    p.add_argument("recordings", nargs="+", metavar="REC.csv", help="one recordings CSV per sensor (name = file stem)")
    p.add_argument("--design", required=True, metavar="DIR", help="family design from `flann gen --family`")
    add_common(p, output=dict(help="OUTDIR/<sensor>/ and OUTDIR/summary.csv", metavar="OUTDIR", required=True,
                              legacy_out=True), jobs="sensors calibrated")
    p.add_argument("--sensor", metavar="TOML", default=None,
                   help="nominal sensor description for the diagnosis (geometry known: faster)")
    p.add_argument("--diagnosis-points", type=int, default=DIAGNOSIS_POINTS, metavar="N",
                   help="the diagnosis sees at most N bin means of the recording (0 = every point; "
                        f"default {DIAGNOSIS_POINTS})")
    g = p.add_argument_group("specification (PASS/FAIL; flags override --spec)")
    g.add_argument("--spec", metavar="SPEC.toml", default=None,
                   help="tolerance and limits every sensor is judged against (docs/production.md)")
    g.add_argument("--tolerance-mm", "--max-error-mm", dest="tolerance_mm", type=bounded(float, 0, lo_open=True),
                   default=None,
                   metavar="MM", help="FAIL a sensor whose hardware max error exceeds this (mm)")
    g.add_argument("--tolerance-pct-fs", type=bounded(float, 0, lo_open=True), default=None, metavar="PCT",
                   help="the same in %% of full scale (half the span judged over: the working range, else the recorded stroke)")
    g.add_argument("--working-range", default=None, metavar="LO:HI",
                   help="judge the error over this displacement range (mm; default the whole stroke)")
    g.add_argument("--max-ratio-to-limit", type=bounded(float, 0, lo_open=True), default=None, metavar="R",
                   help="FAIL when the max error exceeds R x the physical limit")
    g.add_argument("--fail-on-effect", action="append", default=[], metavar="EFFECT",
                   help="FAIL when the diagnosis names this effect (repeatable)")
    t = p.add_argument_group("traceability (a recording's own '# key: value' lines take precedence)")
    t.add_argument("--station", default="", help="calibration station")
    t.add_argument("--operator", default="", help="operator")
    t.add_argument("--fixture", default="", help="fixture")
    t.add_argument("--temperature-c", type=float, default=None, metavar="DEGC",
                   help="calibration temperature (default: the recording's, if it says)")
    t.add_argument("--serial-column", default="", metavar="NAME",
                   help="read each sensor's serial from this CSV column (default: the file name)")
    t.add_argument("--certificate-prefix", default="FLANN", type=_prefix, metavar="TEXT",
                   help="certificate numbers are TEXT-YYYYMMDD-HHMMSS-<recording sha256, 8 digits> (default FLANN)")
    t.add_argument("--reference-standard", default="", metavar="TEXT",
                   help="the displacement reference standard the recordings were taken against (name, serial)")
    t.add_argument("--reference-due", default=None, metavar="YYYY-MM-DD",
                   help="the reference standard's calibration due date (a past date is refused)")


def _prefix(text: str) -> str:
    import argparse
    import re

    if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,31}", text):
        raise argparse.ArgumentTypeError(f"{text!r}: letters, digits, '_', '.', '-' (at most 32)")
    return text


def run(args) -> int:
    spec = build_spec(args.spec, max_error_mm=args.tolerance_mm, max_error_pct_fs=args.tolerance_pct_fs,
                      working_range=args.working_range, max_ratio_to_limit=args.max_ratio_to_limit,
                      fail_on_effects=args.fail_on_effect)
    station = Station(station=args.station, operator=args.operator, fixture=args.fixture,
                      temperature_c=args.temperature_c, serial_column=args.serial_column,
                      certificate_prefix=args.certificate_prefix, reference_standard=" ".join(args.reference_standard.split()),
                      reference_due=parse_due(args.reference_due) if args.reference_due is not None else None)
    results = calibrate_batch(args.recordings, args.output, args.design, jobs=args.jobs, sensor_toml=args.sensor,
                              diagnosis_points=args.diagnosis_points, spec=spec, station=station,
                              progress=False if quiet(args) else None)
    rejected = [r for r in results if r.verdict is None or r.verdict.rejected]
    failed = [r for r in results if r.status != "ok" and r not in rejected]
    for r in rejected:
        print(f"error: {r.sensor}: {r.reason}", file=sys.stderr)
    for r in failed:
        print(f"FAIL: {r.sensor}: {r.reason}", file=sys.stderr)
    for r in results:   # every warning of the row's `warnings` column, one line each
        for w in r.warnings:
            print(f"warning: {r.sensor}: {one_line(w)}", file=sys.stderr)
    passed = len(results) - len(rejected) - len(failed)
    if not spec.judges:   # calibrated, but against nothing: never a PASS
        print(f"{passed} of {len(results)} sensor(s) calibrated and {NOT_JUDGED} (no specification given: "
              f"--spec or --tolerance-mm), {len(rejected)} rejected; summary {summary_path(args.output)}")
    else:
        print(f"{passed} of {len(results)} sensor(s) PASS, {len(failed)} FAIL the specification, "
              f"{len(rejected)} rejected; summary {summary_path(args.output)}")
    return 2 if rejected else 1 if failed else 0
