"""Run the cocotb benches in ``sim/`` under GHDL (through cocotb-test) and summarise.

Layer 5: ``run_bench`` runs one bench module against a generated HDL directory; pass/fail
comes from cocotb's results file.  ``simulate`` is ``flann sim``: generate into a build
directory, run every bench, and return the summary (codes tested, mismatches, error vs the
float model, cycles per sample, samples/s at 50 MHz).
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import sys
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import FlannError
from .benches import BENCH_DIR
from ..hardware.fixed.render import generate, load, read_manifest
from ..hardware.fixed.spec import CLOCK_HZ
from ..hardware.fixed.twin import FlannTop

# bench name -> (toplevel entity, cocotb module in sim/)
BENCHES = {
    "top": ("flann_harness", "test_top"),  # sim/flann_harness.vhd: VHDL clock around flann_top
    "norm": ("flann_norm", "test_blocks"),
    "expansion": ("flann_expansion", "test_blocks"),
    "multiplier": ("flann_multiplier", "test_blocks"),
    "adder": ("flann_adder", "test_blocks"),
}
# test functions of test_blocks.py per block entity
BLOCK_TESTS = {
    "norm": "norm_vs_twin",
    "expansion": "expansion_vs_twin",
    "multiplier": "multiplier_vs_twin",
    "adder": "adder_vs_twin",
}


def sim_dir() -> Path:
    """The cocotb benches, shipped inside the package."""
    return BENCH_DIR


def check_tools() -> None:
    if shutil.which("ghdl") is None:
        raise FlannError("ghdl not found on PATH (install GHDL 2.x, mcode backend: `make tools`)")
    try:
        import cocotb_test.simulator  # noqa: F401
    except ImportError:
        raise FlannError("cocotb-test is not installed (pip install -e '.[dev]')") from None


@dataclass
class BenchResult:
    bench: str
    tests: int
    failures: int
    seconds: float
    records: dict = field(default_factory=dict)
    failed_tests: list = field(default_factory=list)
    test_seconds: dict = field(default_factory=dict)  # cocotb's wall time per test (results.xml)

    @property
    def ok(self) -> bool:
        return self.failures == 0 and self.tests > 0


def _parse_results(path: Path) -> tuple[int, int, list, dict]:
    if not path.is_file():
        return 0, 1, ["(simulation ended without a results file)"], {}
    tree = ET.parse(path)
    tests = failures = 0
    failed = []
    times = {}
    for tc in tree.iter("testcase"):
        tests += 1
        times[tc.get("name")] = float(tc.get("time", "nan"))
        if tc.find("failure") is not None or tc.find("error") is not None:
            failures += 1
            failed.append(tc.get("name"))
    return tests, failures, failed, times


def run_bench(hdl_dir, bench: str, *, model, options: dict, build_dir, seed: int = 1,
              testcase: str | None = None, extra: dict | None = None, quiet: bool = True) -> BenchResult:
    """Run one bench (key of BENCHES) on the HDL in ``hdl_dir``; never raises on test failure."""
    check_tools()
    from cocotb_test.simulator import run as cocotb_run

    if bench not in BENCHES:
        raise FlannError(f"bench {bench!r}: must be one of {', '.join(BENCHES)}")
    toplevel, module = BENCHES[bench]
    if testcase is None and bench in BLOCK_TESTS:
        testcase = BLOCK_TESTS[bench]
    hdl_dir = Path(hdl_dir).resolve()
    man = read_manifest(hdl_dir)
    build = Path(build_dir).resolve() / bench
    if build.exists():
        shutil.rmtree(build)
    build.mkdir(parents=True)
    records = build / "records"
    cfg = {"model": str(Path(model).resolve()), "options": options, "manifest": man, "seed": seed,
           "records_dir": str(records), **(extra or {})}
    cfg_path = build / "bench_config.json"
    cfg_path.write_text(json.dumps(cfg, indent=1))
    results = build / "results.xml"
    env = {"FLANN_BENCH_CONFIG": str(cfg_path), "COCOTB_RESULTS_FILE": str(results),
           "COCOTB_LOG_LEVEL": os.environ.get("COCOTB_LOG_LEVEL", "WARNING" if quiet else "INFO")}
    saved = os.environ.get("COCOTB_RESULTS_FILE")
    os.environ["COCOTB_RESULTS_FILE"] = str(results)
    sources = [str(hdl_dir / f) for f in man["files"]]
    params = {}
    sim_args = ["--ieee-asserts=disable"]
    if toplevel == "flann_harness":
        sources.append(str(sim_dir() / "flann_harness.vhd"))
        params = {"in_bits_g": man["input_bits"], "out_bits_g": man["output_bits"]}
        # the VHDL clock never stops by itself: bound the run generously (a test still running
        # at this time is reported as failed by cocotb)
        n = (1 << man["input_bits"]) if cfg.get("codes", "all") == "all" else int(cfg["codes"]) + 20
        n += 3 * int(cfg.get("handshake_samples", 60)) + 60
        sim_args.append(f"--stop-time={(n * man['cycles_per_sample'] * 3 + 10000) * 10}ns")
        cfg["harness"] = True
        cfg_path.write_text(json.dumps(cfg, indent=1))
    t0 = time.monotonic()
    # cocotb-test logs the simulator's output through the "cocotb" logger: keep it in sim.log
    logger = logging.getLogger("cocotb")
    handler = logging.FileHandler(build / "sim.log")
    handler.setFormatter(logging.Formatter("%(levelname)s %(message)s"))
    saved_handlers, saved_prop = logger.handlers[:], logger.propagate
    logger.handlers = [handler]
    if not quiet:
        logger.handlers.append(logging.StreamHandler(sys.stderr))
    logger.propagate = False
    try:
        cocotb_run(
            simulator="ghdl", toplevel=toplevel, module=module, toplevel_lang="vhdl",
            vhdl_sources=sources, python_search=[str(sim_dir())], parameters=params,
            sim_build=str(build / "ghdl"), compile_args=["--std=93c"],
            sim_args=sim_args, extra_env=env, testcase=testcase, waves=False,
        )
    except SystemExit:
        pass  # failures are read from the results file below
    finally:
        logger.handlers, logger.propagate = saved_handlers, saved_prop
        handler.close()
        if saved is None:
            os.environ.pop("COCOTB_RESULTS_FILE", None)
        else:
            os.environ["COCOTB_RESULTS_FILE"] = saved
    seconds = time.monotonic() - t0
    tests, failures, failed, times = _parse_results(results)
    recs = {}
    if records.is_dir():
        for p in sorted(records.glob("*.json")):
            recs[p.stem] = json.loads(p.read_text())
    return BenchResult(bench, tests, failures, seconds, recs, failed, times)


def simulate(model_path, build_dir, *, options: dict | None = None, seed: int = 1,
             benches=tuple(BENCHES), progress=None) -> dict:
    """Generate, run the benches, and summarise (the fields of `flann sim --json`)."""
    options = dict(options or {})
    build_dir = Path(build_dir)
    hdl = build_dir / "hdl"
    man = generate(model_path, hdl, **options)
    spec = load(model_path, **options)
    results = []
    for b in benches:
        if progress:
            progress(f"simulating {b} ...")
        results.append(run_bench(hdl, b, model=model_path, options=options, build_dir=build_dir, seed=seed))
    top = next((r for r in results if r.bench == "top"), None)
    summary = {
        "codes_tested": 0, "mismatches": None, "max_err_lsb": None, "max_err_mm": None,
        "cycles_per_sample": man["cycles_per_sample"],
        "samples_per_s_at_50mhz": round(CLOCK_HZ / man["cycles_per_sample"], 1),
    }
    rec = top.records.get("top_every_code") if top else None
    curve = None
    if rec:
        codes = np.array(rec["codes"], dtype=np.int64)
        data = np.array(rec["data"], dtype=np.int64)
        sat = np.array(rec["sat"], dtype=bool)
        twin_out, twin_sat = FlannTop(spec).process(codes)
        ref = spec.float_reference(codes) / spec.output_lsb_mm
        err = np.abs(data - ref)
        summary.update(
            codes_tested=int(codes.size),
            mismatches=max(int(np.count_nonzero((data != twin_out) | (sat != twin_sat))),
                           int(rec.get("mismatches", 0))),
            max_err_lsb=round(float(err.max()), 4),
            max_err_mm=round(float(err.max()) * spec.output_lsb_mm, 6),
        )
        curve = {"codes": codes, "hdl": data, "ref": ref}
    summary["benches"] = {r.bench: {"tests": r.tests, "failures": r.failures, "failed": r.failed_tests,
                                    "seconds": round(r.seconds, 1)} for r in results}
    summary["all_passed"] = all(r.ok for r in results)
    summary["latency_cycles"] = man["latency_cycles"]
    summary["output_lsb_mm"] = man["output_lsb_mm"]
    summary["model_sha256"] = man["model_sha256"]
    return {"summary": summary, "curve": curve, "spec": spec}


def plot(curve: dict, spec, path) -> None:
    """HDL output and golden model across the input range, and their difference (paper Fig. 6)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    v = curve["codes"] * spec.input_lsb_v
    q = spec.output_lsb_mm
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    a1.plot(v, curve["ref"] * q, label="golden model (float64)", lw=2, color="0.7")
    a1.plot(v, curve["hdl"] * q, label="HDL (GHDL)", lw=0.8, color="C0")
    a1.axvspan(spec.clamp_lo * spec.input_lsb_v, spec.clamp_hi * spec.input_lsb_v, color="C2", alpha=0.06,
               label="trained range")
    a1.set_ylabel("displacement (mm)")
    a1.legend(loc="best", fontsize=8)
    a1.set_title("(a) FLANN output: HDL vs golden model")
    a2.plot(v, curve["hdl"] - curve["ref"], lw=0.6, color="C3")
    a2.axhline(1, ls=":", color="k")
    a2.axhline(-1, ls=":", color="k")
    a2.set_ylabel("HDL - golden (output LSB)")
    a2.set_xlabel("input (V)")
    a2.set_title(f"(b) difference (1 LSB = {q} mm)")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp.png")
    try:
        fig.savefig(tmp, dpi=120)
        os.replace(tmp, path)
    finally:
        plt.close(fig)
        tmp.unlink(missing_ok=True)


__all__ = ["run_bench", "simulate", "plot", "BenchResult", "BENCHES", "sim_dir"]
