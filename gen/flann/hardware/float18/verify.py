"""The float18 datapath's verification: its top-level cocotb bench (``benches/test_f18_top.py``,
every input code, pass/fail from cocotb's results file, outputs from the bench's records), the
sweep of its mapped netlist, and the generator fuzz's check of a case drawn on it.

``run_top(model, build_dir, codes=None, **options)`` generates the float18 design of a model,
simulates the given input codes (default: every code) and returns what the HDL produced with
the comparison; ``flann trace --hdl`` and the fuzz use it.
"""

from __future__ import annotations

import json
import traceback
from pathlib import Path

import numpy as np

from ...errors import FlannError
from ...golden.model import FlannModel, load_model, model_sha256
from ...numeric.float18 import FLOAT18
from ...verify import plots
from ...verify.fuzz import window
from ...verify.netlist import top_sweep
from ...verify.plugin import Verification
from ...verify.results import SimResult, summary
from ...verify.runner import run_cocotb
from ..design import Design
from .render import generate
from .spec import FlannF18Top, derive_f18_spec
def run_top(model, build_dir, codes=None, seed: int = 1, stage_codes=(), **options) -> dict:
    """Simulate flann_f18_top; returns codes, HDL out/sat, twin out/sat, mismatches, latency,
    and for ``stage_codes`` the internal stages captured by cocotb compared with the twin's."""
    build_dir = Path(build_dir)
    if isinstance(model, FlannModel):
        fmodel, sha = model, ""
    else:
        fmodel, sha = load_model(model), model_sha256(model)
    fspec = derive_f18_spec(fmodel, model_sha256=sha, **options)
    man = generate(model, build_dir / "hdl", **options)
    return run_files(fspec, man, [build_dir / "hdl" / f for f in man["files"]], build_dir, codes, seed, stage_codes)


def run_design(design, build_dir, codes=None, seed: int = 1, stage_codes=()) -> dict:
    """The float18 design of a directory (:class:`flann.hardware.design.Design`), as written."""
    return run_files(design.spec, design.manifest, design.files, Path(build_dir), codes, seed, stage_codes)


def run_files(fspec, man: dict, files, build_dir: Path, codes=None, seed: int = 1, stage_codes=()) -> dict:
    top = FlannF18Top(fspec)
    codes = top.all_codes() if codes is None else np.asarray(codes, dtype=np.int64)
    out, sat = top.process(codes)
    rec = build_dir / "hdl_outputs.json"
    if rec.exists():
        rec.unlink()
    cfg = {"codes": codes.tolist(), "out": out.tolist(), "sat": sat.tolist(),
           "latency": man["latency_cycles"], "in_bits": man["input_bits"],
           "records": str(rec.resolve()), "stage_codes": [int(c) for c in stage_codes]}
    res = run_cocotb(list(files), man["top"], "test_f18_top",
                     build_dir / "sim_build", cfg, name="float18_top", seed=seed)
    failed = not res.ok
    if not rec.is_file():
        raise FlannError(f"float18 simulation produced no outputs (see {build_dir / 'sim_build'})")
    got = json.loads(rec.read_text())
    hcodes = np.asarray(got["codes"], dtype=np.int64)
    order = np.argsort(hcodes)
    hcodes = hcodes[order]
    hout = np.asarray(got["out"], dtype=np.int64)[order]
    hsat = np.asarray(got["sat"], dtype=bool)[order]
    k = np.argsort(codes)
    mism = int(np.count_nonzero((hout != out[k]) | (hsat != sat[k]))) if hcodes.size == codes.size else None
    stages = None
    if len(stage_codes):
        sc = np.asarray(list(stage_codes), dtype=np.int64)
        tw = top.trace(sc)
        stages = {"codes": int(sc.size), "terms": 0, "products": 0, "sums": 0, "missing": 0}
        for n, c in enumerate(sc):
            h = got["stages"].get(str(int(c)))
            if h is None:
                stages["missing"] += 1
                continue
            for key, arr in (("terms", tw.terms), ("products", tw.products), ("sums", tw.running)):
                want = [int(x) for x in arr[n]]
                stages[key] += int(sum(a != b for a, b in zip(h[key], want)) + abs(len(h[key]) - len(want)))
        stages["all_equal"] = stages["missing"] == 0 and not any(stages[k] for k in ("terms", "products", "sums"))
    return {"codes": hcodes, "out": hout, "sat": hsat, "twin_out": out[k], "twin_sat": sat[k],
            "mismatches": mism, "latency": got["latency"], "bench_failed": failed,
            "manifest": man, "spec": fspec, "stages": stages, "seconds": res.seconds}


def bench(design: Design, build_dir, *, seed=1, **_) -> SimResult:
    r = run_design(design, Path(build_dir), seed=seed)
    codes = r["codes"]
    hdl_mm = FLOAT18.decode_array(r["out"])
    ref = design.spec.float_reference(codes)
    inside = ~r["sat"]
    err = float(np.abs(hdl_mm - ref)[inside].max()) if inside.any() else 0.0
    ok = not r["bench_failed"] and r["mismatches"] == 0 and r["latency"] == [design.manifest["latency_cycles"]]
    secs = r["seconds"]
    benches = {"float18_top": {"tests": 1, "failures": int(r["bench_failed"]), "failed": [],
                               "seconds": round(secs, 1)}}
    s = summary(design, int(codes.size), r["mismatches"], err, benches, ok)
    s["sweep"] = {"engine": "ghdl", "backend": "ghdl", "shards": 1,
                  "codes_per_s": round(codes.size / secs, 1) if secs > 0 else None}
    # the float18 design states no error bound (its spec has no error analysis): no bound line
    curve = plots.curve([{"title": None, "series": [plots.series("", codes, hdl_mm, ref)]}],
                        ref=plots.GOLDEN, simulator="GHDL", unit_mm=True,
                        diff_label="HDL - golden (float18 states no error bound)")
    return SimResult(s, curve, design.spec, ok)


def netlist(design: Design, image=None):
    return top_sweep(design, FlannF18Top(design.spec).process)


def fuzz(model, case, fspec, rng, work: Path, hdl_codes: int):
    """A random window of codes through the top-level bench, bit-exact against the twin."""
    try:
        top = FlannF18Top(fspec)
        codes = top.all_codes()
        lo, hi = window(int(codes[0]), int(codes[-1]), rng, hdl_codes)
        r = run_top(model, work, codes=np.arange(lo, hi + 1), seed=case.index, **case.options)
        case.codes_twin = int(codes.size)
        case.codes_hdl = int(r["codes"].size)
        case.mismatches = r["mismatches"] if r["mismatches"] is not None else hi - lo + 1
        case.outcome = "FAIL" if (case.mismatches or r["bench_failed"]) else "ok"
    except Exception:  # a crash is a finding: record it, go on with the next case
        case.outcome, case.detail = "FAIL", traceback.format_exc(limit=3).strip().splitlines()[-1]
    return case


VERIFICATION = Verification(bench=bench, netlist=netlist, fuzz=fuzz, fuzz_share=0.2)

__all__ = ["VERIFICATION", "bench", "netlist", "fuzz", "run_top", "run_design", "run_files"]
