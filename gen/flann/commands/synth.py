"""flann synth DIR: resource estimate of generated VHDL (GHDL synthesis + Yosys) for a Spartan-II."""

from __future__ import annotations

import dataclasses
import sys
import tempfile
from pathlib import Path

from ..argtypes import TOOL_SEED
from ..eda import ABC_MODES, NETLIST
from ..errors import FlannError
from ..implement import ice40, synth
from ..hardware.target import (DEFAULT_ICE40_PART, DEFAULT_PART, DEVICES, ICE40_PARTS, is_ice40,
                               parse_ice40, parse_part)
from ..hardware.design import Design, open_directory
from ..hardware.manifest import refuse_design_directory
from ..verify.netlist import check_synthesized, has_sweep_driver, require_sweep_driver, sweep_datapaths
from ..verify.post_route import checker
from .common import add_common, cores_limited, emit_json, json_to_stdout, quiet

HELP = "resource estimate via GHDL synthesis and Yosys"


ICE40_OUT = "ice40"   # the bitstream directory without -o


def add_arguments(p):
    p.add_argument("directory", metavar="DIR", help="generated design: DIR/manifest.json and its VHDL files")
    p.add_argument(
        "--device", default=None, metavar="PART",
        help="target part DEVICE-PACKAGE-SPEED, e.g. xc2s30-pq208-5 (default: the part in DIR/manifest.json, "
        f"else {DEFAULT_PART}; devices " + ", ".join(d.name for d in DEVICES) + "); or an iCE40 part for real "
        "place and route, timing and a bitstream (" + ", ".join(p.name for p in ICE40_PARTS) + ")",
    )
    p.add_argument("--post-route", action="store_true",
                   help="iCE40 only: simulate the placed-and-routed design (icebox_vlog + Verilator, Yosys's iCE40 "
                        "cell models) over every input code against the twin (needs the model: --model or the "
                        "manifest's)")
    p.add_argument("--seed", type=TOOL_SEED, default=1, help="iCE40 only: nextpnr placement seed (default %(default)s)")
    p.add_argument("--no-lint", action="store_true", help="skip the VSG style check of the VHDL")
    p.add_argument("--vsg-config", metavar="YAML", help="VSG configuration (default: vsg.yaml of the repository)")
    p.add_argument("--abc", choices=ABC_MODES, default="full",
                   help="LUT mapping: full = synth_xilinx as is (default); fast = abc -fast (large designs)")
    p.add_argument("--work", metavar="DIR", help="keep GHDL/Yosys intermediate files (netlist, yosys.log) here")
    p.add_argument("--model", metavar="MODEL.json", default=None,
                   help="the model DIR was generated from, for the netlist check's twin (default: the model "
                        "DIR/manifest.json records)")
    p.add_argument("--no-netlist-check", action="store_true",
                   help="do not simulate the mapped netlist; by default the mapped netlist of a design flann gen "
                        "wrote is simulated over every input code (a design with temperature: at its sweep's "
                        "temperature codes) against the twin (Verilator), with --model or without "
                        "(the manifest's model), reported as 'netlist check' (JSON: netlist_check, null when not "
                        "run), and a disagreeing design is refused")
    add_common(p, output=dict(help=f"iCE40 only: directory for the bitstream (.bin), example pins (.pcf), .asc "
                                   f"and reports (default {ICE40_OUT}/)", metavar="OUT"),
               json="the report", jobs="netlist simulation shards")


def _check_netlist(args, design: Design, netlist: Path) -> dict:
    """The mapped netlist against its twin over every input code, as the report's netlist_*
    fields: the result, or why it was not run (and a warning when the user can supply what
    is missing); a design whose netlist disagrees is refused."""
    if args.no_netlist_check:
        return {"netlist_not_run": "--no-netlist-check"}
    man, dp = design.manifest, design.datapath
    if not has_sweep_driver(dp):
        return {"netlist_not_run": f"no netlist sweep for a {dp.name} design (it has a driver and twin for "
                                   f"{sweep_datapaths()} designs)"}
    if args.model is None and not man.get("model"):
        return {"netlist_not_run": "no model (pass --model MODEL.json)",
                "netlist_warning": "netlist not simulated: pass --model MODEL.json (the twin is built from the model)"}
    design = design.with_twin(args.model)
    if _progress(args):
        print("synth: simulating the mapped netlist over every input code (Verilator)", file=sys.stderr)
    res = check_synthesized(design, netlist)
    if not res.passed:
        raise FlannError(f"the mapped netlist of {args.directory} disagrees with its twin on {res.mismatches} of "
                         f"{res.codes_tested} samples (first: {res.first_mismatches}); not handing it on")
    return {"netlist_check": {"codes": res.codes_tested, "mismatches": res.mismatches, "passed": res.passed,
                              "simulator": res.simulator, "temperature_codes": res.temperature_codes}}


