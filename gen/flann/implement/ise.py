"""ISE 10.1 handoff: an xtclsh project script, a UCF and a FuseSoC core for a generated design.

ISE 10.1 is the last ISE release that supports Spartan-II.  ``write_ise`` copies the
design's VHDL (compile order from ``manifest.json``) into ``OUT/src`` so the directory can
be carried to the machine that runs ISE, and renders from ``templates/ise_*.j2``:

* ``flann_top.tcl``: ``xtclsh flann_top.tcl`` creates ``flann_top.ise`` (family Spartan2,
  device/package/speed of the part), adds sources and UCF, sets the XST options and runs
  the flow up to "Generate Programming File";
* ``flann_top.ucf``: clock PERIOD constraint and a LOC for every bit of every port the top
  entity's VHDL declares (a family's cfg port too), as far as the example pins go: a port
  they cannot hold is listed without a LOC for ISE to place.  The pin map is an *example
  assignment* to edit for the real board;
* ``flann_top.core``: FuseSoC CAPI2 description (GHDL simulation target; its ISE target
  is for ISE 11+ because Edalize writes .xise projects);
* ``README.txt``: the steps.

Pin map source.  Global clock input GCK1 is P77 on Spartan-II PQ208 (DS001 module 4; the
public BurchED B3 XC2S200-PQ208 board files use P77 for the system clock and P185 as a
global clock input).  The user I/O pins below are the ones those board files use as plain
I/O on the same PQ208 footprint (B3 connectors, B5 slots): P57 for reset; inputs on the
left side (P3..P49), outputs on the right (P55..P68, P161..P194), either taking the other
side's spare pins when it has more bits than its own side has pins.  XC2S50..XC2S200 in
PQ208 have 140 user I/O; the XC2S30 has 132, so some of these pins may be unbonded there.
"""

from __future__ import annotations

import re
import shutil
import warnings
from dataclasses import dataclass
from pathlib import Path

from .. import __version__
from ..hardware.target import CLOCK_HZ, Part, parse_part
from ..errors import FlannError
from ..fileio import atomic_directory, check_output_directory
from ..textgen import template
from ..hardware.design import as_design
from .synth import Resources, manifest_device, not_fit_message, shortfall, smallest_fit, synthesize
from .timing import safe_clock_mhz

CLOCK_PIN = "P77"  # GCK1
RESET_PIN = "P57"
INPUT_PINS = (
    "P3", "P4", "P5", "P6", "P7", "P8", "P9", "P10", "P11", "P15", "P16", "P17", "P18",
    "P20", "P21", "P22", "P23", "P24", "P27", "P29", "P30", "P31", "P33", "P34", "P35",
    "P36", "P40", "P41", "P42", "P43", "P44", "P45", "P46", "P47", "P48", "P49",
)
OUTPUT_PINS = (
    "P161", "P162", "P163", "P164", "P165", "P166", "P167", "P168", "P169", "P173",
    "P174", "P175", "P176", "P178", "P179", "P180", "P181", "P187", "P188", "P189",
    "P191", "P192", "P193", "P194", "P55", "P56", "P58", "P59", "P60", "P61", "P62",
    "P63", "P64", "P68",
)
PIN_MAP_DEVICES = ("xc2s50", "xc2s100", "xc2s150", "xc2s200")  # 140 user I/O in PQ208


MAX_PORT_BITS = 1024     # wider than any flat port a top level of this project has


@dataclass(frozen=True)
class Port:
    name: str
    direction: str  # "in" | "out"
    width: int  # 0 for a scalar std_logic

    def bits(self) -> list[str]:
        if self.width == 0:
            return [self.name]
        return [f"{self.name}<{i}>" for i in range(self.width)]


def top_ports(manifest: dict) -> list[Port]:
    """flann_top's ports (fixed interface; widths from the manifest)."""
    try:
        ib, ob = int(manifest["input_bits"]), int(manifest["output_bits"])
    except (KeyError, TypeError, ValueError):
        raise FlannError("manifest.json: fields 'input_bits' and 'output_bits' (integers) are needed for the pin map") from None
    return [
        Port("clk", "in", 0), Port("rst", "in", 0),
        Port("in_valid", "in", 0), Port("in_ready", "out", 0), Port("in_data", "in", ib),
        Port("out_valid", "out", 0), Port("out_data", "out", ob), Port("out_sat", "out", 0),
    ] + _extra_ports(manifest)


