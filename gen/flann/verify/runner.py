"""One simulation runner: cocotb 2.1's own ``cocotb_tools.runner`` under GHDL, for every bench.

``run_cocotb`` builds and runs one cocotb module (benches shipped in :mod:`flann.verify.benches`,
imported by package name, so an installed ``flann sim`` works from any directory); the bench
configuration travels as one JSON file named in ``FLANN_BENCH_CONFIG``; pass/fail comes from
cocotb's results file.  ``sweep`` is the exhaustive check: the VHDL harness ``flann_sweep.vhd``
steps through every input code with stimulus and response in VHDL (no Python per sample),
split into one shard per core, each judged against the twin by ``test_sweep.py``.
Each datapath's folder (``hardware/<name>/verify.py``) composes these into its bench.

GHDL backend: LLVM (Debian ``ghdl-llvm``, about 2.6x faster than mcode on these designs) when
installed, else mcode; the Debian ``ghdl`` wrapper picks it from ``GHDL_BACKEND``.
"""

from __future__ import annotations

import functools
import json
import logging
import os
import shutil
import subprocess
import threading
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import FlannError
from ..hardware.target import CLOCK_HZ
from .benches import BENCH_DIR, CLK_NS, CONFIG_ENV
from ..hardware.design import Design
from .shards import count_lines, cores, end_children, merge, read_results, split

HARNESSES = {"flann_sweep": "flann_sweep.vhd", "flann_harness": "flann_harness.vhd"}
BENCH_PACKAGE = "flann.verify.benches"


def sim_dir() -> Path:
    """The cocotb benches and VHDL harnesses, shipped inside the package."""
    return BENCH_DIR


def need_ghdl() -> None:
    """GHDL missing: said as such (as synth says it), not as a build whose log was never written."""
    if shutil.which("ghdl") is None:
        raise FlannError("ghdl not found on PATH (Debian package ghdl; `make tools` installs it)")


def ghdl_backend() -> str:
    """'llvm' when ghdl-llvm is installed and the ghdl wrapper honours GHDL_BACKEND, else 'mcode'."""
    need_ghdl()
    return _backend()


@functools.lru_cache(maxsize=None)
def _backend() -> str:
    if shutil.which("ghdl-llvm") is None:
        return "mcode"
    r = subprocess.run(["ghdl", "--version"], capture_output=True, text=True,
                       env={**os.environ, "GHDL_BACKEND": "llvm"})
    return "llvm" if "llvm" in r.stdout.lower() else "mcode"


@dataclass
class BenchResult:
    bench: str
    tests: int
    failures: int
    seconds: float
    records: dict = field(default_factory=dict)
    failed_tests: list = field(default_factory=list)
    test_seconds: dict = field(default_factory=dict)  # cocotb's wall time per test (results.xml)
    shards: int = 1  # simulations run side by side

    @property
    def ok(self) -> bool:
        return self.failures == 0 and self.tests > 0


def _parse_results(paths) -> tuple[int, int, list, dict]:
    tests = failures = 0
    failed, times = [], {}
    for path in paths:
        if not Path(path).is_file():
            tests, failures = tests + 1, failures + 1
            failed.append(f"(no results file: {Path(path).parent.name})")
            continue
        for tc in ET.parse(path).iter("testcase"):
            tests += 1
            times[tc.get("name")] = times.get(tc.get("name"), 0.0) + float(tc.get("time", "nan"))
            if tc.find("failure") is not None or tc.find("error") is not None:
                failures += 1
                failed.append(tc.get("name"))
    return tests, failures, failed, times


def _runner(backend: str):
    from cocotb_tools.runner import get_runner  # lazy: cocotb is a dev dependency

    r = get_runner("ghdl")
    r.env["GHDL_BACKEND"] = backend
    # the simulator's own output goes to the log files; the runner's messages ("Simulation
    # failed", also after a Ctrl-C) would add lines to the one-line error on the terminal
    r.log.propagate = False
    if not r.log.handlers:
        r.log.addHandler(logging.NullHandler())
    return r


# LLVM spends ~10 s more than mcode compiling and runs ~2.6x faster: worth it for long runs only
LLVM_CYCLES = 2_000_000


def backend_for(cycles: int) -> str:
    """The GHDL backend for a simulation of ``cycles`` clock cycles in all."""
    return ghdl_backend() if cycles > LLVM_CYCLES else "mcode"


