"""Speed of the exhaustive verification: every input code of a design through the VHDL sweep harness
(GHDL, stimulus and response in VHDL, one shard per core, judged by cocotb against the twin), and
optionally through the Yosys-mapped netlist (Verilator).

Prints codes per second of wall time, the wall time of the whole run (build included) and the
CPU time of the simulator processes.  Target: all 65,536 codes of a 16-bit design in < 60 s wall
on 2 cores.

    .venv/bin/python bench/bench_sim.py [--model data/default_model.json] [--input-bits 12]
        [--engine ghdl|verilator] [--backend llvm|mcode] [--shards N] [--codes N] [--netlist]

engine ghdl: the VHDL under GHDL (sweep harness, cocotb judges each shard); engine verilator:
GHDL's synthesised netlist compiled by Verilator (flann sim --engine verilator), every code.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import tempfile
import time
from pathlib import Path

from flann.verify.design import from_model
from flann.verify.netlist import check_netlist, check_rtl_netlist, compare, sweep_of
from flann.verify.runner import ghdl_backend, sweep
from flann.verify.shards import cores, terminal_progress

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=str(REPO / "data" / "default_model.json"))
    ap.add_argument("--input-bits", type=int, default=12)
    ap.add_argument("--engine", choices=("ghdl", "verilator"), default="ghdl")
    ap.add_argument("--backend", choices=("llvm", "mcode"), default=None, help="GHDL backend (default: fastest installed)")
    ap.add_argument("--shards", type=int, default=None, help="parallel simulations (default: one per core)")
    ap.add_argument("--codes", type=int, default=None, help="only the first N codes (default: every code)")
    ap.add_argument("--netlist", action="store_true", help="also the mapped netlist under Verilator")
    args = ap.parse_args()
    opts = {"input_bits": args.input_bits}
    with tempfile.TemporaryDirectory(prefix="bench-sim-") as tmp:
        design = from_model(args.model, tmp, opts)
        lo = -(1 << (args.input_bits - 1))
        hi = (1 << (args.input_bits - 1)) - 1 if args.codes is None else lo + args.codes - 1
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.monotonic()
        if args.engine == "ghdl":
            r = sweep(design, Path(tmp) / "build", codes=(lo, hi), shards=args.shards,
                      backend=args.backend or ghdl_backend(), progress=terminal_progress("sweep"))
            if not r["bench"].ok:
                raise SystemExit(f"sweep failed: {r['bench'].failed_tests}")
            how = f"ghdl-{r['backend']}"
        else:
            r = check_rtl_netlist(design, Path(tmp) / "rtl", progress=terminal_progress("verilator"))
            how = "verilator (ghdl --synth netlist)"
        wall = time.monotonic() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        n = int(r["codes"].size)
        res = compare(sweep_of(design), r) if args.codes is None else None
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        out = {
            "design": {"input_bits": args.input_bits, "cycles_per_sample": design.manifest["cycles_per_sample"]},
            "codes": n, "mismatches_vs_twin": res.mismatches if res else None,
            "engine": how, "shards": r["shards"], "cores": cores(),
            "sim_wall_s": round(r["seconds"], 2), "codes_per_s": round(n / r["seconds"], 1),
            "build_s": round(r["build_seconds"], 2), "total_wall_s": round(wall, 2),
            "cpu_s": round(cpu, 2), "codes_per_cpu_s": round(n / cpu, 1) if cpu else None,
            "load_average_1min": round(os.getloadavg()[0], 2),
        }
        if args.netlist:
            nl = check_netlist(design, Path(tmp) / "netlist", progress=terminal_progress("netlist"))
            out["netlist"] = {"codes_tested": nl.codes_tested, "mismatches": nl.mismatches,
                              "seconds": round(nl.seconds, 2), "run_seconds": round(nl.run_seconds, 2),
                              "simulator": nl.simulator, "codes_per_s": round(nl.codes_tested / nl.run_seconds, 1)}
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
