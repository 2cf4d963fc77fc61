"""``flann sim MODEL|DIR [--netlist] [--json] [--plot OUT.png]``: verify a design by simulation.

MODEL: generate with the flags given, then verify.  DIR: verify exactly the design in DIR (its own
VHDL files; the twin rebuilt from the manifest and ``--model``).  Every input code goes through
the VHDL sweep harness (GHDL, one shard per core), the reactive and block benches run under
cocotb; ``--netlist`` also simulates the Yosys-mapped Spartan-II netlist over every code.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from ..argtypes import TOOL_SEED, png_path
from ..errors import FlannError
from ..hardware.manifest import refuse_design_directory
from ..fileio import atomic_write_json, check_output_directory
from ..hardware.family.images import IMAGE_FILE
from ..hardware.target import DEFAULT_ICE40_PART, parse_ice40
from ..implement import ice40
from ..hardware.design import is_design_dir, open_design
from ..verify.datapaths import simulate
from ..verify.netlist import require_sweep_driver
from ..verify.post_route import checker
from ..verify.plots import plot
from ..verify.runner import ENGINES
from ..verify.shards import terminal_progress
from ..hardware import options as gen_options
from .common import add_common, cores_limited, emit_json, json_to_stdout, quiet
from .gen import generator_options, refuse_generator_options

HELP = "verify the generated VHDL by simulation (GHDL + cocotb; --netlist: post-synthesis netlist)"

FIELDS = ("codes_tested", "mismatches", "max_err_lsb", "max_err_mm", "cycles_per_sample",
          "samples_per_s", "clock_hz", "samples_per_s_at_50mhz", "clock_nominal", "clock_checked_by")

# sim runs no timing analysis: its throughput is at the clock the design is written for, which
# the design may not reach (a float18 design does not reach 50 MHz on a Spartan-II)
CLOCK_CHECK = "flann synth"


def clock_fields() -> dict:
    """What the summary's clock_hz and samples_per_s are: the nominal clock, checked elsewhere."""
    return {"clock_nominal": True, "clock_checked_by": CLOCK_CHECK}


def throughput_line(s: dict) -> str:
    label = "samples/s at " + format(s["clock_hz"] / 1e6, "g") + " MHz"
    return (f"{label:<24}{s['samples_per_s']:.0f} at the design's nominal clock, not a timing result "
            f"({s['clock_checked_by']} estimates the design's Fmax)")


def add_arguments(parser) -> None:
    parser.add_argument("model", metavar="MODEL|DIR",
                        help="model.json (flann-model/1; generated with the flags below) or a design "
                             "directory written by flann gen -o DIR (verified as it is)")
    parser.add_argument("--model", dest="design_model", metavar="MODEL.json", default=None,
                        help="with DIR: the model DIR was generated from (checked against the manifest's sha256)")
    parser.add_argument("--netlist", action="store_true",
                        help="also synthesise (GHDL + Yosys synth_xilinx -family xcv) and simulate the mapped "
                             "netlist over every input code (Verilator, Yosys's Xilinx cell models); a family "
                             "design's with the last --image (else the last weight image it keeps) loaded through "
                             "cfg_*; a design with temperature at its sweep's temperature codes")
    parser.add_argument("--post-route", action="store_true",
                        help="also place and route on an iCE40 (--post-route-device) and simulate the routed design "
                             "over every input code (icebox_vlog + Verilator, Yosys's iCE40 cell models)")
    parser.add_argument("--post-route-device", metavar="PART", default=DEFAULT_ICE40_PART,
                        help="iCE40 part for --post-route (default %(default)s)")
    parser.add_argument("--engine", choices=ENGINES, default="auto",
                        help="every input code through: ghdl = the VHDL under GHDL; verilator = GHDL's "
                             "synthesised netlist compiled by Verilator (~25x faster), the VHDL on a sample; "
                             "auto (default) = ghdl when that takes about a minute or less, else verilator")
    parser.add_argument("--plot", metavar="OUT.png", default=None, type=png_path,
                        help="HDL vs golden model (a family design: the bit-true twin of each weight image) "
                             "across the input range, at several temperature codes for a design with "
                             "temperature, and their difference (PNG)")
    parser.add_argument("--build", metavar="DIR", default=None,
                        help="keep generated HDL, logs and results here (default: a temporary directory)")
    parser.add_argument("--seed", type=TOOL_SEED, default=1,
                        help="seed of the random stimuli and of --post-route's placement (default %(default)s)")
    parser.add_argument("--image", action="append", metavar="HEX", default=None,
                        help="a family design: a sensor's weight image (flann calibrate) to load through the "
                             "cfg port, each simulated (one alone, on a family without temperature: loaded over an "
                             "image the design keeps, so that the load is seen to change the outputs; "
                             "default: the images flann gen kept in DIR, for a design with temperature its last)")
    # before --json FILE: kept for the scripts that write the file and print the JSON too
    parser.add_argument("--summary-json", metavar="FILE", default=None, help=argparse.SUPPRESS)
    add_common(parser, json="the summary", jobs="simulation shards")
    gen_options.add_arguments(parser)


