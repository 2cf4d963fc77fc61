"""The fixed-point datapath's verification: its sweep harness (every code), its reactive benches
(handshake gaps, reset mid sample, saturation) and block benches (``flann sim``), the sweep of
its mapped netlist, and the generator fuzz's check of a case drawn on it."""

from __future__ import annotations

import sys
import traceback
from pathlib import Path

import numpy as np

from ...errors import FlannError
from ...verify.fuzz import window
from ...verify.netlist import top_sweep
from ...verify.plugin import Verification
from ...verify.results import SimResult
from ...verify import plots
from ...verify.benches import CLK_NS
from ...verify.netlist import check_rtl_netlist
from ...verify.runner import (BenchResult, bench_config, choose_engine, run_cocotb, simulator_name, sources, sweep,
                              throughput)
from ..design import Design
from ..manifest import Manifest
from .render import write
from .twin import FlannTop

# bench name -> (toplevel entity, cocotb module in flann.verify.benches, testcase filter)
BENCHES = {
    "sweep": ("flann_sweep", "test_sweep", None),  # every code, stimulus and response in VHDL
    "top": ("flann_harness", "test_top", None),   # reactive: gaps, reset mid sample, saturation
    "norm": ("flann_norm", "test_blocks", "norm_vs_twin"),
    "expansion": ("flann_expansion", "test_blocks", "expansion_vs_twin"),
    "multiplier": ("flann_multiplier", "test_blocks", "multiplier_vs_twin"),
    "adder": ("flann_adder", "test_blocks", "adder_vs_twin"),
}