def _extra_ports(manifest: dict) -> list[Port]:
    """Ports a datapath adds to the common interface (a family design's cfg_* write port,
    a two-input design's in_temp), as its manifest lists them under ``cfg_port.ports``
    (:func:`flann.hardware.manifest.flat_port`)."""
    decl = (manifest.get("cfg_port") or {}).get("ports") or {}
    if not isinstance(decl, dict):
        raise FlannError("manifest.json: cfg_port.ports must map each port's name to its direction and width")
    out = []
    for name, port in decl.items():
        try:
            direction, width = port["direction"], port["width"]
            ok = (direction in ("in", "out") and isinstance(width, int) and not isinstance(width, bool)
                  and 0 <= width <= MAX_PORT_BITS)
        except (KeyError, TypeError):
            ok = False
        if not ok:
            raise FlannError(f"manifest.json: cfg_port.ports.{name} = {port!r} is not a flat port "
                             f"(direction in/out, width 0..{MAX_PORT_BITS} bits)")
        out.append(Port(name, direction, width))
    return out


_PORT_RE = re.compile(
    r"^\s*(\w+)\s*:\s*(in|out)\s+std_logic(?:_vector\s*\(\s*(\d+)\s+downto\s+0\s*\))?\s*;?\s*$",
    re.I | re.M,
)


def vhdl_ports(text: str, entity: str) -> list[Port]:
    """Ports of ``entity`` as declared in VHDL text (flat std_logic / std_logic_vector ports)."""
    m = re.search(rf"\bentity\s+{entity}\s+is(.*?)\bend\s+entity", text, re.I | re.S)
    if not m:
        return []
    return [Port(n.lower(), d.lower(), int(hi) + 1 if hi else 0) for n, d, hi in _PORT_RE.findall(m.group(1))]


def design_ports(man) -> list[Port]:
    """The top entity's ports as its VHDL declares them (every top: fixed, float18, family,
    thermal, a hand-written one), checked against the ports the manifest implies."""
    implied = top_ports(man.data)
    for f in man.files:
        declared = vhdl_ports(f.read_text(errors="replace"), man.top)
        if declared:
            if sorted(declared, key=lambda p: p.name) != sorted(implied, key=lambda p: p.name):
                want = ", ".join(f"{p.name}:{p.direction}{p.width or ''}" for p in implied)
                got = ", ".join(f"{p.name}:{p.direction}{p.width or ''}" for p in declared)
                raise FlannError(f"{f.name}: entity {man.top} declares ports ({got}), the manifest implies ({want})")
            return declared
    raise FlannError(f"entity {man.top} not found in the manifest's files")


PIN_MAP_PACKAGES = ("pq208",)  # packages with an example pin map; on the others ISE chooses the pins


def pin_map(ports: list[Port], part: Part) -> tuple[list[tuple[str, str, str]], list[Port]]:
    """(net, LOC, note) for every bit of the ports the example map places, and the ports it
    leaves without a LOC for ISE to place; ([], []) on a package without an example map.

    Inputs take the left-side pins, outputs the right-side ones; a design with more input bits
    (a family's cfg port) or output bits than its side has takes the other side's spare pins,
    from the far end, so any mix of up to len(INPUT_PINS) + len(OUTPUT_PINS) bits is placed.
    Beyond that, a port is placed whole or not at all (half a bus on placeholder pins helps no
    board): in declaration order, one whose bits outnumber the pins left is left unplaced and
    the ports after it are still tried."""
    if part.package not in PIN_MAP_PACKAGES:
        return [], []
    preference = {"in": INPUT_PINS + OUTPUT_PINS[::-1], "out": OUTPUT_PINS + INPUT_PINS[::-1]}
    used: set[str] = set()
    rows, unplaced = [], []
    for p in ports:
        if p.name == "clk":
            rows += [(net, CLOCK_PIN, "GCK1 global clock input") for net in p.bits()]
        elif p.name == "rst":
            rows += [(net, RESET_PIN, "synchronous reset, active high") for net in p.bits()]
        else:
            free = [pin for pin in preference[p.direction] if pin not in used]
            if len(p.bits()) > len(free):
                unplaced.append(p)
                continue
            for net, pin in zip(p.bits(), free):
                rows.append((net, pin, p.direction))
                used.add(pin)
    return rows, unplaced


