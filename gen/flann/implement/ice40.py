"""iCE40: real place and route, static timing and a bitstream with the open-source flow.

Flow: ``DIR/manifest.json`` → GHDL synthesis (:func:`flann.eda.ghdl_to_verilog`,
the same repaired Verilog the Spartan-II flow maps) → Yosys ``synth_ice40`` → ``nextpnr-ice40``
(placement, routing, static timing at the design's clock; ``--report`` JSON: Fmax and
utilisation) → ``icepack`` (the ``.bin`` bitstream).  The output directory holds the
bitstream, the ``.asc`` it was packed from, an example pin file (``.pcf``: the pins nextpnr
chose, an *example assignment* to edit for a board), nextpnr's report and ``ice40.json``
(this report).

The Spartan-II is still the design's target; the iCE40 run answers "does it place, route and
close timing on a real 4-input-LUT FPGA", with the same kind of 4 Kbit block RAMs.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from .. import cache
from ..eda import design_key, ghdl_to_verilog, need_tool, tool_version
from ..errors import FlannError
from ..fileio import atomic_directory, check_output_directory
from ..hardware.design import as_design
from ..hardware.target import CLOCK_HZ, Ice40Part, parse_ice40

SYNTH_JSON = "synth_ice40.json"
ROUTED_JSON = "routed.json"
NEXTPNR_REPORT = "nextpnr_report.json"
REPORT = "ice40.json"  # this flow's report; also marks an output directory as ours
CHIPDB_DIRS = (Path("/usr/share/fpga-icestorm/chipdb"), Path("/usr/share/icebox"),
               Path("/usr/local/share/icebox"))


def _tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        raise FlannError(f"{name} not found on PATH: run scripts/ensure_tools.sh "
                         "(Debian packages nextpnr-ice40, fpga-icestorm)")
    return path


def chipdb(part: Ice40Part) -> Path:
    for d in CHIPDB_DIRS:
        f = d / f"chipdb-{part.chipdb}.txt"
        if f.is_file():
            return f
    raise FlannError(f"IceStorm chip database chipdb-{part.chipdb}.txt not found "
                     f"(searched {', '.join(map(str, CHIPDB_DIRS))}; Debian package fpga-icestorm-chipdb)")


def _section(part: Ice40Part, header: list[str]) -> list[list[str]]:
    """The rows of one section of the chip database (``.pins ct256``, ``.gbufpin``)."""
    rows, inside = [], False
    for line in chipdb(part).read_text().splitlines():
        if line.startswith("."):
            inside = line.split() == header
            continue
        if inside and line.strip():
            rows.append(line.split())
    return rows


def package_pins(part: Ice40Part) -> dict[tuple[int, int, int], str]:
    """(x, y, z) of every I/O site → package pin name, from the chip database's ``.pins`` section."""
    pins = {(int(x), int(y), int(z)): name for name, x, y, z in _section(part, [".pins", part.pins])}
    if not pins:
        raise FlannError(f"chipdb-{part.chipdb}.txt has no pins for package {part.pins}")
    return pins


def global_clock_pins(part: Ice40Part) -> list[str]:
    """Bonded package pins that drive a global network directly (``.gbufpin``), in network order."""
    pins = package_pins(part)
    sites = [(int(x), int(y), int(z)) for x, y, z, _glb in _section(part, [".gbufpin"])]
    return [pins[s] for s in sites if s in pins]


_BEL_RE = re.compile(r"^X(\d+)/Y(\d+)/io(\d)$")


