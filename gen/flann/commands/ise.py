"""flann ise DIR: ISE 10.1 project (xtclsh script, UCF with pin map, FuseSoC core) for a generated design."""

from __future__ import annotations

import sys

from ..hardware.target import CLOCK_HZ, DEFAULT_PART, parse_part
from ..hardware.design import open_directory
from ..implement import ise
from .common import add_common

HELP = "write an ISE 10.1 project for the generated VHDL"


def add_arguments(p):
    p.add_argument("directory", metavar="DIR", help="generated design: DIR/manifest.json and its VHDL files")
    p.add_argument("--device", default=None, metavar="PART",
                   help="Spartan-II part DEVICE-PACKAGE-SPEED, e.g. xc2s15-tq144-5 (default: the part in "
                        f"DIR/manifest.json, as for flann synth, else {DEFAULT_PART}; the example pin map is for "
                        "PQ208, on other packages ISE chooses the pins)")
    p.add_argument("--force", action="store_true",
                   help="write the project even when the design's resource estimate (or, without one, its synthesized "
                        "netlist) does not fit the part")
    p.add_argument("--clock-mhz", type=float, default=CLOCK_HZ / 1e6,
                   help="clock frequency for the PERIOD constraint (default %(default)g); lowered to what the "
                        "Spartan-II timing estimate meets, with a warning")
    p.add_argument("--no-timing-check", action="store_true",
                   help="write the PERIOD as given, without synthesising for the timing estimate")
    add_common(p, output=dict(help="output directory (default ise/)", metavar="OUT", default="ise"))


def run(args) -> int:
    # the part the design was generated for unless another is asked for, as flann synth does;
    # read first either way: the design's files are inputs no output may replace
    design = open_directory(args.directory)   # read once, handed to every step
    args.device = args.device or ise.design_device(design)
    parse_part(args.device)  # refuse a bad part before synthesis
    ise.check_output(args.output)  # and an output directory it may not replace
    ise.check_directory_fits(design, args.device, force=args.force)
    clock = args.clock_mhz
    if not args.no_timing_check:
        clock, why = ise.checked_clock(design, args.device, args.clock_mhz, force=args.force)
        if why:
            print(f"warning: {why}", file=sys.stderr)
    files = ise.write_ise(design, args.device, args.output, clock, force=args.force)
    print(ise.summary(files, args.output, args.device))
    return 0
