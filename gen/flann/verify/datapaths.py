"""``flann sim DIR`` for every datapath: the datapath names its bench, this runs it.

One entry per bench a :class:`~flann.hardware.datapath.Datapath` may name (``bench``): the
fixed datapath's sweep harness and benches (:func:`flann.verify.runner.simulate`), the float18
top-level bench, the family bench (sensors' weight images through the cfg port).  A datapath
without a bench is refused in one line saying why.  Every entry returns {"summary", "curve", "spec"}.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import FlannError
from ..numeric.float18 import FLOAT18
from .design import Design
from .float18 import run_design
from .runner import run_family_bench, simulate as simulate_fixed, throughput


def _summary(design: Design, codes: int, mismatches, max_err_mm, benches: dict, ok: bool, lsb=None) -> dict:
    man = design.manifest
    return {"codes_tested": codes, "mismatches": mismatches,
            "max_err_lsb": round(max_err_mm / lsb, 4) if (lsb and max_err_mm is not None) else None,
            "max_err_mm": None if max_err_mm is None else round(float(max_err_mm), 6),
            "cycles_per_sample": man["cycles_per_sample"], **throughput(man["cycles_per_sample"]),
            "benches": benches, "all_passed": ok, "latency_cycles": man["latency_cycles"],
            "output_lsb_mm": lsb, "model_sha256": man.get("model_sha256", ""), "design": str(design.directory)}


def _float18(design: Design, build_dir, *, seed=1, **_) -> dict:
    r = run_design(design, Path(build_dir), seed=seed)
    codes = r["codes"]
    hdl_mm = FLOAT18.decode_array(r["out"])
    ref = design.spec.float_reference(codes)
    inside = ~r["sat"]
    err = float(np.abs(hdl_mm - ref)[inside].max()) if inside.any() else 0.0
    ok = not r["bench_failed"] and r["mismatches"] == 0 and r["latency"] == [design.manifest["latency_cycles"]]
    benches = {"float18_top": {"tests": 1, "failures": int(r["bench_failed"]), "failed": [], "seconds": None}}
    s = _summary(design, int(codes.size), r["mismatches"], err, benches, ok)
    s["sweep"] = {"engine": "ghdl", "backend": "ghdl", "shards": 1, "codes_per_s": None}
    curve = {"codes": codes, "hdl": hdl_mm, "ref": ref, "simulator": "GHDL", "unit_mm": True}
    return {"summary": s, "curve": curve, "spec": design.spec}


def _family(design: Design, build_dir, *, seed=1, images=None, **_) -> dict:
    images = list(images or [{"name": im["name"], "hex": str(design.directory / im["hex"])}
                             for im in design.manifest.get("images", [])])
    if len(images) < 2:
        raise FlannError(f"{design.directory}: the family bench loads two sensors' weight images through the "
                         f"cfg port; the design holds {len(images)} (pass --image A.hex --image B.hex, "
                         "written by flann calibrate)")
    res = run_family_bench(design.directory, images, build_dir, seed=seed)
    rec = res.records.get("family_every_code", {})
    codes = len(rec.get("codes", [])) * len(rec.get("outputs", {}))
    benches = {"family": {"tests": res.tests, "failures": res.failures, "failed": res.failed_tests,
                          "seconds": round(res.seconds, 1)}}
    s = _summary(design, codes, rec.get("mismatches"), None, benches, res.ok and bool(rec),
                 design.manifest["output_lsb_mm"])
    s["images"] = [im["name"] for im in images]
    s["sweep"] = {"engine": "ghdl", "backend": "ghdl", "shards": 1, "codes_per_s": None}
    return {"summary": s, "curve": None, "spec": design.spec}


def _fixed(design: Design, build_dir, *, seed=1, netlist=False, engine="auto", progress=None, **_) -> dict:
    return simulate_fixed(design, build_dir, seed=seed, netlist=netlist, engine=engine, progress=progress)


BENCHES = {"sweep": _fixed, "f18_top": _float18, "family": _family}


def simulate(design: Design, build_dir, **kw) -> dict:
    """Verify ``design`` with its datapath's bench (flann sim)."""
    dp = design.datapath
    if dp.bench is None:
        raise FlannError(f"{design.directory}: {dp.why_no_bench}")
    if kw.get("netlist") and not dp.netlist:
        raise FlannError(f"--netlist: the mapped-netlist check drives flann_top's ports; {design.directory} is "
                         f"a {dp.name} design ({dp.top})")
    return BENCHES[dp.bench](design, build_dir, **kw)


__all__ = ["simulate", "BENCHES"]