def image_names(paths) -> list[dict]:
    """{name, hex} per --image: the file's stem, or its folder and stem where stems repeat or
    the stem is calibrate's (it writes every sensor's image under one name, in the sensor's
    own folder: the folder names the sensor)."""
    files = [Path(h).resolve() for h in paths]
    stems = [f.stem for f in files]
    generic = Path(IMAGE_FILE).stem
    names = [f"{f.parent.name}/{f.stem}" if stems.count(f.stem) > 1 or f.stem == generic else f.stem
             for f in files]
    names = [str(f) if names.count(n) > 1 else n for f, n in zip(files, names)]
    if len(set(names)) < len(names):
        twice = next(n for n in names if names.count(n) > 1)
        raise FlannError(f"--image {twice}: given twice; give different sensors' images")
    return [{"name": n, "hex": str(f)} for n, f in zip(names, files)]


def run(args) -> int:
    opts, given = generator_options(args)
    opts = opts.to_kwargs()
    if is_design_dir(args.model):
        refuse_generator_options(args.model, args, given, "simulated")
    if args.build:
        # a file (or FIFO) where the build directory goes: one line now, not a traceback later;
        # a directory already holding files (an earlier build) is reused
        check_output_directory(args.build, lambda _earlier: True, "build directory")
        refuse_design_directory(args.build, "--build")
    if args.post_route:
        parse_ice40(args.post_route_device)  # refuse a bad part before any slow step
    t0 = time.monotonic()
    with cores_limited(args.jobs), tempfile.TemporaryDirectory(prefix="flann-sim-") as tmp:
        build = Path(args.build).resolve() if args.build else Path(tmp)
        design = open_design(args.model, build, opts, model=args.design_model)
        if args.post_route:
            require_sweep_driver(design.datapath, args.model)
        images = image_names(args.image or [])
        res = simulate(design, build, seed=args.seed, netlist=args.netlist, engine=args.engine,
                       progress=None if quiet(args) else terminal_progress, images=images or None)
        verdict = res.verdict()
        s = {**res.summary, **clock_fields(), "verdict": verdict.to_json()}
        if args.post_route:
            # a family design's routed netlist computes with the last image given, as its bench ends
            check = checker(design, image=images[-1] if images else None)
            rep = ice40.implement(design.directory, args.post_route_device, build / "ice40", work=build / "ice40_work",
                                  seed=args.seed, progress=not (json_to_stdout(args) or quiet(args)),
                                  post_route=check)
            s["post_route"] = {**rep.post_route, "device": rep.part.name, "fmax_mhz": rep.fmax_mhz,
                               "timing_met": rep.timing_met}
        plotted = bool(args.plot and res.curve is not None)
        if plotted:
            plot(res.curve, design.manifest, args.plot)
        # a design generated into the temporary directory is gone when the command returns
        temporary = Path(tmp).resolve() in design.directory.parents
        if temporary:
            s["design"] = None
    s["seconds"] = round(time.monotonic() - t0, 1)   # the whole command: generation, builds, benches
    if args.summary_json:
        atomic_write_json(args.summary_json, s)
    if not emit_json(args, s):
        where = s["design"] or "generated in a temporary directory (deleted); keep it with --build DIR"
        print(f"design                  {where}")
        sw = s.get("sweep") or {}
        how = sw.get("backend") or "Verilator on GHDL's synthesised netlist"
        print(f"input codes tested      {s['codes_tested']}"
              + (f" ({sw['codes_per_s']} codes/s, {how}, {sw['shards']} shard(s))" if sw.get("codes_per_s") else
                 f" ({how})" if sw else ""))
        if sw.get("vhdl_sample"):
            print(f"  VHDL under GHDL       {sw['vhdl_sample']['codes']} codes (sample)")
        print(f"bit mismatches vs twin  {s['mismatches']}")
        if isinstance(s.get("chain"), dict):
            c = s["chain"]
            print(f"  whole chain           {c['samples']} strobes of {c['source']}: {c['windows']} displacement "
                  f"codes, {c['mismatches']} mismatches, {'/'.join(map(str, c['latency_cycles'] or []))} clocks "
                  "after their window")
        if s["max_err_lsb"] is not None:
            print(f"max |HDL - float model| {s['max_err_lsb']:.4f} LSB = {s['max_err_mm']:.6f} mm "
                  f"(1 LSB = {s['output_lsb_mm']} mm)")
        elif s["max_err_mm"] is not None:
            print(f"max |HDL - float model| {s['max_err_mm']:.6f} mm")
        if isinstance(s.get("temperature_codes"), list):
            print(f"temperature codes       {len(s['temperature_codes'])} x every voltage code: "
                  f"{', '.join(map(str, s['temperature_codes']))}")
        if s.get("images"):
            per = s.get("image_mismatches") or {}
            names = [f"{n} ({per[n]} mismatches)" if per.get(n) is not None else n for n in s["images"]]
            print(f"weight images           {', '.join(names)} (through the cfg port)")
        print(f"cycles per sample       {s['cycles_per_sample']} (latency {s['latency_cycles']})")
        print(throughput_line(s))
        for name, b in s["benches"].items():
            state = "ok" if b["failures"] == 0 and b["tests"] > 0 else f"FAILED {b['failed']}"
            secs = f"{b['seconds']:>6.1f} s" if b["seconds"] is not None else ""
            print(f"  bench {name:<11} {b['tests']} test(s) {secs}  {state}")
        if "netlist" in s:
            n = s["netlist"]
            what = (f"samples ({n['temperature_codes']} temperature codes)" if n.get("temperature_codes")
                    else "codes")
            print(f"netlist (Yosys xcv)     {n['codes_tested']} {what}, {n['mismatches']} mismatches "
                  f"({n['simulator']}, {n['seconds']:.0f} s)")
        if "post_route" in s:
            n = s["post_route"]
            print(f"post-route ({n['device']})  {n['codes_tested']} codes, {n['mismatches']} mismatches "
                  f"(Fmax {n['fmax_mhz']:.1f} MHz, {n['seconds']:.0f} s)")
        if plotted:
            print(f"plot: {args.plot}")
        print(f"simulated in {s['seconds']:.0f} s")
        print(verdict.line())
    if args.plot and not plotted:
        print(f"{args.plot}: not written, the simulation gave no outputs to plot", file=sys.stderr)
    # on stderr with --json too: a script sees why beside the exit code, its JSON stays clean
    if s.get("post_route", {}).get("mismatches"):
        print("error: the placed-and-routed design disagrees with its twin", file=sys.stderr)
        return 1
    if not res.passed or s["mismatches"]:
        why = [f"bench {name}: {', '.join(b['failed']) or 'failed'}" for name, b in s.get("benches", {}).items()
               if b.get("failures")]
        if s["mismatches"]:
            why.append(f"{s['mismatches']} mismatches with the twin")
        if (s.get("netlist") or {}).get("mismatches"):
            why.append(f"mapped netlist: {s['netlist']['mismatches']} mismatches")
        print(f"error: co-simulation failed ({'; '.join(why) or 'see the summary'})", file=sys.stderr)
        return 1
    return 0
