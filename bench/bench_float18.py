"""Resources and accuracy of the fixed and float18 designs side by side.

    .venv/bin/python bench/bench_float18.py [MODEL] [--device PART]

Generates both designs for MODEL (default data/default_model.json) with the generators'
default options, measures each with the `flann synth` flow (GHDL synthesis + Yosys
synth_xilinx -family xcv), also each float18 block alone, and takes the accuracy from
`flann trace` over every input code (the float18 row is `flann.analysis.explore_float18.measure`).
Prints a table (samples/s at the clock each design meets by the timing estimate); about
20 s to 3 min on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

from flann.implement import synth
from flann.hardware.float18.render import generate as generate_f18
from flann.hardware.fixed.render import generate as generate_fixed
from flann.golden.model import load_model
from flann.hardware.target import CLOCK_HZ
from flann.analysis.trace import run_trace
from flann.implement.timing import safe_clock_mhz


def clock_mhz(report) -> float:
    """The clock the design runs at: the design's, or the estimate's safe clock below it."""
    t = report.timing
    return CLOCK_HZ / 1e6 if t is None or t.meets(CLOCK_HZ) else min(CLOCK_HZ / 1e6, safe_clock_mhz(t))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model", nargs="?", default="data/default_model.json")
    ap.add_argument("--device", default="xc2s200-pq208-5")
    args = ap.parse_args()
    model = load_model(args.model)
    rows = []
    with tempfile.TemporaryDirectory(prefix="f18res") as tmp:
        tmp = Path(tmp)
        designs = {"fixed": generate_fixed(args.model, tmp / "fixed"),
                   "float18": generate_f18(args.model, tmp / "float18")}
        for fmt, man in designs.items():
            print(f"synthesising {fmt} ...", file=sys.stderr)
            report = synth.synthesize(tmp / fmt, args.device, progress=False)
            tr = run_trace(model, fmt)
            rows.append((fmt, man["top"], report.to_dict(), man["cycles_per_sample"], tr, clock_mhz(report)))
        blocks = []
        for b in ("flann_f18_cvt", "flann_f18_mul", "flann_f18_add"):
            d = tmp / b
            d.mkdir()
            (d / f"{b}.vhd").write_text((tmp / "float18" / f"{b}.vhd").read_text())
            (d / "manifest.json").write_text(json.dumps({"top": b, "files": [f"{b}.vhd"]}))
            blocks.append((b, synth.synthesize(d, args.device, progress=False).to_dict()))
    print(f"model {args.model}, device {args.device}, every input code")
    print(f"{'format':<8} {'top':<14} {'LUT4':>5} {'FF':>5} {'BRAM':>4} {'cyc/sample':>10} {'clock MHz':>9} "
          f"{'samples/s':>10} {'max err mm':>10} {'rms err mm':>10}  dominant stage")
    for fmt, top, rep, cyc, tr, mhz in rows:
        print(f"{fmt:<8} {top:<14} {rep['luts']:>5} {rep['ffs']:>5} {rep['brams']:>4} {cyc:>10} {mhz:>9g} "
              f"{mhz * 1e6 / cyc:>10.0f} {tr.total['max_mm']:>10.3g} {tr.total['rms_mm']:>10.3g}  "
              f"{tr.dominant['stage']}")
    print(f"clock: the design's {CLOCK_HZ / 1e6:g} MHz, or the timing estimate's safe clock below it "
          "(as flann ise writes the PERIOD)")
    print("float18 blocks alone:")
    for b, rep in blocks:
        print(f"  {b:<14} {rep['luts']:>5} LUT4 {rep['ffs']:>4} FF")
    return 0


if __name__ == "__main__":
    sys.exit(main())
