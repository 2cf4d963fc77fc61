"""Resource estimate of generated VHDL for a Spartan-II.

Flow: ``DIR/manifest.json`` (top entity, files in compile order) → ``ghdl -a --std=93c``
→ ``ghdl --synth --std=93c --out=verilog`` (fails on inferred latches and multiple
assignments) → Yosys ``synth_xilinx -family xcv`` (Yosys's Virtex / Spartan-II target) →
cell counts → utilisation of the target part (:mod:`flann.hardware.target`).

The numbers are a synthesis estimate, not a place-and-route result: ISE's XST maps
differently and the packer may not pair every LUT with a flip-flop.  The check is
"fits before place and route"; the ISE handoff (:mod:`flann.implement.ise`) gives the final word.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from ..hardware.design import Design, as_design
from ..hardware.manifest import Manifest
from ..hardware.target import CLOCK_HZ, DEFAULT_PART, DEVICES, Part, parse_part
from ..eda import ABC_MODES, FAMILY, MAPPED_JSON, SynthCheckError, need_tool, synthesize_cells
from ..errors import FlannError
from . import timing as spartan2_timing

# LUT4 sites used per cell (Virtex/Spartan-II library): INV is a LUT1, distributed RAM
# and SRL16 live in LUTs.
_LUT_SITES = {
    "LUT1": 1, "LUT2": 1, "LUT3": 1, "LUT4": 1, "INV": 1,
    "SRL16": 1, "SRL16E": 1, "SRL16_1": 1, "SRL16E_1": 1,
    "RAM16X1S": 1, "RAM16X1S_1": 1, "RAM16X1D": 2, "RAM16X1D_1": 2,
    "RAM32X1S": 2, "RAM32X1S_1": 2,
}
_IO_CELLS = ("IBUF", "IBUFG", "OBUF", "OBUFT", "IOBUF")


@dataclass(frozen=True)
class Resources:
    luts: int
    ffs: int
    brams: int
    carry: int  # MUXCY: one per carry-chain bit
    xorcy: int
    mult_and: int
    muxf5: int
    muxf6: int
    io: int  # user I/O pins (clock input on a global clock pin not counted)
    cells: dict = field(default_factory=dict)

    @classmethod
    def from_cells(cls, cells: dict[str, int]) -> "Resources":
        unknown_latches = sorted(c for c in cells if c.startswith("LD") or c.startswith("$_DLATCH"))
        if unknown_latches:
            raise SynthCheckError(f"synthesis produced latches ({', '.join(unknown_latches)}): every storage element must be a clocked flip-flop")
        luts = sum(n * _LUT_SITES.get(c, 0) for c, n in cells.items())
        ffs = sum(n for c, n in cells.items() if c.startswith("FD"))
        brams = sum(n for c, n in cells.items() if c.startswith("RAMB4"))
        io = sum(n for c, n in cells.items() if c in _IO_CELLS)
        gclk = min(cells.get("BUFG", 0), 4)  # clocks enter on dedicated GCK pins, not user I/O
        return cls(
            luts=luts,
            ffs=ffs,
            brams=brams,
            carry=cells.get("MUXCY", 0),
            xorcy=cells.get("XORCY", 0),
            mult_and=cells.get("MULT_AND", 0),
            muxf5=cells.get("MUXF5", 0),
            muxf6=cells.get("MUXF6", 0),
            io=max(io - gclk, 0),
            cells=dict(sorted(cells.items())),
        )


def shortfall(res: Resources, part: Part) -> list[str]:
    """What does not fit on ``part`` (empty when it fits)."""
    d = part.device
    out = []
    if res.luts > d.luts:
        out.append(f"{res.luts} LUT4 > {d.luts}")
    if res.ffs > d.ffs:
        out.append(f"{res.ffs} flip-flops > {d.ffs}")
    if res.brams > d.brams:
        out.append(f"{res.brams} block RAMs > {d.brams}")
    if res.io > part.user_io:
        out.append(f"{res.io} user I/O > {part.user_io} on {part.package}")
    return out


def smallest_fit(res: Resources, part: Part) -> Part | None:
    """Smallest Spartan-II that fits, preferring the target's package and speed grade."""
    for d in DEVICES:
        if d.user_io(part.package) is not None:
            cand = Part(d, part.package, part.speed)
            if not shortfall(res, cand):
                return cand
    for d in DEVICES:  # any package, fewest pins that suffice
        for pkg, _io in sorted(d.packages, key=lambda p: p[1]):
            cand = Part(d, pkg, part.speed)
            if not shortfall(res, cand):
                return cand
    return None