def _described(p: Port) -> str:
    """A port as a UCF comment or a message names it, e.g. ``cfg_data<31:0> (in, 32 bits)``."""
    bits = len(p.bits())
    return f"{p.name}{f'<{p.width - 1}:0>' if p.width else ''} ({p.direction}, {bits} bit{'s' * (bits > 1)})"


def _unplaced_warning(ports: list[Port], unplaced: list[Port], ucf: Path) -> str:
    bits = {d: sum(len(p.bits()) for p in ports if p.direction == d and p.name not in ("clk", "rst"))
            for d in ("in", "out")}
    return (f"{ucf}: no LOC for {', '.join(_described(p) for p in unplaced)}, ISE chooses their pins (the ports "
            f"have {bits['in']} input and {bits['out']} output bits beside clk and rst, more than the example pin "
            f"map's {len(INPUT_PINS) + len(OUTPUT_PINS)} pins); add their LOCs for your board")


def check_fits(man, dp, part, force: bool = False, warn: bool = True) -> None:
    """Refuse (one line naming the smallest part that fits) a part the design's resource
    estimate exceeds, unless ``force`` (then a warning, when ``warn``); a datapath without an
    estimate is not checked, one without an ISE handoff is refused."""
    if not dp.ise:
        raise dp.lacking(man.directory, "ISE handoff")
    est = dp.estimate(man)
    if est is None:
        return
    res = Resources(luts=est["luts"], ffs=est["ffs"], brams=est["brams"], carry=0, xorcy=0, mult_and=0,
                    muxf5=0, muxf6=0, io=sum(len(p.bits()) for p in top_ports(man) if p.name != "clk"))
    short = shortfall(res, part)
    if not short:
        return
    best = smallest_fit(res, part)
    where = f"smallest Spartan-II that fits: {best.name}" if best else "no Spartan-II holds it"
    why = f"{man.top} does not fit {part.name} (estimate: {'; '.join(short)}); {where}"
    if force:
        if warn:
            warnings.warn(f"{why}; the project is written anyway (--force)")
        return
    raise FlannError(f"{why} (--force writes the project anyway)")


def design_device(design) -> str:
    """The part a design (or the directory it names) was generated for (its manifest's), else the
    default part."""
    return manifest_device(as_design(design).manifest)


def check_directory_fits(design, device: str, force: bool = False) -> None:
    """:func:`check_fits` for a design (or the directory it names), before anything slow runs (the
    warning under ``force`` is :func:`write_ise`'s)."""
    design = as_design(design)
    check_fits(design.manifest, design.datapath, parse_part(device), force, warn=False)


def check_output(out_dir) -> None:
    """Refuse now, in one line, an output directory :func:`write_ise` would refuse only after
    its checks and warnings (a user's directory, the design's own)."""
    check_output_directory(out_dir, _is_ise_project, "flann ISE project")


def check_clock_mhz(clock_mhz: float) -> None:
    if not (0 < clock_mhz <= 200):
        raise FlannError(f"--clock-mhz {clock_mhz}: must be in (0, 200] MHz")