def post_route_check(design: Design, model):
    """The post-route simulation as :func:`flann.implement.ice40.implement` calls it; refuses a
    routed design that disagrees with its twin (nothing is written then)."""
    require_sweep_driver(design.datapath, design.directory)
    if model is None and not design.manifest.get("model"):
        raise FlannError("--post-route: pass --model MODEL.json (the twin is built from the model)")
    return checker(design.with_twin(model), refuse=True)


VSG_CONFIG_MAX_BYTES = 1 << 20


def check_vsg_config(path) -> None:
    """A --vsg-config VSG would choke on, refused in one line before it runs: YAML aliases (an
    alias bomb expands without bound), tags that build Python objects, or not a mapping."""
    if path is None:
        return
    import yaml   # VSG's own dependency: needed only with a lint

    p = Path(path)
    if not p.is_file():
        raise FlannError(f"--vsg-config {path}: no such file" if not p.exists() else f"--vsg-config {path}: not a regular file")
    if p.stat().st_size > VSG_CONFIG_MAX_BYTES:
        raise FlannError(f"--vsg-config {path}: larger than {VSG_CONFIG_MAX_BYTES >> 20} MB, not a VSG configuration")
    text = p.read_text(errors="replace")
    try:
        for event in yaml.parse(text, Loader=yaml.SafeLoader):
            if isinstance(event, yaml.AliasEvent):
                raise FlannError(f"--vsg-config {path}: uses a YAML alias (*{event.anchor}); a VSG configuration "
                                 "needs none: write the values out")
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        first = " ".join(str(exc).split())
        raise FlannError(f"--vsg-config {path}: not a VSG configuration: {first}") from None
    if not isinstance(data, dict):
        raise FlannError(f"--vsg-config {path}: not a VSG configuration (expected a YAML mapping of rules)")


def run_ice40(args) -> int:
    parse_ice40(args.device)  # refuse a bad part before any slow step
    refuse_design_directory(args.work, "--work")
    check_vsg_config(args.vsg_config)
    design = open_directory(args.directory)   # read once, handed to every step
    if not args.no_lint:
        synth.check_lint(design.files, args.vsg_config, start=args.directory)
    check = post_route_check(design, args.model) if args.post_route else None
    with tempfile.TemporaryDirectory(prefix="flann-ice40-") as tmp:
        report = ice40.implement(design, args.device, args.output or ICE40_OUT, work=Path(args.work or tmp),
                                 seed=args.seed, progress=_progress(args), post_route=check)
    if not emit_json(args, report.to_dict()):
        print(report.table())
    for w in report.all_warnings():   # the JSON's "warnings" too
        print(f"warning: {w}", file=sys.stderr)
    return 0


def _progress(args) -> bool:
    """synth's steps on stderr, except under JSON on stdout or --quiet."""
    return not (json_to_stdout(args) or quiet(args))


def run(args) -> int:
    with cores_limited(args.jobs):
        return _run(args)


def _run(args) -> int:
    if args.device is not None and is_ice40(args.device):
        return run_ice40(args)
    if args.post_route:
        raise FlannError(f"--post-route needs an iCE40 part (--device {DEFAULT_ICE40_PART}): the Spartan-II is not "
                         "placed and routed here (its mapped netlist is simulated unless --no-netlist-check)")
    if args.output is not None:
        raise FlannError(f"-o {args.output}: a Spartan-II synthesis writes no files (its figures are printed; "
                         "--work DIR keeps the netlist and logs); -o names the bitstream directory of an iCE40 part")
    if args.device is not None:
        parse_part(args.device)  # refuse a bad part before any slow step
    if args.work and Path(args.work).exists() and not Path(args.work).is_dir():
        raise FlannError(f"--work {args.work}: exists and is not a directory")
    refuse_design_directory(args.work, "--work")
    check_vsg_config(args.vsg_config)
    # read once (a tampered manifest refused before any slow step), handed to every step
    design = open_directory(args.directory)
    if not args.no_lint:
        synth.check_lint(design.files, args.vsg_config, start=args.directory)
    with tempfile.TemporaryDirectory(prefix="flann-synth-") as tmp:
        work = Path(args.work) if args.work else Path(tmp)
        report = synth.synthesize(design, args.device, work=work, progress=_progress(args), abc=args.abc)
        report = dataclasses.replace(report, **_check_netlist(args, design, work / NETLIST))
    if not emit_json(args, report.to_dict()):
        print(report.table())
    for w in report.all_warnings():   # the JSON's "warnings" too
        print(f"warning: {w}", file=sys.stderr)
    if not report.fits:
        print(f"error: {synth.not_fit_message(report)}", file=sys.stderr)
        return 2
    return 0