def _pct(used: int, avail: int) -> float:
    return round(100.0 * used / avail, 1) if avail else 0.0


@dataclass(frozen=True)
class SynthReport:
    part: Part
    top: str
    resources: Resources
    warnings: tuple[str, ...]
    manifest: dict
    abc: str = "full"
    entities: dict = field(default_factory=dict)
    timing: spartan2_timing.Timing | None = None
    # the mapped netlist simulated against the twin: {codes, mismatches, passed, simulator},
    # or None with why it was not run
    netlist_check: dict | None = None
    netlist_not_run: str = ""
    netlist_warning: str = ""   # why the netlist check could not run, when the user should act on it

    @property
    def fits(self) -> bool:
        return not shortfall(self.resources, self.part)

    @property
    def smallest(self) -> Part | None:
        return smallest_fit(self.resources, self.part)

    def all_warnings(self) -> list[str]:
        """Every warning of this synthesis, as flann synth prints them and its JSON lists them."""
        out = [f"yosys: {w}" for w in self.warnings]
        if self.netlist_warning:
            out.append(self.netlist_warning)
        if self.timing and not self.timing.meets(CLOCK_HZ):
            out.append(f"{self.top} is estimated at {self.timing.fmax_mhz:.1f} MHz on {self.part.name}, below the "
                       f"design's clock {CLOCK_HZ / 1e6:g} MHz: run it at most at "
                       f"{spartan2_timing.safe_clock_mhz(self.timing):g} MHz (flann ise writes that PERIOD)")
        return out

    def to_dict(self) -> dict:
        r, d = self.resources, self.part.device
        smallest = self.smallest
        return {
            "device": self.part.name,
            "luts": r.luts,
            "ffs": r.ffs,
            "brams": r.brams,
            "lut_pct": _pct(r.luts, d.luts),
            "ff_pct": _pct(r.ffs, d.ffs),
            "bram_pct": _pct(r.brams, d.brams),
            "fits": self.fits,
            "smallest_device": smallest.name if smallest else None,
            # details beyond the keys
            "carry": r.carry,
            "xorcy": r.xorcy,
            "mult_and": r.mult_and,
            "muxf5": r.muxf5,
            "muxf6": r.muxf6,
            "io": r.io,
            "io_available": self.part.user_io,
            "device_luts": d.luts,
            "device_ffs": d.ffs,
            "device_brams": d.brams,
            "top": self.top,
            "cycles_per_sample": self.manifest.get("cycles_per_sample"),
            "latency_cycles": self.manifest.get("latency_cycles"),
            "timing": self.timing.to_dict(CLOCK_HZ) if self.timing else None,
            "netlist_check": self.netlist_check,
            "cells": r.cells,
            "entities": self.entities,
            "warnings": self.all_warnings(),
            "yosys_warnings": list(self.warnings),
            "flow": f"ghdl --synth --std=93c --out=verilog | yosys synth_xilinx -family {FAMILY}"
                    + (" (abc -fast)" if self.abc == "fast" else ""),
        }

    def table(self) -> str:
        r, d = self.resources, self.part.device
        rows = [
            ("LUT4", r.luts, d.luts),
            ("flip-flops", r.ffs, d.ffs),
            ("block RAM (4 Kbit)", r.brams, d.brams),
            ("user I/O", r.io, self.part.user_io),
        ]
        how = " with abc -fast" if self.abc == "fast" else ""
        lines = [f"{self.top} on {self.part.name} (yosys synth_xilinx -family {FAMILY}{how})"]
        for name, used, avail in rows:
            lines.append(f"  {name:<20} {used:>6} / {avail:<6} {_pct(used, avail):5.1f} %")
        # counts of two cell kinds each, not used / available as in the rows above
        lines.append(f"  {'MUXCY, XORCY':<20} {r.carry:>6}, {r.xorcy} (carry chain cells)")
        lines.append(f"  {'MUXF5, MUXF6':<20} {r.muxf5:>6}, {r.muxf6}")
        if len(self.entities) > 1:
            lines.append("  per entity (LUT4 / FF / BRAM): " + ", ".join(
                f"{n} {e['luts']}/{e['ffs']}/{e['brams']}" for n, e in self.entities.items()))
        cps = self.manifest.get("cycles_per_sample")
        if cps:
            lines.append(f"  {'cycles per sample':<20} {cps:>6}")
        if self.timing is None:
            lines.append(f"  {'Fmax estimate':<20}   none: no register-to-register path (a combinational block)")
        else:
            t = self.timing
            lines.append(f"  {'Fmax estimate':<20} {t.fmax_mhz:6.1f} MHz (-{t.grade}: {t.logic_levels} LUT levels, "
                         f"{t.carry_bits} carry bits, {t.delay_ns:.1f} ns; DS001 figures + routing allowance)")
            if not t.meets(CLOCK_HZ):
                lines.append(f"  DOES NOT MEET the design's clock {CLOCK_HZ / 1e6:g} MHz (estimate)")
        n = self.netlist_check
        if n is not None:
            temps = n.get("temperature_codes")
            what = f"samples (every input code x {temps} temperature codes)" if temps else "input codes"
            lines.append(f"  {'netlist check':<20} {n['codes']:>6} {what} simulated on the mapped netlist "
                         f"({n['simulator']}), {n['mismatches']} mismatches with the twin: "
                         + ("passed" if n["passed"] else "FAILED"))
        elif self.netlist_not_run:
            lines.append(f"  {'netlist check':<20} not run: {self.netlist_not_run}")
        if self.fits:   # then the part itself bounds the smallest that fits
            smallest = self.smallest.name
            lines.append(f"  fits {self.part.name}; smallest device that fits: "
                         + ("this one" if smallest == self.part.name else smallest))
        else:
            lines.append(f"  DOES NOT FIT {self.part.name}: {'; '.join(shortfall(r, self.part))}")
        return "\n".join(lines)