def write_ise(design, device: str | None = None, out_dir="ise", clock_mhz: float = CLOCK_HZ / 1e6,
              force: bool = False) -> list[str]:
    """Write the ISE 10.1 handoff for a generated design (or the directory it names; ``device``:
    default the part its manifest records); returns the files written."""
    design = as_design(design)
    man, dp = design.manifest, design.datapath
    check_output(out_dir)
    part = parse_part(device if device is not None else manifest_device(man))
    check_fits(man, dp, part, force)
    check_clock_mhz(clock_mhz)
    if part.package in PIN_MAP_PACKAGES and part.device.name not in PIN_MAP_DEVICES:
        warnings.warn(
            f"{part.device.name} in PQ208 has {part.user_io} user I/O, the pin map was taken from "
            "XC2S200 boards (140): check every LOC against DS001 module 4 before building"
        )
    ports = design_ports(man)
    pins, unplaced = pin_map(ports, part)
    sources = [f"src/{f.name}" for f in man.files]
    pins_kind = "pq208" if pins else "unplaced"
    period_ns = 1000.0 / clock_mhz
    ctx = dict(
        version=__version__, part=part, top=man.top, sources=sources, ucf=f"{man.top}.ucf",
        period_ns=f"{period_ns:.3f}".rstrip("0").rstrip("."), clock_mhz=f"{clock_mhz:g}",
        pins=pins, ports=ports, no_loc=[_described(p) for p in unplaced],
        model_sha256=man.data.get("model_sha256") or "(not recorded)",
        cycles_per_sample=man.data.get("cycles_per_sample"), latency=man.data.get("latency_cycles"),
        core_name=f"flann:lvdt:{man.top}:{__version__}", input_bits=man.data["input_bits"],
        output_bits=man.data["output_bits"],
        # the ports a datapath adds to the common interface: the board must wire them too
        extra_ports=[p.name for p in _extra_ports(man.data)],
        cfg_timing=(man.data.get("cfg_port") or {}).get("timing"),
        pin_notes=f"implement/templates/ucf_pins/{pins_kind}_notes.j2",
        pin_lines=f"implement/templates/ucf_pins/{pins_kind}_lines.j2",
    )
    texts = {
        f"{man.top}.tcl": template("implement/templates/ise_project.tcl.j2").render(**ctx),
        f"{man.top}.ucf": template("implement/templates/ise_pins.ucf.j2").render(**ctx),
        f"{man.top}.core": template("implement/templates/ise_fusesoc.core.j2").render(**ctx),
        "README.txt": template("implement/templates/ise_readme.txt.j2").render(**ctx),
    }
    out = Path(out_dir)
    with atomic_directory(out, _is_ise_project, "flann ISE project") as tmp:
        tmp = Path(tmp)
        (tmp / "src").mkdir()
        for f in man.files:
            shutil.copyfile(f, tmp / "src" / f.name)
        shutil.copyfile(man.directory / "manifest.json", tmp / "src" / "manifest.json")
        for name, text in texts.items():
            (tmp / name).write_text(text, newline="")
    if unplaced:   # said once the UCF it names is written
        warnings.warn(_unplaced_warning(ports, unplaced, out / f"{man.top}.ucf"))
    return [*texts, *sources, "src/manifest.json"]


def checked_clock(design, device: str, clock_mhz: float, abc: str = "full",
                  force: bool = False) -> tuple[float, str | None]:
    """The clock for the PERIOD constraint: ``clock_mhz`` when the Spartan-II timing estimate
    (:mod:`flann.implement.timing`, on the Yosys-mapped netlist) meets it, else the highest
    whole MHz the estimate meets with its margin.  Returns (MHz, why it was lowered or None).
    A mapped netlist that does not fit the part is refused (unless ``force``): the check for a
    datapath with no estimate before synthesis."""
    check_clock_mhz(clock_mhz)
    report = synthesize(design, device, abc=abc)
    if not force and not report.fits:
        raise FlannError(f"{not_fit_message(report)} (synthesized; --force writes the project anyway)")
    t = report.timing
    if t is None or t.meets(clock_mhz * 1e6):   # a combinational block has no path to clock
        return clock_mhz, None
    safe = safe_clock_mhz(t)
    return safe, (f"{report.top} is estimated at {t.fmax_mhz:.1f} MHz on {report.part.name} ({t.logic_levels} LUT "
                  f"levels, {t.carry_bits} carry bits), below the requested {clock_mhz:g} MHz: PERIOD written for "
                  f"{safe:g} MHz ({1000.0 / safe:.3f} ns)")


def _is_ise_project(directory: Path) -> bool:
    return (directory / "README.txt").is_file() and (directory / "src" / "manifest.json").is_file()


def summary(files: list[str], out_dir, part: Part | str) -> str:
    p = part if isinstance(part, Part) else parse_part(part)
    return (f"wrote {len(files)} files to {out_dir} for {p.name}: run `xtclsh {files[0]}` there "
            f"with ISE 10.1 (see README.txt)")


__all__ = ["write_ise", "design_device", "check_directory_fits", "check_output", "pin_map", "top_ports",
           "design_ports", "Port", "summary", "CLOCK_PIN", "RESET_PIN", "INPUT_PINS", "OUTPUT_PINS"]
