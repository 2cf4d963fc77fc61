"""The external tools that turn generated VHDL into a mapped Spartan-II netlist.

``ghdl -a / --synth --std=93c --out=verilog`` (refusing inferred latches and multiple
drivers, with GHDL 2.0's Verilog-writer errata undone) → Yosys ``synth_xilinx -family xcv``
(cell counts, the mapped netlist, the flattened JSON for the timing estimate).  Both the
resource estimate (:mod:`flann.implement.synth`) and the mapped-netlist check
(:mod:`flann.verify.netlist`) run them; neither stage owns them.
"""

from __future__ import annotations

import functools
import json
import re
import shutil
import subprocess
from pathlib import Path

from . import __version__, cache
from .errors import FlannError
from .hardware.manifest import Manifest

FAMILY = "xcv"

# Yosys warnings that say nothing about the design (feature gaps of the xcv target).
BENIGN_YOSYS_WARNINGS = (
    "Shift register inference not yet supported for family xcv",
)


class SynthCheckError(FlannError):
    """The design synthesises to something that must not reach hardware (latch, multiple drivers)."""


def need_tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        raise FlannError(f"{name} not found on PATH: run scripts/ensure_tools.sh (Debian packages ghdl, yosys)")
    return path


_LATCH_RE = re.compile(r'^(?P<loc>[^\s:]+:\d+:\d+):.*latch infered for net "(?P<net>[^"]+)"', re.M)
_MULTI_RE = re.compile(r'^(?P<loc>[^\s:]+:\d+:\d+):.*multiple assignments for "(?P<net>[^"]+)"', re.M)


def _ghdl_errors(stderr: str, top: str) -> FlannError:
    latches = [f'"{m["net"]}" ({Path(m["loc"]).name})' for m in _LATCH_RE.finditer(stderr)]
    multi = [f'"{m["net"]}" ({Path(m["loc"]).name})' for m in _MULTI_RE.finditer(stderr)]
    if latches:
        return SynthCheckError(
            f"{top}: latch inferred for {', '.join(latches)}: assign the signal on every path "
            "of the combinational process, or register it in a clocked process"
        )
    if multi:
        return SynthCheckError(
            f"{top}: multiple drivers for {', '.join(multi)}: drive each signal from exactly one "
            "process or concurrent assignment"
        )
    return FlannError(f"ghdl --synth of {top} failed: {_first_problem(stderr)}")


def _first_problem(stderr: str) -> str:
    """The line that says what went wrong (GHDL prints notes about ROMs first)."""
    lines = [ln.strip() for ln in stderr.splitlines() if ln.strip()]
    if any("GHDL Bug occurred" in ln for ln in lines):
        where = next((ln for ln in lines if ln.startswith("raised ")), "")
        return f"GHDL crashed (internal error{': ' + where[7:] if where else ''}); the VHDL needs a workaround"
    for ln in lines:
        if "error" in ln.lower() and "note:" not in ln:
            return ln
    return next((ln for ln in lines if "note:" not in ln), lines[0] if lines else "no message")


_PMUX_RE = re.compile(
    r"(always @\*\n\s*case \([^\n]*\)\n)((?:[ \t]+[^\n]*:\s*(\S+)\s*<=[^\n]*\n)+)([ \t]*)endcase"
)


def complete_pmux_cases(verilog: str) -> tuple[str, int]:
    """Give GHDL's one-hot ``always @* case`` blocks a ``default: x <= 'bx``.

    GHDL writes the parallel mux of a VHDL ``case`` (all choices covered, one-hot select)
    as a combinational Verilog ``case`` without ``default``; Yosys cannot prove the select
    one-hot and infers a latch for the impossible remaining values.  GHDL has already
    checked the VHDL for real latches (it refuses them), so the missing selections are
    don't-cares.  Returns (text, number of such case blocks).
    """

    def fix(m: re.Match) -> str:
        body = m.group(2)
        if re.search(r"^\s*default\s*:", body, re.M):
            return m.group(0)
        indent = re.match(r"[ \t]*", body).group(0)
        return f"{m.group(1)}{body}{indent}default: {m.group(3)} <= 'bx;\n{m.group(4)}endcase"

    return _PMUX_RE.subn(fix, verilog)


# GHDL 2.0's Verilog writer (netlists-disp_verilog.adb) prints two net kinds so that Verilog
# reads another circuit than the VHDL describes:
#  * a constant wider than 32 bits (Const_Bit) as a string literal "0101..." (Verilog takes
#    each character as 8 bits of ASCII), e.g. the 36- and 42-bit constants of flann_norm;
#  * an arithmetic shift right (Id_Asr, numeric_std shift_right of a signed) as
#    `$signed(x) >> n`, a logical shift in Verilog, so negative values turn large positive.
# Later GHDL releases print N'b... and >>>.  Both forms are fixed in the text GHDL wrote
# (one net per statement, so the rewrite cannot straddle statements); the netlist
# simulation (flann.verify.netlist) checks the result against the twin.
_STRING_CONST_RE = re.compile(r'"([01xzXZ]+)"')
_ASR_RE = re.compile(r"(\$signed\((?:\\\S+ |[A-Za-z_][A-Za-z0-9_$]*)\)) >> ")


