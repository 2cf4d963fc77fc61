"""Post-synthesis simulation: the netlist Yosys maps to Spartan-II cells, checked against the twin.

Flow: the design's VHDL -> ``ghdl --synth --out=verilog`` (with :func:`flann.eda.
repair_ghdl_verilog`) -> Yosys ``synth_xilinx -family xcv`` -> ``write_verilog`` (the netlist
whose cells ``flann synth`` counts) -> Verilator, compiled with Yosys's own Xilinx cell models
(``<yosys datdir>/xilinx/cells_sim.v``; block RAMs from ``benches/ramb4_sim.v``, which Yosys does
not model) and a C++ driver that steps through every input code -> every output compared with
the twin in one pass.  Verilator, not Icarus: on the default design's mapped netlist Icarus runs
about 1 code/s, Verilator a few hundred.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from ..errors import FlannError
from ..hardware.fixed.datapath import DATAPATH as FIXED
from ..hardware.fixed.twin import FlannTop
from ..eda import NETLIST, ghdl_to_verilog, yosys_cells
from ..hardware.manifest import read_manifest
from .benches import BENCH_DIR
from .design import Design
from .shards import cores, count_lines, merge, read_results, split

DRIVER = "netlist_main.cpp"
DRIVER_TOP = FIXED.top      # the driver is written against this entity's ports (Vflann_top)
RAM_MODELS = "ramb4_sim.v"


def yosys_datdir() -> Path:
    """Yosys's share directory (what ``yosys-config --datdir`` prints; Debian ships yosys-config
    only in yosys-dev, so it is found next to the yosys binary)."""
    exe = shutil.which("yosys")
    if exe is None:
        raise FlannError("yosys not found on PATH (Debian package yosys; `make tools` installs it)")
    cfg = shutil.which("yosys-config")
    if cfg:
        r = subprocess.run([cfg, "--datdir"], capture_output=True, text=True)
        if r.returncode == 0 and Path(r.stdout.strip(), "xilinx", "cells_sim.v").is_file():
            return Path(r.stdout.strip())
    d = Path(exe).resolve().parent.parent / "share" / "yosys"
    if not (d / "xilinx" / "cells_sim.v").is_file():
        raise FlannError(f"Yosys's Xilinx cell models not found ({d / 'xilinx' / 'cells_sim.v'})")
    return d


def mapped_netlist(design: Design, work, abc: str = "full") -> Path:
    """Synthesise ``design`` as ``flann synth`` does; returns the Yosys-mapped Verilog netlist."""
    work = Path(work).resolve()
    work.mkdir(parents=True, exist_ok=True)
    man = read_manifest(design.directory)
    verilog = ghdl_to_verilog(man, work)
    yosys_cells(verilog, man.top, work, abc)
    return work / NETLIST


def compile_netlist(netlist: Path, build: Path, in_bits: int, out_bits: int, cells: bool = True,
                    models: list | None = None, defines: tuple = ()) -> Path:
    """Verilator model of ``netlist`` with the sweep driver (and the Xilinx cell models for a
    mapped netlist; GHDL's own Verilog has no cells; ``models`` replaces them for another
    family's netlist, with ``defines`` for its model files)."""
    exe_tool = shutil.which("verilator")
    if exe_tool is None:
        raise FlannError("verilator not found on PATH (Debian package verilator; `make tools` installs it)")
    build = Path(build).resolve()
    if build.exists():
        shutil.rmtree(build)
    build.mkdir(parents=True)
    if models is None:
        models = [str(yosys_datdir() / "xilinx" / "cells_sim.v"), str(BENCH_DIR / RAM_MODELS)] if cells else []
    cmd = [exe_tool, "--cc", str(Path(netlist).resolve()), *map(str, models), *(f"+define+{d}" for d in defines),
           "--top-module", DRIVER_TOP, "--exe", str(BENCH_DIR / DRIVER), "--build", "-j", "2",
           "-Mdir", str(build / "obj"), "-O3", "--no-timing", "-Wno-fatal", "-Wno-lint", "-Wno-style",
           "-CFLAGS", f"-DIN_BITS={in_bits} -DOUT_BITS={out_bits}"]
    log = build / "verilator.log"
    with open(log, "w") as fh:
        r = subprocess.run(cmd, stdout=fh, stderr=subprocess.STDOUT, cwd=build)
    exe = build / "obj" / f"V{DRIVER_TOP}"
    if r.returncode != 0 or not exe.is_file():
        text = log.read_text(errors="replace")
        first = next((ln.strip() for ln in text.splitlines() if "%Error" in ln or "error:" in ln), f"see {log}")
        raise FlannError(f"verilator could not build the netlist simulation: {first}")
    return exe


def run_netlist(exe: Path, lo: int, hi: int, build: Path, shards: int = 2, progress=None) -> dict:
    """Run the compiled netlist over codes lo..hi in ``shards`` processes; arrays in code order."""
    parts = split(lo, hi, max(1, shards))
    files = [Path(build) / f"netlist_{k}.txt" for k in range(len(parts))]
    procs = [subprocess.Popen([str(exe), str(a), str(b), str(f)], stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True) for (a, b), f in zip(parts, files)]
    t0 = time.monotonic()
    try:
        while any(p.poll() is None for p in procs):
            time.sleep(0.5)
            if progress:
                progress(sum(count_lines(f) for f in files), hi - lo + 1, time.monotonic() - t0)
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
    bad = [p for p in procs if p.returncode != 0]
    if bad:
        raise FlannError(f"netlist simulation failed: {(bad[0].stderr.read() or '').strip() or bad[0].returncode}")
    return {**merge([read_results(f) for f in files]), "seconds": time.monotonic() - t0}


def compare(design: Design, got: dict) -> dict:
    """Mismatches of the netlist's outputs against the twin (and missing codes)."""
    man = design.manifest
    lo, hi = -(1 << (man["input_bits"] - 1)), (1 << (man["input_bits"] - 1)) - 1
    out, sat = FlannTop(design.spec).process(got["codes"])
    bad = (got["data"] != out) | (got["sat"] != sat) | (got["latency"] != man["latency_cycles"])
    missing = (hi - lo + 1) - int(np.unique(got["codes"]).size)
    first = [int(c) for c in got["codes"][bad][:5]]
    return {"codes_tested": int(got["codes"].size), "mismatches": int(np.count_nonzero(bad)) + missing,
            "first_mismatches": first}


def check_netlist(design: Design, build, netlist: Path | None = None, progress=None, abc: str = "full") -> dict:
    """Every input code through the mapped netlist (synthesised here unless ``netlist`` is given)."""
    build = Path(build).resolve()
    build.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    if netlist is None:
        netlist = mapped_netlist(design, build / "synth", abc)
    man = design.manifest
    exe = compile_netlist(netlist, build / "verilator", man["input_bits"], man["output_bits"])
    lo, hi = -(1 << (man["input_bits"] - 1)), (1 << (man["input_bits"] - 1)) - 1
    got = run_netlist(exe, lo, hi, build, shards=cores(), progress=progress)
    res = compare(design, got)
    res.update(simulator="verilator", seconds=time.monotonic() - t0, run_seconds=got["seconds"],
               netlist=str(netlist))
    return res


def check_rtl_netlist(design: Design, build, progress=None) -> dict:
    """Every input code through GHDL's own synthesis of the VHDL (``ghdl --synth``, repaired, the
    text Yosys maps), compiled by Verilator: the fast exhaustive engine (``flann sim --engine
    verilator``).  Returns the arrays in code order as the VHDL sweep does, plus timings."""
    build = Path(build).resolve()
    build.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    man = design.manifest
    verilog = ghdl_to_verilog(read_manifest(design.directory), build / "ghdl_synth")
    exe = compile_netlist(verilog, build / "verilator", man["input_bits"], man["output_bits"], cells=False)
    t_build = time.monotonic() - t0
    lo, hi = -(1 << (man["input_bits"] - 1)), (1 << (man["input_bits"] - 1)) - 1
    got = run_netlist(exe, lo, hi, build, shards=cores(), progress=progress)
    return {**got, "build_seconds": t_build, "shards": min(cores(), hi - lo + 1)}


def require_sweep_driver(datapath, directory, flag: str = "--post-route") -> None:
    """The netlist and post-route sweeps drive :data:`DRIVER_TOP`'s flat ports: refuse another
    datapath's design before any slow step."""
    if not datapath.netlist:
        raise FlannError(f"{flag}: the sweep driver drives {DRIVER_TOP}'s ports; {directory} holds a "
                         f"{datapath.name} design")


def check_synthesized(design: Design, netlist: Path) -> dict:
    """``flann synth``'s check of the netlist it just counted (temporary build directory)."""
    with tempfile.TemporaryDirectory(prefix="flann-netlist-") as tmp:
        return check_netlist(design, tmp, netlist=netlist)


__all__ = ["DRIVER_TOP", "require_sweep_driver", "check_netlist", "check_rtl_netlist", "check_synthesized", "mapped_netlist", "compile_netlist", "run_netlist", "compare",
           "yosys_datdir"]
