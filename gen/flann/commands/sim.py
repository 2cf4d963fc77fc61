"""``flann sim model.json [--json] [--plot OUT.png]``: generate, co-simulate every bench, summarise."""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from ..errors import FlannError
from ..fileio import atomic_write_json
from ..hardware import options as gen_options

HELP = "co-simulate the generated VHDL under GHDL/cocotb"

FIELDS = ("codes_tested", "mismatches", "max_err_lsb", "max_err_mm", "cycles_per_sample",
          "samples_per_s_at_50mhz")


def add_arguments(parser) -> None:
    parser.add_argument("model", help="model.json (flann-model/1)")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON on stdout")
    parser.add_argument("--plot", metavar="OUT.png", default=None,
                        help="HDL vs golden model across the input range and their difference (PNG)")
    parser.add_argument("--build", metavar="DIR", default=None,
                        help="keep generated HDL, logs and results here (default: a temporary directory)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the random stimuli (default %(default)s)")
    parser.add_argument("--summary-json", metavar="FILE", default=None, help="also write the summary here")
    gen_options.add_arguments(parser)


def _progress(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def run(args) -> int:
    from ..verify.runner import plot, simulate

    if args.plot and not args.plot.lower().endswith(".png"):
        raise FlannError(f"--plot {args.plot}: the figure is written as PNG, name it *.png")
    opts = gen_options.from_args(args).to_kwargs()
    with tempfile.TemporaryDirectory(prefix="flann-sim-") as tmp:
        build = Path(args.build) if args.build else Path(tmp)
        res = simulate(args.model, build, options=opts, seed=args.seed, progress=_progress)
        s = res["summary"]
        if args.plot and res["curve"] is not None:
            plot(res["curve"], res["spec"], args.plot)
    if args.summary_json:
        atomic_write_json(args.summary_json, s)
    if args.json:
        print(json.dumps(s, indent=2))
    else:
        print(f"input codes tested      {s['codes_tested']}")
        print(f"bit mismatches vs twin  {s['mismatches']}")
        if s["max_err_lsb"] is not None:
            print(f"max |HDL - float model| {s['max_err_lsb']:.4f} LSB = {s['max_err_mm']:.6f} mm "
                  f"(1 LSB = {s['output_lsb_mm']} mm)")
        print(f"cycles per sample       {s['cycles_per_sample']} (latency {s['latency_cycles']})")
        print(f"samples/s at 50 MHz     {s['samples_per_s_at_50mhz']:.0f}")
        for name, b in s["benches"].items():
            state = "ok" if b["failures"] == 0 and b["tests"] > 0 else f"FAILED {b['failed']}"
            print(f"  bench {name:<11} {b['tests']} test(s) {b['seconds']:>6.1f} s  {state}")
        if args.plot:
            print(f"plot: {args.plot}")
    if not s["all_passed"] or s["mismatches"]:
        if not args.json:
            print("error: co-simulation failed (see the bench lines above)", file=sys.stderr)
        return 1
    return 0