def entity_breakdown(modules: dict[str, dict[str, int]]) -> dict[str, dict[str, int]]:
    """LUT4 / FF / block RAM per entity (synth_xilinx keeps GHDL's hierarchy; cells of one
    module only, instances of sub-entities are not counted inside their parent)."""
    out = {}
    for name, cells in sorted(modules.items()):
        cells = {str(k): int(v) for k, v in cells.items() if not str(k).startswith("\\")}
        out[name] = {
            "luts": sum(n * _LUT_SITES.get(c, 0) for c, n in cells.items()),
            "ffs": sum(n for c, n in cells.items() if c.startswith("FD")),
            "brams": sum(n for c, n in cells.items() if c.startswith("RAMB4")),
        }
    return out


def manifest_device(man: Manifest) -> str:
    """The part the design was generated for (manifest spec.device), else the generator's default part."""
    spec = man.data.get("spec")
    dev = spec.get("device") if isinstance(spec, dict) else None
    return dev if isinstance(dev, str) and dev else DEFAULT_PART


def synthesize(design: Design | str | Path, device: str | None = None, work: str | Path | None = None,
               progress: bool = False, abc: str = "full") -> SynthReport:
    """Full flow for one generated design directory.  ``work`` keeps the intermediate files.

    ``device`` defaults to the part recorded in the manifest (``flann gen --device``).
    """
    man = as_design(design).manifest
    part = parse_part(device if device is not None else manifest_device(man))
    if abc not in ABC_MODES:
        raise FlannError(f"--abc {abc!r}: allowed {', '.join(ABC_MODES)}")
    need_tool("ghdl")
    need_tool("yosys")
    with tempfile.TemporaryDirectory(prefix="flann-synth-") as tmp:
        # absolute: GHDL and Yosys run with the work directory as cwd
        wdir = Path(work).resolve() if work is not None else Path(tmp)
        wdir.mkdir(parents=True, exist_ok=True)
        if progress:
            print(f"synth: ghdl --synth --std=93c {man.top} ({len(man.files)} files), then yosys synth_xilinx "
                  f"-family {FAMILY}, abc {abc} (minutes for wide multipliers; once per design, then cached)",
                  file=sys.stderr)
        cells, warnings = synthesize_cells(man, wdir, abc)
        modules = entity_breakdown(json.loads((wdir / "modules.json").read_text()))
        est = spartan2_timing.analyse(wdir / MAPPED_JSON, part, man.top)
    return SynthReport(part, man.top, Resources.from_cells(cells), tuple(warnings), man.data, abc, modules, est)


