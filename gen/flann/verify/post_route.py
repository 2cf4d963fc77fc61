"""Post-route simulation: the placed-and-routed iCE40 design, checked against the twin.

Flow: the ``.asc`` nextpnr wrote (the bitstream before packing, i.e. what the device will
do: every LUT's truth table, every routing switch, the block-RAM contents) → ``icebox_vlog``
(IceStorm: the configured chip as Verilog, its block RAMs as ``SB_RAM40_4K``, ports named
from the ``.pcf``) → Verilator with Yosys's iCE40 cell models (``<yosys datdir>/ice40/
cells_sim.v``) and the same sweep driver as the Spartan-II netlist
(:mod:`flann.verify.netlist`; a family design's weight image loaded first through its cfg port)
→ every input code compared with the twin in one pass.
"""

from __future__ import annotations

import dataclasses
import re
import shutil
import subprocess
import time
from pathlib import Path

from ..errors import FlannError
from ..hardware.target import Ice40Part
from ..hardware.design import Design
from .netlist import NetlistCheck, compare, compile_netlist, run_netlist, sweep_of, yosys_datdir
from .shards import cores

# cells_sim.v gives some cell inputs default values, which Verilator does not parse
DEFINES = ("NO_ICE40_DEFAULT_ASSIGNMENTS",)


def icebox_vlog() -> list[str]:
    exe = shutil.which("icebox_vlog")
    if exe is None:
        raise FlannError("icebox_vlog not found on PATH: run scripts/ensure_tools.sh (Debian package fpga-icestorm)")
    return [exe]


_HEADER_RE = re.compile(r"^module\s+(\S+)\s*\((.*?)\);[ \t]*$", re.M | re.S)


def non_ansi_header(verilog: str) -> str:
    """icebox_vlog declares the ports in the module header (ANSI style) and declares them again
    as wires/regs in the body, which Verilog-2001 allows only for a non-ANSI header: rewrite
    ``module m (input a, output [3:0] \\b );`` as ``module m (a, \\b ); input a; output [3:0] \\b ;``."""
    m = _HEADER_RE.search(verilog)
    if m is None:
        raise FlannError("icebox_vlog output has no module header")
    decls = [d.strip() for d in m.group(2).split(",") if d.strip()]
    names, lines = [], []
    for d in decls:
        last = d.split()[-1]
        sep = " " if last.startswith("\\") else ""  # an escaped identifier ends at white space
        names.append(last + sep)
        lines.append(f"{d}{sep};\n")
    head = f"module {m.group(1)} ({', '.join(names)});\n" + "".join(lines)
    return verilog[:m.start()] + head + verilog[m.end():].lstrip("\n")


def routed_verilog(asc: Path, pcf: Path, part: Ice40Part, top: str, out: Path) -> Path:
    r = subprocess.run([*icebox_vlog(), "-s", "-S", "-c", "-n", top, "-p", str(pcf), "-d", part.pins, str(asc)],
                       capture_output=True, text=True)
    if r.returncode != 0 or "module" not in r.stdout:
        raise FlannError(f"icebox_vlog failed on {asc.name}: {(r.stderr.strip().splitlines() or ['no output'])[-1]}")
    out.write_text(non_ansi_header(r.stdout))
    return out


def check_post_route(design: Design, asc: Path, pcf: Path, part: Ice40Part, build, progress=None,
                     image: dict | None = None) -> NetlistCheck:
    """Every input code through the routed design (a family design loaded with ``image``, else
    its last kept one)."""
    build = Path(build).resolve()
    build.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    sweep = sweep_of(design, image)
    netlist = routed_verilog(Path(asc), Path(pcf), part, sweep.top, build / "post_route.v")
    models = [yosys_datdir() / "ice40" / "cells_sim.v"]
    exe = compile_netlist(netlist, build / "verilator_post_route", sweep, models=models, defines=DEFINES)
    got = run_netlist(exe, sweep, build, shards=cores(), progress=progress)
    return dataclasses.replace(compare(sweep, got), simulator="icebox_vlog + Verilator (Yosys iCE40 cell models)",
                               seconds=time.monotonic() - t0, netlist=str(netlist))


def checker(design: Design, refuse: bool = False, image: dict | None = None):
    """The post-route check as :func:`flann.implement.ice40.implement` calls it: (asc, pcf, part,
    work) → summary.  ``refuse``: a routed design that disagrees with its twin raises (nothing
    is written then) instead of being reported; ``image``: a family design's weight image to load."""

    def check(asc, pcf, part, work) -> dict:
        res = check_post_route(design, asc, pcf, part, Path(work) / "post_route", image=image)
        if refuse and not res.passed:
            raise FlannError(f"the routed design of {design.directory} on {part.name} disagrees with its twin on "
                             f"{res.mismatches} of {res.codes_tested} samples (first: "
                             f"{res.first_mismatches}); no bitstream written")
        summary = res.summary()
        del summary["temperature_codes"]
        return summary

    return check


__all__ = ["check_post_route", "checker", "non_ansi_header", "routed_verilog"]