def repair_ghdl_verilog(verilog: str) -> tuple[str, int, int]:
    """Undo GHDL 2.0's Verilog-writer errata (wide constants as strings, >> for arithmetic
    shifts); returns (text, constants fixed, shifts fixed)."""
    text, n_const = _STRING_CONST_RE.subn(lambda m: f"{len(m.group(1))}'b{m.group(1).lower()}", verilog)
    text, n_asr = _ASR_RE.subn(r"\1 >>> ", text)
    if '"' in text:
        line = next(ln for ln in text.splitlines() if '"' in ln)
        raise FlannError(f"GHDL's Verilog has a literal this flow cannot read: {line.strip()}")
    return text, n_const, n_asr


def ghdl_to_verilog(man: Manifest, work: Path) -> Path:
    """Analyse and synthesise the manifest's files with GHDL; return the Verilog netlist."""
    ghdl = need_tool("ghdl")
    work = Path(work).resolve()  # GHDL runs with work as cwd: a relative --workdir would nest
    lib = work / "ghdl"
    lib.mkdir(parents=True, exist_ok=True)
    files = [str(f.resolve()) for f in man.files]
    a = subprocess.run(
        [ghdl, "-a", "--std=93c", f"--workdir={lib}", *files], capture_output=True, text=True, cwd=work
    )
    if a.returncode != 0:
        raise FlannError(f"ghdl -a --std=93c failed: {_first_problem(a.stderr)}")
    s = subprocess.run(
        [ghdl, "--synth", "--std=93c", f"--workdir={lib}", "--out=verilog", man.top],
        capture_output=True, text=True, cwd=work,
    )
    if s.returncode != 0:
        raise _ghdl_errors(s.stderr, man.top)
    out = work / f"{man.top}.v"
    text, _ = complete_pmux_cases(s.stdout)
    text, _, _ = repair_ghdl_verilog(text)
    out.write_text(text)
    return out


ABC_MODES = ("full", "fast")


NETLIST = "netlist.v"  # the mapped Spartan-II netlist, written next to stat.json
MAPPED_JSON = "mapped.json"  # the same netlist flattened, for the timing estimate (flann.implement.timing)


def yosys_script(verilog: str, top: str, abc: str = "full", stat: str = "stat.json") -> str:
    """The Yosys script.  ``abc="full"`` is ``synth_xilinx -family xcv`` with its coarse step run
    here, its memory pass with ``-nowiden`` (below).

    ``abc="fast"`` runs the same synth_xilinx steps but replaces its LUT-mapping ABC
    script (fraig, scorr, dch, mfs2: minutes to hours on wide multipliers) by ``abc -fast``;
    the map_luts commands are those synth_xilinx runs for a LUT4 family (Yosys 0.23
    synth_xilinx.cc; xilinx_srl is skipped for xcv).  Counts come out a little higher.
    """
    if abc not in ABC_MODES:
        raise FlannError(f"abc mode {abc!r}: allowed {', '.join(ABC_MODES)}")
    # synth_xilinx's coarse step with `memory -nowiden`: two ports written at addr & 0 and addr & 1
    # (the family's weight memory) stay the two ports of one RAMB4_S16_S16, as XST maps them, not
    # one wide port of two RAMB4_S16
    head = [f"read_verilog {verilog}", f"synth_xilinx -family {FAMILY} -top {top} -run begin:coarse",
            "techmap -map +/cmp2lut.v -map +/cmp2lcu.v -D LUT_WIDTH=4", "alumacc", "share", "opt",
            "memory -nomap -nowiden", "opt_clean"]
    # the netlist the counts describe, flattened, for post-synthesis simulation (flann.verify.
    # netlist): its vectors split into one net per bit, since a vector feeding back into itself
    # through cells (a carry chain) is a loop to Verilator, which then mis-simulated a thermal
    # design's clamp (563 of 8192 samples; Icarus and the split netlist agree with the twin);
    # wires nothing reads go first (a constant table's, split, is a line Verilator refuses)
    tail = ["check -assert", f"tee -q -o {stat} stat -json",
            # flattening and dropping the cell library change nothing counted above
            "flatten", "delete =A:blackbox", f"write_json {MAPPED_JSON}",
            "opt_clean -purge", "splitnets", f"write_verilog -noattr {NETLIST}"]
    if abc == "full":
        return "; ".join(head + [f"synth_xilinx -family {FAMILY} -top {top} -run map_memory:"] + tail)
    return "; ".join(head + [
        f"synth_xilinx -family {FAMILY} -top {top} -run map_memory:map_luts",
        "opt_expr -mux_undef -noclkinv",
        "abc -fast -lut 4:6",  # LUT4 plus MUXF5/MUXF6 wide functions, as synth_xilinx maps xcv
        "clean",
        "techmap -map +/xilinx/ff_map.v",
        "techmap -map +/xilinx/lut_map.v -map +/xilinx/cells_map.v -D LUT_WIDTH=4",
        "xilinx_dffopt -lut4",
        "opt_lut_ins -tech xilinx",
        f"synth_xilinx -family {FAMILY} -top {top} -run finalize:",
    ] + tail)


