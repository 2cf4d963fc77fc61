"""Post-synthesis simulation: the netlist Yosys maps to Spartan-II cells, checked against the twin.

Flow: the design's VHDL -> ``ghdl --synth --out=verilog`` (with :func:`flann.eda.
repair_ghdl_verilog`) -> Yosys ``synth_xilinx -family xcv`` -> ``write_verilog`` (the netlist
whose cells ``flann synth`` counts) -> Verilator, compiled with Yosys's own Xilinx cell models
(``<yosys datdir>/xilinx/cells_sim.v``; block RAMs from ``benches/ramb4_sim.v``, which Yosys does
not model) and a C++ driver that steps through every input code -> every output compared with
the twin in one pass.  Verilator, not Icarus: on the default design's mapped netlist Icarus runs
about 1 code/s, Verilator a few hundred.

A datapath's folder states its sweep (``netlist`` of its :class:`~flann.verify.plugin.Verification`):
the top the driver drives, the twin it is compared with, for a design with temperature the
temperature codes each voltage code runs at (those of its RTL sweep), and for a family design
the weight image the driver first loads through the cfg port (the last one the design keeps,
over the memory's initial sensor, so that the load is what the sweep sees).
"""

from __future__ import annotations

import dataclasses
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from .. import cache
from ..errors import FlannError
from ..eda import NETLIST, ghdl_to_verilog, synthesize_cells, tool_version
from .benches import BENCH_DIR
from ..hardware.design import Design
from .plugin import verification, with_netlist
from .shards import cores, count_lines, merge, read_results, split

DRIVER = "netlist_main.cpp"
RAM_MODELS = "ramb4_sim.v"
PREFIX = "Vdut"             # the Verilated model's class, whatever the top (the driver includes Vdut.h)


@dataclass(frozen=True)
class NetlistSweep:
    """What the driver needs of a design: its top, widths and latency, the twin's outputs of a
    code array (and a temperature code array), the temperature codes every voltage code runs at
    (None: the top has no temperature input) and the weight image it loads first (None: the
    weights are built in)."""

    top: str
    in_bits: int
    out_bits: int
    latency: int
    process: Callable
    image: tuple | None = None
    cfg_addr_bits: int | None = None
    temps: tuple | None = None
    temp_bits: int | None = None

    @property
    def codes(self) -> tuple[int, int]:
        return -(1 << (self.in_bits - 1)), (1 << (self.in_bits - 1)) - 1

    @property
    def samples(self) -> int:
        lo, hi = self.codes
        return (hi - lo + 1) * (len(self.temps) if self.temps is not None else 1)

    def expected(self, got: dict):
        """The twin's (out_data, out_sat) at the samples the driver ran."""
        return self.process(got["codes"]) if self.temps is None else self.process(got["codes"], got["temps"])


def top_sweep(design: Design, process: Callable, **more) -> NetlistSweep:
    """The sweep of ``design``'s top as its manifest states it, compared with ``process``."""
    man = design.manifest
    return NetlistSweep(man["top"], man["input_bits"], man["output_bits"], man["latency_cycles"], process, **more)


def sweep_of(design: Design, image: dict | None = None) -> NetlistSweep:
    """The sweep the design's datapath folder states for its netlist (``image``: the weight
    image a family design loads first)."""
    require_sweep_driver(design.datapath, design.directory, "the netlist sweep")
    return verification(design.datapath).netlist(design, image)


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
    synthesize_cells(design.manifest, work, abc)
    return work / NETLIST