def example_pcf(routed: dict, part: Ice40Part, top: str) -> str:
    """``set_io`` for every port bit at the pin nextpnr placed it on."""
    mod = routed["modules"].get(top) or next(iter(routed["modules"].values()))
    pins = package_pins(part)
    lines = []
    for name, cell in mod["cells"].items():
        if cell["type"] != "SB_IO":
            continue
        m = _BEL_RE.match(cell.get("attributes", {}).get("NEXTPNR_BEL", ""))
        if not m:
            raise FlannError(f"nextpnr left I/O cell {name} unplaced")
        site = tuple(int(v) for v in m.groups())
        if site not in pins:
            raise FlannError(f"I/O site {site} of {name} is not bonded in {part.package}")
        lines.append((name.split("$")[0], pins[site]))
    lines.sort()
    head = [f"# {top} on {part.name}: EXAMPLE ASSIGNMENT (clk on a global clock input pin, the other pins "
            "nextpnr chose); edit it for your board.",
            "# Written by flann synth --device " + part.name + "."]
    return "\n".join(head + [f"set_io {net} {pin}" for net, pin in lines]) + "\n"


@dataclass(frozen=True)
class Ice40Report:
    part: Ice40Part
    top: str
    cells: dict
    logic_cells: int
    brams: int
    io: int
    fmax_mhz: float | None
    clock_mhz: float
    output: str
    seconds: float
    post_route: dict | None = None
    warnings: tuple = field(default_factory=tuple)

    @property
    def luts(self) -> int:
        return self.cells.get("SB_LUT4", 0)

    @property
    def ffs(self) -> int:
        return sum(n for c, n in self.cells.items() if c.startswith("SB_DFF"))

    @property
    def timing_met(self) -> bool:
        return self.fmax_mhz is not None and self.fmax_mhz >= self.clock_mhz

    def all_warnings(self) -> list[str]:
        """Every warning of this run, as flann synth prints them and its JSON lists them."""
        out = list(self.warnings)
        if not self.timing_met:
            out.append(f"{self.top} on {self.part.name}: nextpnr's Fmax {self.fmax_mhz or 0:.1f} MHz is below "
                       f"the design's clock {self.clock_mhz:g} MHz")
        return out

    @property
    def bitstream(self) -> str:
        return str(Path(self.output) / f"{self.top}.bin")

    @property
    def pcf(self) -> str:
        return str(Path(self.output) / f"{self.top}.pcf")

    def to_dict(self) -> dict:
        return {
            "device": self.part.name,
            "luts": self.luts,
            "ffs": self.ffs,
            "brams": self.brams,
            "logic_cells": self.logic_cells,
            "lc_pct": round(100.0 * self.logic_cells / self.part.logic_cells, 1),
            "bram_pct": round(100.0 * self.brams / self.part.brams, 1),
            "carry": self.cells.get("SB_CARRY", 0),
            "io": self.io,
            "fmax_mhz": None if self.fmax_mhz is None else round(self.fmax_mhz, 2),
            "clock_mhz": self.clock_mhz,
            "timing_met": self.timing_met,
            "bitstream": self.bitstream,
            "pcf": self.pcf,
            "post_route": self.post_route,
            "top": self.top,
            "cells": dict(sorted(self.cells.items())),
            "seconds": round(self.seconds, 1),
            "warnings": self.all_warnings(),
            "flow": (f"ghdl --synth --std=93c --out=verilog | yosys synth_ice40 | nextpnr-ice40 --{self.part.nextpnr} "
                     f"--package {self.part.package} --freq {self.clock_mhz:g} | icepack"),
        }

    def table(self) -> str:
        p = self.part
        lines = [f"{self.top} on {p.name} (yosys synth_ice40, nextpnr-ice40 place and route, icepack)",
                 f"  {'LUT4':<20} {self.luts:>6}",
                 f"  {'flip-flops':<20} {self.ffs:>6}",
                 f"  {'logic cells':<20} {self.logic_cells:>6} / {p.logic_cells:<6} "
                 f"{100.0 * self.logic_cells / p.logic_cells:5.1f} %",
                 f"  {'block RAM (4 Kbit)':<20} {self.brams:>6} / {p.brams:<6} {100.0 * self.brams / p.brams:5.1f} %",
                 f"  {'Fmax (nextpnr)':<20} {self.fmax_mhz or 0:6.1f} MHz, clock {self.clock_mhz:g} MHz: "
                 + ("met" if self.timing_met else "NOT MET"),
                 f"  bitstream {self.bitstream}, example pins {self.pcf}"]
        if self.post_route is not None:
            pr = self.post_route
            lines.append(f"  post-route simulation {pr['codes_tested']} codes, {pr['mismatches']} mismatches "
                         f"({pr['simulator']})")
        return "\n".join(lines)