# Yosys 0.23's `stat -json` writes the text of its design hierarchy ("  name  count" lines) into
# the JSON when the hierarchy is more than one level deep (a top instantiating tops)
_HIERARCHY_LINE = re.compile(r"^\s+[A-Za-z_\\$][^\s\"]*\s+\d+\s*$")


def _stat_json(text: str) -> str:
    return "\n".join(ln for ln in text.splitlines() if not _HIERARCHY_LINE.match(ln))


def yosys_cells(verilog: Path, top: str, work: Path, abc: str = "full") -> tuple[dict[str, int], list[str]]:
    """Run Yosys synth_xilinx -family xcv; return (cells by type, warnings that matter)."""
    yosys = need_tool("yosys")
    work = Path(work).resolve()
    stat = work / "stat.json"
    log = work / "yosys.log"
    script = yosys_script(verilog.name, top, abc, stat.name)
    r = subprocess.run([yosys, "-q", "-l", log.name, "-p", script], capture_output=True, text=True, cwd=work)
    text = log.read_text() if log.exists() else r.stderr
    if r.returncode != 0:
        err = next((ln for ln in (r.stderr + text).splitlines() if "ERROR" in ln), "see yosys log")
        if "check -assert" in err:   # the netlist was built, and it has multiple drivers or loops
            last_check = text.rsplit("Executing CHECK pass", 1)[-1]
            found = [ln[len("Warning:"):].strip() for ln in last_check.splitlines() if ln.startswith("Warning:")]
            raise SynthCheckError(f"{top}: yosys check failed: {found[0] if found else err.strip()}")
        raise FlannError(f"yosys synth_xilinx -family {FAMILY} failed: {err.strip()}")
    warnings = []
    for ln in text.splitlines():
        if ln.startswith("Warning:"):
            msg = ln[len("Warning:"):].strip()
            if not any(b in msg for b in BENIGN_YOSYS_WARNINGS) and msg not in warnings:
                warnings.append(msg)
    data = json.loads(_stat_json(stat.read_text()))
    cells = data["design"]["num_cells_by_type"]
    (work / "modules.json").write_text(json.dumps({
        str(name).lstrip("\\"): mod.get("num_cells_by_type", {}) for name, mod in data.get("modules", {}).items()
    }))
    return {str(k): int(v) for k, v in cells.items()}, warnings


@functools.lru_cache(maxsize=None)
def tool_version(name: str, flag: str = "--version") -> str:
    """The first line ``name flag`` prints (part of every cache key the tool's output enters)."""
    r = subprocess.run([need_tool(name), flag], capture_output=True, text=True)
    return (r.stdout or r.stderr).strip().splitlines()[0] if (r.stdout or r.stderr).strip() else ""


CELLS_JSON = "cells.json"  # the cell counts and the warnings that matter, as yosys_cells returns them


def design_key(man: Manifest, *parts) -> str:
    """The cache key of a flow from ``man``'s VHDL through GHDL's synthesis (this module) and
    ``parts`` (the later tools' versions, their flow's source and options)."""
    return cache.key(__version__, tool_version("ghdl"), Path(__file__), man.top, *parts,
                     *[x for f in man.files for x in (f.name, f)])


def synthesize_cells(man: Manifest, work: Path, abc: str = "full") -> tuple[dict[str, int], list[str]]:
    """:func:`ghdl_to_verilog` then :func:`yosys_cells` into ``work`` (its files: GHDL's Verilog,
    ``stat.json``, ``modules.json``, the mapped netlist and its JSON), once per design: a design
    synthesised before with the same files, tools and flow is taken from :mod:`flann.cache`."""
    work = Path(work).resolve()
    names = [f"{man.top}.v", "stat.json", "modules.json", MAPPED_JSON, NETLIST, "yosys.log", CELLS_JSON]
    digest = design_key(man, tool_version("yosys", "-V"), yosys_script("design.v", man.top, abc))
    with cache.entry("synth", digest, work, names) as hit:
        if not hit:
            verilog = ghdl_to_verilog(man, work)
            cells, warnings = yosys_cells(verilog, man.top, work, abc)
            (work / CELLS_JSON).write_text(json.dumps({"cells": cells, "warnings": warnings}))
    data = json.loads((work / CELLS_JSON).read_text())
    return data["cells"], data["warnings"]


__all__ = ["ABC_MODES", "CELLS_JSON", "design_key", "synthesize_cells", "tool_version", "BENIGN_YOSYS_WARNINGS", "FAMILY", "MAPPED_JSON", "NETLIST", "SynthCheckError",
           "complete_pmux_cases", "ghdl_to_verilog", "need_tool", "repair_ghdl_verilog", "yosys_cells", "yosys_script"]
