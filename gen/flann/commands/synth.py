"""flann synth DIR: resource estimate of generated VHDL (GHDL synthesis + Yosys) for a Spartan-II."""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from ..errors import FlannError
from ..implement import synth
from ..hardware.target import DEFAULT_PART, DEVICES, parse_part
from ..hardware.registry import read_design
from ..verify.design import from_directory
from ..verify.netlist import check_synthesized

HELP = "resource estimate via GHDL synthesis and Yosys"


def add_arguments(p):
    p.add_argument("directory", metavar="DIR", help="generated design: DIR/manifest.json and its VHDL files")
    p.add_argument(
        "--device", default=None, metavar="PART",
        help="target part DEVICE-PACKAGE-SPEED, e.g. xc2s30-pq208-5 (default: the part in DIR/manifest.json, "
        f"else {DEFAULT_PART}; devices " + ", ".join(d.name for d in DEVICES) + ")",
    )
    p.add_argument("--json", action="store_true", help="print the report as JSON on stdout")
    p.add_argument("--no-lint", action="store_true", help="skip the VSG style check of the VHDL")
    p.add_argument("--vsg-config", metavar="YAML", help="VSG configuration (default: vsg.yaml of the repository)")
    p.add_argument("--abc", choices=synth.ABC_MODES, default="full",
                   help="LUT mapping: full = synth_xilinx as is (default); fast = abc -fast (large designs)")
    p.add_argument("--work", metavar="DIR", help="keep GHDL/Yosys intermediate files (netlist, yosys.log) here")
    p.add_argument("--model", metavar="MODEL.json", default=None,
                   help="the model DIR was generated from: the mapped netlist is then simulated over every input "
                        "code against the twin (Verilator) and a disagreeing design is refused")
    p.add_argument("--no-netlist-check", action="store_true", help="do not simulate the mapped netlist")


def _check_netlist(args, netlist: Path) -> None:
    """Refuse a design whose mapped netlist disagrees with its twin (needs the model)."""
    man, dp = read_design(args.directory)
    if not dp.netlist:
        return  # the netlist is driven by the sweep harness of flann_top's ports
    if args.model is None and not man.get("model"):
        print("warning: netlist not simulated: pass --model MODEL.json (the twin is built from the model)",
              file=sys.stderr)
        return
    design = from_directory(args.directory, args.model)
    if not args.json:
        print("synth: simulating the mapped netlist over every input code (Verilator)", file=sys.stderr)
    res = check_synthesized(design, netlist)
    if res["mismatches"]:
        raise FlannError(f"the mapped netlist of {args.directory} disagrees with its twin on {res['mismatches']} of "
                         f"{res['codes_tested']} input codes (first: {res['first_mismatches']}); not handing it on")


def run(args) -> int:
    if args.device is not None:
        parse_part(args.device)  # refuse a bad part before any slow step
    read_design(args.directory)  # a tampered manifest is refused before any slow step
    if not args.no_lint:
        man = synth.read_manifest(args.directory)
        synth.check_lint(man.files, args.vsg_config, start=args.directory)
    with tempfile.TemporaryDirectory(prefix="flann-synth-") as tmp:
        work = Path(args.work) if args.work else Path(tmp)
        report = synth.synthesize(args.directory, args.device, work=work, progress=not args.json, abc=args.abc)
        if not args.no_netlist_check:
            _check_netlist(args, work / synth.NETLIST)
    if args.json:
        print(json.dumps(report.to_dict(), indent=2))
    else:
        print(report.table())
        for w in report.warnings:
            print(f"warning: yosys: {w}", file=sys.stderr)
    if not report.fits:
        print(f"error: {synth.not_fit_message(report)}", file=sys.stderr)
        return 2
    return 0
