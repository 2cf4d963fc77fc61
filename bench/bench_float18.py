"""Resources and accuracy of the fixed and float18 designs side by side.

    .venv/bin/python bench/bench_float18.py [MODEL] [--device PART]

Generates both designs for MODEL (default data/default_model.json) with the generators'
default options, measures each with the `flann synth` flow (GHDL synthesis + Yosys
synth_xilinx -family xcv), also each float18 block alone, and takes the accuracy from
`flann trace` over every input code (the float18 row is `flann.hardware.float18.analysis.measure`).
Prints a table (samples/s at the clock each design meets by the timing estimate); about
20 s to 3 min on 2 cores.

    .venv/bin/python bench/bench_float18.py --estimate-vs-synth RECORDING [--work DIR]

The float18 resource estimate (the one `flann ise` refuses or recommends a part by) against
`flann synth` on a grid of float18 designs: models trained on RECORDING with --terms 5, 11,
25, 51 (lms) and --terms auto, generated at --input-bits 8, 10, 12.  Prints estimate and
measured LUT4 / FF / BRAM per design and per entity, and the ratios.  Designs and synth
reports are kept in --work (re-used on a second run); about 7 min on 2 shared cores.
"""

from __future__ import annotations

import argparse
import json
import subprocess
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


GRID_TERMS = ("5", "11", "25", "51", "auto")
GRID_BITS = (8, 10, 12)
# designs the estimate was not fitted to: other input widths, and the repository's model
CHECKS = (("25", 9), ("auto", 11), ("default", 12), ("default", 10))


def _flann(*args) -> str:
    return subprocess.run([str(Path(sys.executable).with_name("flann")), *map(str, args)], check=True,
                          capture_output=True, text=True).stdout


def estimate_vs_synth(recording: str, work: Path, device: str) -> int:
    """Estimate against `flann synth` for every design of the grid (see the module docstring)."""
    from flann.hardware.registry import read_design
    work.mkdir(parents=True, exist_ok=True)
    rows = []
    for design in [(t, b) for t in GRID_TERMS for b in GRID_BITS] + [None] + list(CHECKS):
        if design is None:   # the rest: designs the estimate was not fitted to
            rows.append(None)
            continue
        terms, bits = design
        model = Path("data/default_model.json") if terms == "default" else work / f"m_{terms}.json"
        if not model.exists():
            print(f"training --terms {terms} ...", file=sys.stderr)
            how = (["--input-bits", "12", "--input-lsb-v", str(5 / 4096)] if terms == "auto"
                   else ["--method", "lms"])
            _flann("train", recording, "-o", model, "--terms", terms, *how)
        d, rep = work / f"f_{terms}_{bits}", work / f"synth_{terms}_{bits}.json"
        if not d.exists():
            _flann("gen", model, "-o", d, "--input-bits", bits, "--format", "float18")
        if not rep.exists():
            print(f"synthesising {d.name} ...", file=sys.stderr)
            rep.write_text(_flann("synth", d, "--device", device, "--json", "--no-netlist-check"))
        man, dp = read_design(d)
        rows.append((terms, bits, man["spec"], dp.estimate(man), json.loads(rep.read_text())))
    print(f"float18 estimate vs flann synth ({device}, GHDL + Yosys synth_xilinx, abc full); recording {recording}")
    print(f"{'terms':>5} {'bits':>4} {'P':>3} {'T':>3} | {'est LUT':>7} {'syn LUT':>7} {'ratio':>5} | "
          f"{'est FF':>6} {'syn FF':>6} | {'est BR':>6} {'syn BR':>6} | synth LUT4 per entity")
    ratios = []
    for row in rows:
        if row is None:
            print("not fitted to (other input widths; default: data/default_model.json):")
            continue
        terms, bits, s, est, rep = row
        r = est["luts"] / rep["luts"]
        ratios.append(r)
        ent = " ".join(f"{k.removeprefix('flann_')}={v['luts']}" for k, v in sorted(rep["entities"].items()))
        print(f"{s['terms']:>5} {bits:>4} {s['phase_bits']:>3} {s['term'].split('<')[1].split(',')[0]:>3} | "
              f"{est['luts']:>7} {rep['luts']:>7} {r:>5.2f} | {est['ffs']:>6} {rep['ffs']:>6} | "
              f"{est['brams']:>6} {rep['brams']:>6} | {ent}")
    print(f"LUT4 estimate / synth: {min(ratios):.2f} .. {max(ratios):.2f} over {len(ratios)} designs")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model", nargs="?", default="data/default_model.json")
    ap.add_argument("--device", default="xc2s200-pq208-5")
    ap.add_argument("--estimate-vs-synth", metavar="RECORDING",
                    help="compare the float18 resource estimate with flann synth on a grid of designs")
    ap.add_argument("--work", default="bench_float18_work", help="--estimate-vs-synth: designs and reports")
    args = ap.parse_args()
    if args.estimate_vs_synth:
        return estimate_vs_synth(args.estimate_vs_synth, Path(args.work), args.device)
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
