"""flann ise DIR: ISE 10.1 project (xtclsh script, UCF with pin map, FuseSoC core) for a generated design."""

from __future__ import annotations

from ..hardware.target import CLOCK_HZ, DEFAULT_PART
from ..implement import ise

HELP = "write an ISE 10.1 project for the generated VHDL"


def add_arguments(p):
    p.add_argument("directory", metavar="DIR", help="generated design: DIR/manifest.json and its VHDL files")
    p.add_argument("--device", default=DEFAULT_PART, metavar="PART",
                   help="Spartan-II part DEVICE-PQ208-SPEED (default %(default)s)")
    p.add_argument("-o", "--output", default="ise", metavar="OUT", help="output directory (default ise/)")
    p.add_argument("--force", action="store_true",
                   help="write the project even when the design's resource estimate does not fit the part")
    p.add_argument("--clock-mhz", type=float, default=CLOCK_HZ / 1e6,
                   help="clock frequency for the PERIOD constraint (default %(default)g)")


def run(args) -> int:
    files = ise.write_ise(args.directory, args.device, args.output, args.clock_mhz, force=args.force)
    print(ise.summary(files, args.output, args.device))
    return 0