def _is_ice40_output(directory: Path) -> bool:
    return (directory / REPORT).is_file()


def _first_error(log: Path, fallback: str) -> str:
    text = log.read_text(errors="replace") if log.exists() else fallback
    return next((ln.strip() for ln in text.splitlines() if ln.startswith("ERROR")), fallback.strip()[:200] or "see log")


def yosys_ice40(verilog: Path, top: str, work: Path) -> dict[str, int]:
    """Yosys ``synth_ice40``; writes the JSON netlist nextpnr reads; returns cells by type."""
    yosys = need_tool("yosys")
    script = (f"read_verilog {verilog.name}; synth_ice40 -top {top} -json {SYNTH_JSON}; "
              "tee -q -o stat_ice40.json stat -json")
    r = subprocess.run([yosys, "-q", "-l", "yosys_ice40.log", "-p", script], capture_output=True, text=True, cwd=work)
    if r.returncode != 0:
        raise FlannError(f"yosys synth_ice40 failed: {_first_error(work / 'yosys_ice40.log', r.stderr)}")
    data = json.loads((work / "stat_ice40.json").read_text())
    return {str(k): int(v) for k, v in data["design"]["num_cells_by_type"].items()}


CLOCK_PORT = "clk"


def place_and_route(part: Ice40Part, top: str, work: Path, clock_mhz: float, seed: int = 1) -> dict:
    """nextpnr-ice40: placement, routing and timing; returns its ``--report`` JSON.  The clock is
    put on a global clock input pin; nextpnr places the other ports."""
    gbin = global_clock_pins(part)
    if not gbin:
        raise FlannError(f"{part.name}: no global clock input pin bonded in {part.package}")
    (work / "clock.pcf").write_text(f"set_io {CLOCK_PORT} {gbin[0]}\n")
    cmd = [_tool("nextpnr-ice40"), f"--{part.nextpnr}", "--package", part.package, "--json", SYNTH_JSON,
           "--pcf", "clock.pcf", "--pcf-allow-unconstrained",
           "--write", ROUTED_JSON, "--asc", f"{top}.asc", "--report", NEXTPNR_REPORT, "--freq", f"{clock_mhz:g}",
           "--seed", str(seed), "--timing-allow-fail", "-q", "-l", "nextpnr.log"]
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=work)
    if r.returncode != 0 or not (work / NEXTPNR_REPORT).is_file():
        raise FlannError(f"nextpnr-ice40 on {part.name} failed: {_first_error(work / 'nextpnr.log', r.stderr)}")
    return json.loads((work / NEXTPNR_REPORT).read_text())


def fmax_of(report: dict) -> float | None:
    """The slowest clock's achieved frequency (MHz) in nextpnr's report."""
    clocks = report.get("fmax", {})
    vals = [float(c["achieved"]) for c in clocks.values() if "achieved" in c]
    return min(vals) if vals else None


CELLS_JSON = "ice40_cells.json"