def build(sources, toplevel: str, build_dir, backend: str | None = None) -> str:
    """Analyse and elaborate ``sources`` for ``toplevel`` (VHDL-93); returns the backend used
    (default mcode: the cocotb benches are short, and mcode compiles in a second)."""
    backend = backend or "mcode"
    need_ghdl()
    build_dir = Path(build_dir).resolve()
    build_dir.mkdir(parents=True, exist_ok=True)
    args = ["--std=93c"] + (["-O2"] if backend == "llvm" else [])
    try:
        _runner(backend).build(sources=[Path(s).resolve() for s in sources], hdl_toplevel=toplevel,
                               build_dir=build_dir, build_args=args, always=True,
                               log_file=build_dir / "build.log")
    except (RuntimeError, SystemExit):
        raise FlannError(f"GHDL could not build {toplevel}: {_first_error(build_dir / 'build.log')}") from None
    return backend


def _first_error(log: Path) -> str:
    text = log.read_text(errors="replace") if log.is_file() else ""
    return next((ln.strip() for ln in text.splitlines() if "error" in ln.lower()), f"see {log}")


def _results_file(build_dir: Path, tag: str) -> Path:
    return build_dir / f"results_{tag}.xml"


def _test(build_dir: Path, toplevel: str, module: str, backend: str, cfg_path: Path, tag: str,
          parameters: dict, plusargs: list, testcase: str | None, seed: int) -> Path:
    """Run one simulation of a built design; returns its results file (never raises on failure)."""
    results = _results_file(build_dir, tag)
    try:
        _runner(backend).test(
            test_module=f"{BENCH_PACKAGE}.{module}", hdl_toplevel=toplevel, hdl_toplevel_lang="vhdl",
            build_dir=build_dir,
            parameters=parameters, plusargs=["--ieee-asserts=disable", *plusargs], testcase=testcase,
            seed=seed, results_xml=str(results), log_file=build_dir / f"sim_{tag}.log",
            extra_env={CONFIG_ENV: str(cfg_path), "GHDL_BACKEND": backend,
                       "COCOTB_LOG_LEVEL": os.environ.get("COCOTB_LOG_LEVEL", "WARNING")},
        )
    except (RuntimeError, SystemExit):
        pass  # failures are read from the results file
    return results


def run_cocotb(sources, toplevel: str, module: str, build_dir, config: dict, *, name: str = "bench",
               parameters: dict | None = None, plusargs=(), testcase: str | None = None, seed: int = 1,
               backend: str | None = None) -> BenchResult:
    """Build ``sources`` and run the cocotb module ``module`` once; the one way every bench runs."""
    build_dir = Path(build_dir).resolve()
    if build_dir.exists():
        shutil.rmtree(build_dir)
    records = build_dir / "records"
    cfg = {**config, "seed": seed, "records_dir": str(records)}
    t0 = time.monotonic()
    backend = build(sources, toplevel, build_dir, backend)
    cfg_path = build_dir / "bench_config.json"
    cfg_path.write_text(json.dumps(cfg))
    res = _test(build_dir, toplevel, module, backend, cfg_path, "0", dict(parameters or {}), list(plusargs),
                testcase, seed)
    return _result(name, [res], records, time.monotonic() - t0)


def _result(name: str, results, records: Path, seconds: float) -> BenchResult:
    tests, failures, failed, times = _parse_results(results)
    recs = {p.stem: json.loads(p.read_text()) for p in sorted(records.glob("*.json"))} if records.is_dir() else {}
    return BenchResult(name, tests, failures, seconds, recs, failed, times)


def bench_config(design: Design) -> dict:
    return {"model": str(design.model), "options": design.options, "manifest": design.manifest}


def sources(design: Design, toplevel: str) -> list[Path]:
    files = list(design.files)
    if toplevel in HARNESSES:
        files.append(BENCH_DIR / HARNESSES[toplevel])
    return files


