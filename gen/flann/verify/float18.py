"""Run the float18 top-level cocotb bench (``benches/test_f18_top.py``) through the one runner.

``run_top(model, build_dir, codes=None, **options)`` generates the float18 design,
computes the twin's outputs, simulates the given input codes (default: every code) and
returns what the HDL produced with the comparison; pass/fail comes from cocotb's results
file, the outputs from the bench's records.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import FlannError
from .runner import run_cocotb
from ..hardware.float18.render import generate
from ..hardware.float18.spec import FlannF18Top, derive_f18_spec
from ..golden.model import FlannModel, load_model, model_sha256


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


__all__ = ["run_top", "run_design", "run_files"]