def not_fit_message(report: SynthReport) -> str:
    short = "; ".join(shortfall(report.resources, report.part))
    best = report.smallest
    if best is not None:
        return f"{report.top} does not fit {report.part.name} ({short}); smallest Spartan-II that fits: {best.name}"
    biggest = DEVICES[-1]
    return (
        f"{report.top} does not fit {report.part.name} ({short}) nor any Spartan-II "
        f"(largest: {biggest.name}, {biggest.luts} LUT4, {biggest.brams} block RAMs): "
        "generate a smaller datapath (fewer lanes, a serial multiplier or narrower words)"
    )



# --------------------------------------------------------------------------- VSG lint
def find_vsg_config(start: str | Path | None = None) -> Path | None:
    """The repository's vsg.yaml: searched upwards from ``start``, the cwd and the package."""
    roots = [Path(start).resolve()] if start is not None else []
    roots += [Path.cwd(), Path(__file__).resolve().parent]
    for root in roots:
        for d in (root, *root.parents):
            cand = d / "vsg.yaml"
            if cand.is_file():
                return cand
    return None


def lint_vhdl(files, config: str | Path | None = None, start: str | Path | None = None) -> list[str]:
    """Run VSG (all phases) on ``files``; return violations as 'file(line) rule -- message'.

    Raises FlannError when vsg or the configuration is missing: a lint that silently does
    nothing would read as a pass.
    """
    sibling = Path(sys.executable).with_name("vsg")  # the venv's vsg when the venv is not activated
    vsg = shutil.which("vsg") or (str(sibling) if sibling.exists() else None)
    if vsg is None:
        raise FlannError("vsg not found: install the dev extras (pip install -e '.[dev]') or pass --no-lint")
    cfg = Path(config) if config is not None else find_vsg_config(start)
    if cfg is None or not cfg.is_file():
        raise FlannError(f"VSG configuration {cfg or 'vsg.yaml'} not found: pass --vsg-config or --no-lint")
    with tempfile.TemporaryDirectory(prefix="flann-vsg-") as tmp:
        out = Path(tmp) / "vsg.json"
        r = subprocess.run(
            [vsg, "-c", str(cfg), "-ap", "-p", "1", "-js", str(out), "-of", "syntastic",
             "-f", *[str(f) for f in files]],
            capture_output=True, text=True,
        )
        if not out.exists():
            first = next((ln for ln in (r.stdout + r.stderr).splitlines() if ln.strip()), "no output")
            raise FlannError(f"vsg failed: {first}")
        data = json.loads(out.read_text())
    violations = []
    for f in data.get("files", []):
        for v in f.get("violations", []):
            if str(v.get("severity", "Error")).lower() == "error":
                violations.append(f"{Path(f['file_path']).name}({v.get('linenumber')}) {v['rule']} -- {v.get('solution', '')}")
    return violations


def check_lint(files, config: str | Path | None = None, start: str | Path | None = None) -> None:
    violations = lint_vhdl(files, config, start)
    if violations:
        more = f" (+{len(violations) - 3} more)" if len(violations) > 3 else ""
        raise FlannError(f"VSG style check failed, {len(violations)} violations: " + "; ".join(violations[:3]) + more)