def sweep(design: Design, build_dir, *, codes=None, shards: int | None = None,
          backend: str | None = None, progress=None) -> dict:
    """Input codes through the VHDL sweep harness, in shards run side by side (one per core).

    ``codes``: None = every input code; (lo, hi) = that range; a list or array = those codes
    (handed to the harness in a file).  Returns {"bench": BenchResult, "codes", "data", "sat",
    "latency" (arrays in the order simulated), "backend", "shards", "seconds", "build_seconds"}.
    ``progress(done, total, elapsed_s)`` is called about twice a second while the shards run, and
    once when they have.
    """
    man = design.manifest
    half = 1 << (man["input_bits"] - 1)
    listed = codes is not None and not isinstance(codes, tuple)
    if listed:
        todo = np.asarray(codes, dtype=np.int64)
        total = int(todo.size)
    else:
        lo, hi = codes if codes is not None else (-half, half - 1)
        total = hi - lo + 1
    n_shards = shards or min(cores(), max(1, total // 256))
    build_dir = Path(build_dir).resolve() / "sweep"
    if build_dir.exists():
        shutil.rmtree(build_dir)
    records = build_dir / "records"
    t0 = time.monotonic()
    backend = backend or backend_for(total * man["cycles_per_sample"])
    backend = build(sources(design, "flann_sweep"), "flann_sweep", build_dir, backend)
    t_build = time.monotonic() - t0
    shard_cfg = []
    if listed:
        for k, chunk in enumerate(c for c in np.array_split(todo, n_shards) if c.size):
            cf = build_dir / f"codes_{k}.txt"
            cf.write_text("".join(f"{int(c)}\n" for c in chunk))
            shard_cfg.append({"codes": [int(c) for c in chunk], "codes_file": str(cf)})
    else:
        shard_cfg = [{"lo": a, "hi": b} for a, b in split(lo, hi, n_shards)]
    for k, s in enumerate(shard_cfg):  # one configuration file per shard (the bench's only channel)
        s.update(name=f"sweep_{k}", file=str(build_dir / f"sweep_{k}.txt"))
        (build_dir / f"bench_config_{k}.json").write_text(
            json.dumps({**bench_config(design), "records_dir": str(records), "shard": s}))
    def params(s: dict) -> dict:
        p = {"in_bits_g": man["input_bits"], "out_bits_g": man["output_bits"], "half_ns_g": CLK_NS // 2,
             "code_lo_g": s.get("lo", 0), "code_hi_g": s.get("hi", -1), "out_file_g": s["file"]}
        return {**p, "codes_file_g": s["codes_file"]} if "codes_file" in s else p

    files = [Path(s["file"]) for s in shard_cfg]
    t1 = time.monotonic()
    stops = [stop_time(len(s["codes"]) if "codes" in s else s["hi"] - s["lo"] + 1, man["cycles_per_sample"])
             for s in shard_cfg]
    results = _run_shards(build_dir, "test_sweep", backend,
                          [(build_dir / f"bench_config_{k}.json", params(s)) for k, s in enumerate(shard_cfg)],
                          1, files, total, progress, stops)
    seconds = time.monotonic() - t1
    bench = _result("sweep", results, records, time.monotonic() - t0)
    got = merge([read_results(f) for f in files])
    return {"bench": bench, **got, "backend": backend, "shards": len(shard_cfg), "seconds": seconds,
            "build_seconds": t_build}


def stop_time(samples: int, cycles_per_sample: int) -> str:
    """The ``--stop-time`` of a harness offering ``samples`` inputs: three times the cycles they
    take plus a start-up margin.  A design that never answers (its top entity renamed, so the
    harness's component stays unbound) ends there and its missing lines fail the bench."""
    return f"--stop-time={(3 * (samples + 8) * cycles_per_sample + 10000) * CLK_NS}ns"


def _run_shards(build_dir: Path, module: str, backend: str, shards: list[tuple[Path, dict]], seed: int,
                files: list[Path], total: int, progress, stops: list[str]) -> list[Path]:
    """The built sweep harness run once per shard ((bench configuration, generics) each), side by
    side, each to its stop time ``stops[k]``; ``progress(done, total, elapsed_s)`` about twice a
    second from the lines in ``files``.  Returns the shards' results files, one per shard in order
    (a shard that wrote none is counted failed when they are read).  Interrupted (Ctrl-C,
    SIGTERM), the simulators end with flann: none runs on into a deleted build directory."""
    results = [_results_file(build_dir, str(k)) for k in range(len(shards))]

    def one(k: int) -> None:
        results[k] = _test(build_dir, "flann_sweep", module, backend, shards[k][0], str(k), shards[k][1],
                           [stops[k]] if stops[k] else [], None, seed)

    threads = [threading.Thread(target=one, args=(k,), daemon=True) for k in range(len(shards))]
    t1 = time.monotonic()
    try:
        for t in threads:
            t.start()
        while any(t.is_alive() for t in threads):
            next(t for t in threads if t.is_alive()).join(0.5)
            if progress:
                progress(sum(count_lines(f) for f in files), total, time.monotonic() - t1)
    except BaseException:
        end_children()
        raise
    if progress:  # the last figure, whatever the timing: a terminal's line ends at done
        progress(sum(count_lines(f) for f in files), total, time.monotonic() - t1)
    return results


def sweep_temperatures(sources, module: str, build_dir, config: dict, parameters: dict, temps, *, name: str,
                       seed: int = 1, backend: str | None = None, progress=None) -> BenchResult:
    """A two-input design's sweep harness (every voltage code of ``config["sweep"]`` at each code of
    ``temps``) in shards of whole temperature codes, one per core, built once; the shards' lines
    joined in order into ``config["sweep"]["file"]``, their records ``name`` into one (samples and
    mismatches summed, the largest ``max_err_lsb``, every latency seen).  A shard without its
    record leaves the result without one: the bench has failed and its log says why."""
    build_dir = Path(build_dir).resolve()
    if build_dir.exists():
        shutil.rmtree(build_dir)
    t0 = time.monotonic()
    backend = build(sources, "flann_sweep", build_dir, backend)
    sweep_cfg = config["sweep"]
    chunks = [c for c in np.array_split(np.asarray(temps, dtype=np.int64), min(cores(), len(temps))) if c.size]
    shards, files = [], []
    for k, chunk in enumerate(chunks):
        temps_file, out_file = build_dir / f"temps_{k}.txt", build_dir / f"sweep_{k}.txt"
        temps_file.write_text("".join(f"{int(t)}\n" for t in chunk))
        cfg = {**config, "seed": seed, "records_dir": str(build_dir / f"records_{k}"),
               "sweep": {**sweep_cfg, "file": str(out_file), "temps": [int(t) for t in chunk]}}
        cfg_path = build_dir / f"bench_config_{k}.json"
        cfg_path.write_text(json.dumps(cfg))
        shards.append((cfg_path, {**parameters, "temps_file_g": str(temps_file), "out_file_g": str(out_file)}))
        files.append(out_file)
    per_temp = sweep_cfg["code_hi"] - sweep_cfg["code_lo"] + 1
    total = len(temps) * per_temp
    cycles = int(config.get("manifest", {}).get("cycles_per_sample", 0)) or None
    stops = [stop_time(len(c) * per_temp, cycles) if cycles else "" for c in chunks]
    results = _run_shards(build_dir, module, backend, shards, seed, files, total, progress, stops)
    with open(sweep_cfg["file"], "wb") as joined:
        for f in files:
            if f.is_file():
                joined.write(f.read_bytes())
    parts = [_result(name, [r], build_dir / f"records_{k}", 0.0) for k, r in enumerate(results)]
    res = BenchResult(name, sum(p.tests for p in parts), sum(p.failures for p in parts),
                      time.monotonic() - t0, {}, [t for p in parts for t in p.failed_tests], shards=len(chunks))
    recs = [p.records.get(name) for p in parts]
    if len(recs) == len(chunks) and all(recs):
        merged = {"samples": sum(r["samples"] for r in recs), "mismatches": sum(r["mismatches"] for r in recs),
                  "latency": sorted({lat for r in recs for lat in r["latency"]})}
        if all("max_err_lsb" in r for r in recs):
            merged["max_err_lsb"] = max(r["max_err_lsb"] for r in recs)
        res.records[name] = merged
    return res


ENGINES = ("auto", "ghdl", "verilator")
# GHDL (LLVM) simulates the design at roughly 1e5 clock cycles/s per shard on this class of
# machine: beyond a minute of that, every code goes through the compiled netlist instead.
GHDL_CYCLES_PER_MINUTE = 6e6


def choose_engine(design: Design, engine: str = "auto", samples: int | None = None) -> str:
    """``auto``: the VHDL under GHDL when every sample (default: every input code) fits in about a
    minute there (or Verilator is missing), else GHDL's synthesised netlist compiled by Verilator
    with the VHDL on a sample."""
    if engine not in ENGINES:
        raise FlannError(f"engine {engine!r}: must be one of {', '.join(ENGINES)}")
    if engine != "auto":
        return engine
    man = design.manifest
    samples = (1 << man["input_bits"]) if samples is None else samples
    cycles = samples * man["cycles_per_sample"] / max(1, cores())
    return "verilator" if cycles > GHDL_CYCLES_PER_MINUTE and shutil.which("verilator") else "ghdl"


def throughput(cycles_per_sample: int, clock_hz: float = CLOCK_HZ) -> dict:
    """Samples per second at the design's clock; ``samples_per_s_at_50mhz`` is the older
    name of the same figure (scripts read it), kept as an alias."""
    sps = round(clock_hz / cycles_per_sample, 1)
    return {"clock_hz": clock_hz, "samples_per_s": sps, "samples_per_s_at_50mhz": sps}


def simulator_name(about: dict) -> str:
    """Which simulator produced every code's output, for a plot's legend."""
    if about.get("engine") == "verilator":
        return "Verilator, GHDL's synthesised netlist"
    backend = str(about.get("backend", "")).removeprefix("ghdl-")
    return f"GHDL, {backend}" if backend else "GHDL"


__all__ = ["throughput", "simulator_name", "choose_engine", "run_cocotb", "bench_config", "sources", "HARNESSES", "sweep", "sweep_temperatures", "backend_for", "BenchResult", "sim_dir",
           "ghdl_backend"]
