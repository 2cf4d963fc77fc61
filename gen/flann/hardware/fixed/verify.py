"""The fixed-point datapath's verification: its sweep harness and benches (``flann sim``), the
sweep of its mapped netlist, and the generator fuzz's check of a case drawn on it."""

from __future__ import annotations

import traceback
from pathlib import Path

import numpy as np

from ...errors import FlannError
from ...verify.fuzz import window
from ...verify.netlist import top_sweep
from ...verify.plugin import Verification
from ...verify.results import SimResult
from ...verify.runner import simulate, sweep
from ..design import Design
from ..manifest import Manifest
from .render import write
from .twin import FlannTop


def bench(design: Design, build_dir, *, seed=1, engine="auto", progress=None, **_) -> SimResult:
    return SimResult.from_summary(**simulate(design, build_dir, seed=seed, engine=engine, progress=progress))


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

__all__ = ["VERIFICATION", "bench", "netlist", "fuzz", "fuzz_options"]
