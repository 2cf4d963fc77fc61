"""Speed of the exhaustive top-level co-simulation (every input code of the default design).

Prints input codes per second of wall time and per CPU second for cocotb's `top_every_code` test (GHDL mcode,
VHDL clock harness, one Python wake-up per sample) and the simulated clock rate.

    .venv/bin/python bench/bench_sim.py [--model data/default_model.json] [--codes all|N] [--lut]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import tempfile
from pathlib import Path

from flann.hardware.fixed.render import generate
from flann.verify.runner import run_bench

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=str(REPO / "data" / "default_model.json"))
    ap.add_argument("--codes", default="all", help="'all' or a number of random codes")
    ap.add_argument("--mult-style", default="shiftadd", choices=("shiftadd", "lut"))
    ap.add_argument("--lanes", type=int, default=1)
    args = ap.parse_args()
    opts = {"mult_style": args.mult_style, "lanes": args.lanes}
    with tempfile.TemporaryDirectory(prefix="bench-sim-") as tmp:
        man = generate(args.model, Path(tmp) / "hdl", **opts)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        r = run_bench(Path(tmp) / "hdl", "top", model=args.model, options=opts, build_dir=Path(tmp) / "build",
                      testcase="top_every_code", extra={"codes": args.codes})
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if not r.ok:
        raise SystemExit(f"bench failed: {r.failed_tests}")
    rec = r.records["top_every_code"]
    n = len(rec["codes"])
    sec = r.test_seconds["top_every_code"]
    cycles = rec["sim_time_ns"] / 10.0
    out = {
        "design": opts, "codes": n, "cycles_per_sample": man["cycles_per_sample"],
        "test_wall_s": round(sec, 2), "codes_per_s": round(n / sec, 1),
        "sim_cycles_per_s": round(cycles / sec), "run_wall_s_incl_compile": round(r.seconds, 2),
        # CPU time of the GHDL (+ embedded Python) processes: independent of other jobs' load
        "run_cpu_s_incl_compile": round(cpu, 2), "codes_per_cpu_s": round(n / cpu, 1),
        "load_average_1min": round(os.getloadavg()[0], 2),
    }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