def _synth_place_route(man, part: Ice40Part, wdir: Path, clock_mhz: float, seed: int, say) -> None:
    """GHDL synthesis, Yosys synth_ice40, nextpnr and icepack in ``wdir``."""
    say(f"ghdl --synth --std=93c {man.top}")
    verilog = ghdl_to_verilog(man, wdir)
    say("yosys synth_ice40")
    cells = yosys_ice40(verilog, man.top, wdir)
    luts = cells.get("SB_LUT4", 0)
    brams_needed = sum(n for c, n in cells.items() if c.startswith("SB_RAM40"))
    if luts > part.logic_cells or brams_needed > part.brams:
        raise FlannError(f"{man.top} does not fit {part.name}: {luts} LUT4 (of {part.logic_cells} logic cells), "
                         f"{brams_needed} block RAMs (of {part.brams})")
    say(f"nextpnr-ice40 --{part.nextpnr} --package {part.package} --freq {clock_mhz:g} (place, route, timing)")
    place_and_route(part, man.top, wdir, clock_mhz, seed)
    routed = json.loads((wdir / ROUTED_JSON).read_text())
    (wdir / f"{man.top}.pcf").write_text(example_pcf(routed, part, man.top))
    say("icepack")
    r = subprocess.run([_tool("icepack"), f"{man.top}.asc", f"{man.top}.bin"], capture_output=True, text=True,
                       cwd=wdir)
    if r.returncode != 0:
        raise FlannError(f"icepack failed: {r.stderr.strip() or r.returncode}")
    (wdir / CELLS_JSON).write_text(json.dumps(cells))


def implement(directory, device: str, out_dir, *, work=None, seed: int = 1, progress: bool = False,
              post_route=None) -> Ice40Report:
    """The whole iCE40 flow for one design directory; writes ``out_dir`` as a whole.

    ``post_route``: a callable (asc, pcf, part, work) → dict run before the output is
    committed (the post-route simulation), or None."""
    t0 = time.monotonic()
    part = parse_ice40(device)
    man = as_design(directory).manifest
    check_output_directory(out_dir, _is_ice40_output, "flann iCE40 build")   # before minutes of work
    for name in ("ghdl", "yosys", "nextpnr-ice40", "icepack"):
        _tool(name)
    clock_mhz = CLOCK_HZ / 1e6
    say = (lambda msg: print(f"synth: {msg}", file=sys.stderr)) if progress else (lambda msg: None)
    with tempfile.TemporaryDirectory(prefix="flann-ice40-") as tmp:
        wdir = Path(work).resolve() if work is not None else Path(tmp)
        wdir.mkdir(parents=True, exist_ok=True)
        # synthesis, place and route and the bitstream once per design, part, clock and seed
        names = [f"{man.top}.asc", f"{man.top}.bin", f"{man.top}.pcf", NEXTPNR_REPORT, ROUTED_JSON, CELLS_JSON]
        digest = design_key(man, tool_version("yosys", "-V"), tool_version("nextpnr-ice40"), Path(__file__), part.name,
                            clock_mhz, seed)
        with cache.entry("ice40", digest, wdir, names) as hit:
            if hit:
                say("synthesis, place and route: this design, part and seed done before (cached)")
            else:
                _synth_place_route(man, part, wdir, clock_mhz, seed, say)
        cells = json.loads((wdir / CELLS_JSON).read_text())
        rep = json.loads((wdir / NEXTPNR_REPORT).read_text())
        util = rep.get("utilization", {})
        post = post_route(wdir / f"{man.top}.asc", wdir / f"{man.top}.pcf", part, wdir) if post_route else None
        report = Ice40Report(
            part=part, top=man.top, cells=cells,
            logic_cells=int(util.get("ICESTORM_LC", {}).get("used", 0)),
            brams=int(util.get("ICESTORM_RAM", {}).get("used", 0)),
            io=int(util.get("SB_IO", {}).get("used", 0)),
            fmax_mhz=fmax_of(rep), clock_mhz=clock_mhz, output=str(Path(out_dir)),
            seconds=time.monotonic() - t0, post_route=post,
        )
        with atomic_directory(out_dir, _is_ice40_output, "flann iCE40 build") as tmp_out:
            tmp_out = Path(tmp_out)
            for name in (f"{man.top}.bin", f"{man.top}.asc", f"{man.top}.pcf", NEXTPNR_REPORT):
                shutil.copyfile(wdir / name, tmp_out / name)
            (tmp_out / REPORT).write_text(json.dumps(report.to_dict(), indent=2) + "\n")
    return report


__all__ = ["Ice40Report", "implement", "example_pcf", "package_pins", "global_clock_pins", "fmax_of", "REPORT"]