def compile_netlist(netlist: Path, build: Path, sweep: NetlistSweep, cells: bool = True,
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
    flags = f"-DIN_BITS={sweep.in_bits} -DOUT_BITS={sweep.out_bits}"
    if sweep.temps is not None:
        flags += f" -DTEMP_BITS={sweep.temp_bits}"
    if sweep.image is not None:
        flags += f" -DCFG_ADDR_BITS={sweep.cfg_addr_bits} -DCFG_WORDS={len(sweep.image)}"
    options = ["--top-module", sweep.top, "--prefix", PREFIX, "-O3", "--no-timing", "-Wno-fatal", "-Wno-lint",
               "-Wno-style", "-CFLAGS", flags]
    cmd = [exe_tool, "--cc", str(Path(netlist).resolve()), *map(str, models), *(f"+define+{d}" for d in defines),
           "--exe", str(BENCH_DIR / DRIVER), "--build", "-j", "2", "-Mdir", str(build / "obj"), *options]
    exe = build / "obj" / PREFIX
    # the C++ build takes most of a small design's check: once per netlist, driver and options
    digest = cache.key(tool_version("verilator"), Path(netlist), *map(Path, models), *defines, *options,
                       BENCH_DIR / DRIVER)
    with cache.entry("verilator", digest, build / "obj", [PREFIX]) as hit:
        if not hit:
            log = build / "verilator.log"
            with open(log, "w") as fh:
                r = subprocess.run(cmd, stdout=fh, stderr=subprocess.STDOUT, cwd=build)
            if r.returncode != 0 or not exe.is_file():
                text = log.read_text(errors="replace")
                first = next((ln.strip() for ln in text.splitlines() if "%Error" in ln or "error:" in ln),
                             f"see {log}")
                raise FlannError(f"verilator could not build the netlist simulation: {first}")
    return exe


def run_netlist(exe: Path, sweep: NetlistSweep, build: Path, shards: int = 2, progress=None) -> dict:
    """Run the compiled netlist over every code of ``sweep`` in ``shards`` processes (each loads
    the weight image first; a shard runs its codes at every temperature code); arrays in code
    order within each shard."""
    lo, hi = sweep.codes
    parts = split(lo, hi, max(1, shards))
    files = [Path(build) / f"netlist_{k}.txt" for k in range(len(parts))]
    extra = []
    if sweep.temps is not None:
        (Path(build) / "netlist_temps.txt").write_text("".join(f"{t}\n" for t in sweep.temps))
        extra.append(str(Path(build) / "netlist_temps.txt"))
    if sweep.image is not None:
        (Path(build) / "netlist_image.txt").write_text("".join(f"{w:x}\n" for w in sweep.image))
        extra.append(str(Path(build) / "netlist_image.txt"))
    procs = [subprocess.Popen([str(exe), str(a), str(b), str(f), *extra], stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True) for (a, b), f in zip(parts, files)]
    t0 = time.monotonic()
    try:
        while any(p.poll() is None for p in procs):
            time.sleep(0.5)
            if progress:
                progress(sum(count_lines(f) for f in files), sweep.samples, time.monotonic() - t0)
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
    bad = [p for p in procs if p.returncode != 0]
    if bad:
        raise FlannError(f"netlist simulation failed: {(bad[0].stderr.read() or '').strip() or bad[0].returncode}")
    return {**merge([read_results(f, sweep.temps is not None) for f in files]), "seconds": time.monotonic() - t0}


@dataclass
class NetlistCheck:
    """A compiled netlist judged against the twin over its sweep: ``passed`` when every sample
    ran and none differs (a missing sample counts as a mismatch)."""

    codes_tested: int
    mismatches: int
    first_mismatches: list
    temperature_codes: int | None = None
    simulator: str = "verilator"
    seconds: float = 0.0
    run_seconds: float = 0.0
    netlist: str = ""

    @property
    def passed(self) -> bool:
        return self.mismatches == 0 and self.codes_tested > 0

    def summary(self) -> dict:
        """What the command summaries report of it."""
        return {"codes_tested": self.codes_tested, "mismatches": self.mismatches,
                "first_mismatches": self.first_mismatches, "simulator": self.simulator,
                "temperature_codes": self.temperature_codes, "seconds": round(self.seconds, 1)}


def compare(sweep: NetlistSweep, got: dict) -> NetlistCheck:
    """Mismatches of the netlist's outputs against the twin (and missing samples)."""
    out, sat = sweep.expected(got)
    # the driver prints out_data as signed; a float18 code is a bit pattern
    mask = (1 << sweep.out_bits) - 1
    bad = ((got["data"] & mask) != (out & mask)) | (got["sat"] != sat) | (got["latency"] != sweep.latency)
    ran = np.column_stack([got["codes"]] + ([got["temps"]] if sweep.temps is not None else []))
    missing = sweep.samples - int(np.unique(ran, axis=0).shape[0])
    first = ran[bad][:5].tolist() if sweep.temps is not None else [int(c) for c in got["codes"][bad][:5]]
    return NetlistCheck(int(got["codes"].size), int(np.count_nonzero(bad)) + missing, first,
                        None if sweep.temps is None else len(sweep.temps), run_seconds=got.get("seconds", 0.0))


def check_netlist(design: Design, build, netlist: Path | None = None, progress=None, abc: str = "full",
                  image: dict | None = None) -> NetlistCheck:
    """Every input code through the mapped netlist (synthesised here unless ``netlist`` is given)."""
    build = Path(build).resolve()
    build.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    sweep = sweep_of(design, image)
    if netlist is None:
        netlist = mapped_netlist(design, build / "synth", abc)
    exe = compile_netlist(netlist, build / "verilator", sweep)
    got = run_netlist(exe, sweep, build, shards=cores(), progress=progress)
    return dataclasses.replace(compare(sweep, got), seconds=time.monotonic() - t0, netlist=str(netlist))


def netlist_summary(design: Design, build_dir, progress=None, image: dict | None = None) -> tuple[dict, bool]:
    """``flann sim --netlist``: the mapped netlist's sweep as the summary reports it, and whether it
    passed (every code, no mismatch)."""
    nl = check_netlist(design, Path(build_dir) / "netlist", progress=progress("netlist") if progress else None,
                       image=image)
    entry = nl.summary()
    del entry["first_mismatches"]
    return entry, nl.passed


def check_rtl_netlist(design: Design, build, progress=None, temps=None) -> dict:
    """Every input code through GHDL's own synthesis of the VHDL (``ghdl --synth``, repaired, the
    text Yosys maps), compiled by Verilator: the fast exhaustive engine (``flann sim --engine
    verilator``).  ``temps``: a two-input design's temperature codes (default: its netlist
    sweep's).  Returns the arrays in code order as the VHDL sweep does, plus timings and the
    ``sweep`` (what :func:`compare` judges them by)."""
    build = Path(build).resolve()
    build.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    sweep = sweep_of(design)
    if temps is not None:
        sweep = dataclasses.replace(sweep, temps=tuple(int(t) for t in temps))
    verilog = ghdl_to_verilog(design.manifest, build / "ghdl_synth")
    exe = compile_netlist(verilog, build / "verilator", sweep, cells=False)
    t_build = time.monotonic() - t0
    lo, hi = sweep.codes
    got = run_netlist(exe, sweep, build, shards=cores(), progress=progress)
    return {**got, "build_seconds": t_build, "shards": min(cores(), hi - lo + 1), "sweep": sweep}


def sweep_datapaths() -> str:
    """The datapaths the netlist sweep drives, as a sentence lists them."""
    names = [dp.name for dp in with_netlist()]
    return f"{', '.join(names[:-1])} and {names[-1]}"


def has_sweep_driver(datapath) -> bool:
    found = verification(datapath)
    return found is not None and found.netlist is not None


def require_sweep_driver(datapath, directory, flag: str = "--post-route") -> None:
    """The netlist and post-route sweeps drive the tops whose datapath states a netlist sweep:
    refuse another datapath's design before any slow step."""
    if not has_sweep_driver(datapath):
        raise FlannError(f"{flag}: {directory} holds a {datapath.name} design, and the netlist sweep has a driver "
                         f"and twin for {sweep_datapaths()} designs only")


def check_synthesized(design: Design, netlist: Path) -> NetlistCheck:
    """``flann synth``'s check of the netlist it just counted (temporary build directory)."""
    with tempfile.TemporaryDirectory(prefix="flann-netlist-") as tmp:
        return check_netlist(design, tmp, netlist=netlist)


__all__ = ["NetlistSweep", "NetlistCheck", "netlist_summary", "top_sweep", "sweep_of", "sweep_datapaths", "has_sweep_driver", "require_sweep_driver", "check_netlist", "check_rtl_netlist", "check_synthesized", "mapped_netlist", "compile_netlist", "run_netlist", "compare",
           "yosys_datdir"]