def run_bench(design: Design, bench: str, build_dir, *, seed: int = 1, testcase: str | None = None,
              extra: dict | None = None, backend: str | None = None) -> BenchResult:
    """Run one bench (key of BENCHES, not the sweep) on ``design``; never raises on test failure."""
    if bench not in BENCHES or bench == "sweep":
        raise FlannError(f"bench {bench!r}: must be one of {', '.join(b for b in BENCHES if b != 'sweep')}")
    toplevel, module, tc = BENCHES[bench]
    man = design.manifest
    params, plus = {}, []
    if toplevel == "flann_harness":
        params = {"in_bits_g": man["input_bits"], "out_bits_g": man["output_bits"], "half_ns_g": CLK_NS // 2}
        # the harness's clock never stops: bound the run (a test still running is reported failed)
        n = 3 * int((extra or {}).get("handshake_samples", 60)) + 80
        plus.append(f"--stop-time={(n * man['cycles_per_sample'] * 3 + 10000) * CLK_NS}ns")
    cfg = {**bench_config(design), **(extra or {}), "harness": toplevel == "flann_harness"}
    return run_cocotb(sources(design, toplevel), toplevel, module, Path(build_dir) / bench, cfg, name=bench,
                      parameters=params, plusargs=plus, testcase=testcase or tc, seed=seed, backend=backend)


def _every_code(design: Design, build_dir: Path, engine: str, progress) -> tuple[dict, dict]:
    """Every input code: (the VHDL sweep's result, the outputs of every code with a description).

    engine "ghdl": the VHDL itself under GHDL, every code.  engine "verilator": every code through
    GHDL's synthesis of the VHDL compiled by Verilator (the netlist Yosys maps), and the VHDL
    under GHDL on a sample (random windows, the clamp edges, both ends of the range), so the
    compiled netlist is tied to the VHDL's own simulation on every run.
    """
    man = design.manifest
    engine = choose_engine(design, engine)
    if engine == "ghdl":
        sw = sweep(design, build_dir, progress=progress("sweep") if progress else None)
        about = {"engine": "ghdl", "backend": f"ghdl-{sw['backend']}", "shards": sw["shards"],
                 "seconds": round(sw["seconds"], 1), "build_seconds": round(sw["build_seconds"], 1),
                 "codes_per_s": round(sw["codes"].size / sw["seconds"], 1) if sw["seconds"] else None}
        return sw, {**{k: sw[k] for k in ("codes", "data", "sat", "latency")}, "about": about}
    nl = check_rtl_netlist(design, build_dir / "rtl_netlist", progress=progress("sweep") if progress else None)
    lo, hi = int(nl["codes"].min()), int(nl["codes"].max())
    rng = np.random.default_rng(int(man["model_sha256"][:8], 16) if man.get("model_sha256") else 1)
    c_lo, c_hi = man["clamp_codes"]
    sample = {lo, lo + 1, hi - 1, hi, -1, 0, 1}
    sample |= {c + d for c in (c_lo, c_hi) for d in range(-3, 4)}
    sample |= {int(c) for c in rng.integers(lo, hi + 1, 200)}
    sw = sweep(design, build_dir, codes=sorted(c for c in sample if lo <= c <= hi))
    about = {"engine": "verilator", "netlist": "ghdl --synth --out=verilog (repaired), Verilator",
             "shards": nl["shards"], "seconds": round(nl["seconds"], 1), "build_seconds": round(nl["build_seconds"], 1),
             "codes_per_s": round(nl["codes"].size / nl["seconds"], 1) if nl["seconds"] else None,
             "vhdl_sample": {"codes": int(sw["codes"].size), "backend": f"ghdl-{sw['backend']}",
                             "bench_ok": sw["bench"].ok}}
    return sw, {**{k: nl[k] for k in ("codes", "data", "sat", "latency")}, "about": about}


def bench(design: Design, build_dir, *, seed: int = 1, benches=tuple(BENCHES), engine: str = "auto",
          progress=None, **_) -> SimResult:
    """Verify ``design`` (flann sim): every input code (engine ghdl: the VHDL under GHDL; verilator:
    GHDL's synthesised netlist compiled, plus the VHDL on a sample), the other benches."""
    build_dir = Path(build_dir)
    spec, man = design.spec, design.manifest
    results, summary = [], {
        "codes_tested": 0, "mismatches": None, "max_err_lsb": None, "max_err_mm": None,
        "cycles_per_sample": man["cycles_per_sample"], **throughput(man["cycles_per_sample"]),
    }
    curve = None
    for b in benches:
        if b == "sweep":
            sw, every = _every_code(design, build_dir, engine, progress)
            results.append(sw["bench"])
            codes, data, sat = every["codes"], every["data"], every["sat"]
            if codes.size:
                twin_out, twin_sat = design.twin().process(codes)
                ref = spec.float_reference(codes) / spec.output_lsb_mm
                err = np.abs(data - ref)
                bad = (data != twin_out) | (sat != twin_sat) | (every["latency"] != man["latency_cycles"])
                summary.update(codes_tested=int(codes.size), mismatches=int(np.count_nonzero(bad)),
                               max_err_lsb=round(float(err.max()), 4),
                               max_err_mm=round(float(err.max()) * spec.output_lsb_mm, 6))
                curve = plots.curve([{"title": None, "series": [plots.series("", codes, data, ref)]}],
                                    ref=plots.GOLDEN, simulator=simulator_name(every["about"]),
                                    bound={"value": 1.0, "label": "±1 output LSB"})
            summary["sweep"] = every["about"]
        else:
            if progress and sys.stderr.isatty():
                print(f"simulating {b} ...", file=sys.stderr, flush=True)
            results.append(run_bench(design, b, build_dir, seed=seed))
    summary["benches"] = {r.bench: {"tests": r.tests, "failures": r.failures, "failed": r.failed_tests,
                                    "seconds": round(r.seconds, 1)} for r in results}
    summary["all_passed"] = all(r.ok for r in results)
    summary["latency_cycles"] = man["latency_cycles"]
    summary["output_lsb_mm"] = man["output_lsb_mm"]
    summary["model_sha256"] = man["model_sha256"]
    summary["design"] = str(design.directory)
    return SimResult(summary, curve, spec, summary["all_passed"], max(1.0, float(spec.analysis["bound_total_lsb"])))


def netlist(design: Design, image=None):
    return top_sweep(design, FlannTop(design.spec).process)


def fuzz_options(rng) -> dict:
    """The fixed datapath's own generator options, drawn at random."""
    opts = {"lanes": int(rng.choice([1, 1, 2, 3])), "mult_style": str(rng.choice(["shiftadd", "lut"]))}
    if opts["mult_style"] == "shiftadd":
        opts["mult_digit_bits"] = int(rng.choice([1, 2, 4]))
    if rng.random() < 0.5:
        opts["output_bits"] = int(rng.choice([14, 16, 18, 20]))
    opts["check_device"] = False  # verify every datapath, not only those that fit a part
    return opts


def fuzz(model, case, spec, rng, work: Path, hdl_codes: int):
    """The twin over every code within the spec's stated bound of the float model; the sweep
    harness on a random window and the clamp edges, bit-exact against the twin."""
    try:
        top = FlannTop(spec)
        codes = top.all_codes()
        out, _ = top.process(codes)
        err = np.abs(out - spec.float_reference(codes) / spec.output_lsb_mm)
        case.codes_twin = int(codes.size)
        case.max_err_lsb = round(float(err.max()), 4)
        case.bound_lsb = round(max(1.0, float(spec.analysis["bound_total_lsb"])), 4)
        man = write(spec, work / "hdl")
        model.save(work / "model.json")
        design = Design((work / "hdl").resolve(), Manifest.written(work / "hdl", man), (work / "model.json").resolve(),
                        case.options, spec)
        windows = [window(spec.code_min, spec.code_max, rng, hdl_codes),
                   (max(spec.code_min, spec.clamp_lo - 2), min(spec.code_max, spec.clamp_lo + 2)),
                   (max(spec.code_min, spec.clamp_hi - 2), min(spec.code_max, spec.clamp_hi + 2))]
        sample = sorted({c for a, b in windows for c in range(a, b + 1)})
        r = sweep(design, work / "build", codes=sample, shards=1)
        total = len(sample)
        want_out, want_sat = top.process(r["codes"])
        case.mismatches = int(np.count_nonzero((r["data"] != want_out) | (r["sat"] != want_sat)))
        case.mismatches += total - int(r["codes"].size)
        if not r["bench"].ok:
            case.mismatches = max(case.mismatches, 1)
            case.detail = f"sweep bench failed: {r['bench'].failed_tests}"
        case.codes_hdl = total
        bad = case.max_err_lsb > case.bound_lsb + 1e-9 or case.mismatches
        case.outcome = "FAIL" if bad else "ok"
        if case.max_err_lsb > case.bound_lsb + 1e-9:
            case.detail = f"twin {case.max_err_lsb} LSB from the float model > bound {case.bound_lsb}"
    except FlannError as exc:
        case.outcome, case.detail = "FAIL", f"after a valid spec: {exc}"
    except Exception:  # a crash is a finding: record it, go on with the next case
        case.outcome, case.detail = "FAIL", traceback.format_exc(limit=3).strip().splitlines()[-1]
    return case


VERIFICATION = Verification(bench=bench, netlist=netlist, fuzz=fuzz, fuzz_share=0.8, fuzz_options=fuzz_options,
                            engines=("ghdl", "verilator"))

__all__ = ["VERIFICATION", "BENCHES", "run_bench", "bench", "netlist", "fuzz", "fuzz_options"]
