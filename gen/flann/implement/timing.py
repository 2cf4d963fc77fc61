"""Spartan-II timing estimate: the longest register-to-register path of the mapped netlist.

Yosys ``synth_xilinx -family xcv`` maps to Virtex / Spartan-II cells (LUT1-4, MUXF5/6, MUXCY,
XORCY, MULT_AND, FD*, RAMB4_*) but gives no timing, and ISE 10.1 cannot run here.  This
module walks the flattened mapped netlist (``mapped.json``, written by the synthesis script)
as a graph of net bits, and adds up, along every path from a register or block-RAM output to a
register or block-RAM input:

    clock-to-out + per cell delay + a routing allowance per routed net + setup

with the -5 / -6 figures of the data sheet (:data:`GRADES`).  The longest path gives the
estimated Fmax; its number of LUT levels and carry-chain bits are reported with it.

It is an estimate, not a static timing analysis of a placed design: the routing of a real
placement is replaced by a fixed allowance per routed net (:data:`ROUTE_NS`); dedicated
connections (carry chain, F5/F6 multiplexers, XOR into the slice's own flip-flop) get none.
Paths from and to the device pins are not counted (the design registers its ports).
"""

from __future__ import annotations

import json
from collections import defaultdict, deque
from dataclasses import dataclass
from pathlib import Path

from ..errors import FlannError
from ..hardware.target import CLOCK_HZ, Part

SOURCE = ('Xilinx DS001 "Spartan-II FPGA Family Data Sheet" v2.8 (2008-06-13), Module 3, '
          '"CLB Switching Characteristics" (p. 64)')


@dataclass(frozen=True)
class Grade:
    """Delays (ns) of one speed grade.  ``ds001`` lists those read from DS001 Module 3 p. 64;
    the others are assumptions (see docs/synthesis.md) and are named in the method text."""

    tilo: float  # TILO: 4-input function, F/G inputs to X/Y outputs
    tif5x_extra: float  # TIF5X - TILO: LUT output through the F5 multiplexer to X
    tf5iny: float  # TF5INY: F5IN input to Y output through the F6 multiplexer
    tcko: float  # TCKO: flip-flop clock to XQ/YQ
    tick_extra: float  # TICK - TILO: setup of a flip-flop fed by its own slice's LUT
    tdick: float  # TDICK: BX/BY (direct) input setup
    tceck: float  # TCECK: CE input setup
    trck: float  # TRCK: synchronous SR input setup
    # assumed (DS001 Module 3 pp. 65-66 were not available to check): carry and block RAM
    carry_bit: float  # CIN to COUT, per MUXCY
    carry_in: float  # operand (LUT output, S/DI) into the carry chain
    xor_sum: float  # CIN or LI through XORCY to the output
    bram_cko: float  # block RAM clock to DO
    bram_setup: float  # block RAM ADDR/DI/EN/WE setup


GRADES = {
    "6": Grade(tilo=0.6, tif5x_extra=0.3, tf5iny=0.4, tcko=1.1, tick_extra=0.7, tdick=0.8, tceck=0.9,
               trck=0.8, carry_bit=0.1, carry_in=0.9, xor_sum=0.7, bram_cko=3.4, bram_setup=1.4),
    "5": Grade(tilo=0.7, tif5x_extra=0.4, tf5iny=0.4, tcko=1.3, tick_extra=0.7, tdick=0.8, tceck=0.9,
               trck=0.8, carry_bit=0.1, carry_in=1.0, xor_sum=0.8, bram_cko=4.0, bram_setup=1.6),
}

# Allowance for one routed net (general interconnect between CLBs): not a data-sheet figure.
# Spartan-II designs typically spend about as long in routing as in logic; 1 ns per net is
# above the single-hop delays and makes the estimate conservative for short nets.
ROUTE_NS = 1.0

# Required margin of the estimate over the clock a design is generated for.
MARGIN = 1.2

_LUTS = {"LUT1", "LUT2", "LUT3", "LUT4", "INV"}
_OUTPUT_PINS = {"O", "Q", "DO", "DOA", "DOB", "LO", "SPO", "DPO", "Q15"}
_FF_PREFIX = "FD"
_IGNORED = {"BUFG", "IBUF", "IBUFG", "OBUF", "OBUFT", "GND", "VCC"}  # clock tree, pads, constants
# LUT RAM and shift registers: written on the clock (a start point, TCKO), read through the LUT
# from the address pins (TILO, as a LUT level); data and enables are end points
_LUT_MEMORY = ("RAM16X1", "RAM32X1", "SRL16")
_ADDRESS_PINS = {"A0", "A1", "A2", "A3", "A4", "DPRA0", "DPRA1", "DPRA2", "DPRA3"}


@dataclass(frozen=True)
class Timing:
    grade: str
    delay_ns: float
    logic_levels: int  # LUTs (and inverters) on the longest path
    carry_bits: int  # MUXCY on the longest path
    routed_nets: int
    start: str
    end: str
    loops_broken: int = 0  # structural loops of the mapped netlist left out of the walk

    @property
    def fmax_mhz(self) -> float:
        return 1000.0 / self.delay_ns if self.delay_ns > 0 else float("inf")

    def meets(self, clock_hz: float, margin: float = 1.0) -> bool:
        return self.fmax_mhz * 1e6 >= clock_hz * margin

    def method(self) -> str:
        g = GRADES[self.grade]
        return (f"longest register-to-register path of the Yosys-mapped netlist: TCKO {g.tcko} + "
                f"TILO {g.tilo} per LUT level + {ROUTE_NS} ns routing allowance per routed net + "
                f"{g.carry_bit} ns per carry bit + setup (speed grade -{self.grade}; CLB figures from "
                f"{SOURCE}; carry and block RAM figures assumed; estimate, not place and route"
                + (f"; {self.loops_broken} structural loop(s) of abc's logic sharing left out" if self.loops_broken
                   else "") + ")")

    def to_dict(self, clock_hz: float = CLOCK_HZ) -> dict:
        return {
            "fmax_mhz_estimate": round(self.fmax_mhz, 1),
            "logic_levels": self.logic_levels,
            "carry_bits": self.carry_bits,
            "method": self.method(),
            "delay_ns": round(self.delay_ns, 2),
            "routed_nets": self.routed_nets,
            "speed_grade": f"-{self.grade}",
            "clock_mhz": round(clock_hz / 1e6, 3),
            "meets_clock": self.meets(clock_hz),
            "from": self.start,
            "to": self.end,
            "loops_broken": self.loops_broken,
        }


def _bits(conn) -> list:
    return [b for b in conn if isinstance(b, int)]  # "0"/"1"/"x" are constants


def analyse(netlist_json: str | Path, part: Part, top: str = "flann_top") -> Timing | None:
    """Longest register-to-register path of ``netlist_json`` (flattened Yosys JSON); None for a
    purely combinational block (a datapath's block synthesised alone), which has no clock."""
    data = json.loads(Path(netlist_json).read_text())
    mod = data.get("modules", {}).get(top)
    if mod is None:
        raise FlannError(f"{netlist_json}: module {top} not found")
    g = GRADES.get(part.speed)
    if g is None:
        raise FlannError(f"no timing figures for speed grade -{part.speed}")
    cells = mod["cells"]

    driver: dict[int, tuple[str, str]] = {}  # net bit -> (cell type, pin)
    for name, c in cells.items():
        for pin, conn in c["connections"].items():
            if pin in _OUTPUT_PINS:
                for b in _bits(conn):
                    driver[b] = (c["type"], pin)

    def local(bit: int, cell_type: str, pin: str) -> bool:
        """A dedicated connection inside a slice or a carry column: no routing allowance."""
        src = driver.get(bit, ("", ""))[0]
        if cell_type in ("MUXCY", "XORCY") and pin in ("CI", "LI", "S"):
            return True
        if cell_type in ("MUXF5", "MUXF6") and pin in ("I0", "I1"):
            return True
        if cell_type == "MUXCY" and pin == "DI" and src == "MULT_AND":
            return True
        if cell_type.startswith(_FF_PREFIX) and pin == "D" and (src in _LUTS or src in ("XORCY", "MUXF5", "MUXF6")):
            return True
        return False

    # edges: (from bit, to bit, delay, is_lut, is_carry, routed)
    edges: dict[int, list] = defaultdict(list)
    indeg: dict[int, int] = defaultdict(int)
    sources: dict[int, float] = {}
    sinks: list[tuple[int, float, bool, str]] = []  # (bit, setup, routed, cell name)
    for name, c in cells.items():
        t, conns = c["type"], c["connections"]
        if t in _IGNORED:
            continue
        if t.startswith(_FF_PREFIX) or t.startswith("RAMB4"):
            bram = t.startswith("RAMB4")
            for pin, conn in conns.items():
                if pin in ("C", "CLK"):
                    continue
                for b in _bits(conn):
                    if pin in _OUTPUT_PINS:
                        sources[b] = g.bram_cko if bram else g.tcko
                    elif bram:
                        sinks.append((b, g.bram_setup, True, name))
                    else:
                        loc = local(b, t, pin)
                        setup = {"CE": g.tceck, "R": g.trck, "S": g.trck}.get(
                            pin, g.tick_extra if loc and driver.get(b, ("",))[0] != "XORCY" else g.tdick)
                        sinks.append((b, setup, not loc, name))
            continue
        if t.startswith(_LUT_MEMORY):
            outs = [b for p, conn in conns.items() if p in _OUTPUT_PINS for b in _bits(conn)]
            for pin, conn in conns.items():
                if pin in ("WCLK", "CLK"):
                    continue
                for b in _bits(conn):
                    if pin in _OUTPUT_PINS:
                        sources[b] = g.tcko
                    elif pin in _ADDRESS_PINS:
                        for o in outs:
                            edges[b].append((o, g.tilo + ROUTE_NS, True, False, True))
                            indeg[o] += 1
                    else:
                        sinks.append((b, g.tick_extra + g.tilo, True, name))
            continue
        if t in _LUTS or t == "MULT_AND":
            arcs = {p: g.tilo for p in conns if p not in _OUTPUT_PINS}
        elif t == "MUXF5":
            arcs = {"I0": g.tif5x_extra, "I1": g.tif5x_extra, "S": g.tilo}
        elif t == "MUXF6":
            arcs = {"I0": g.tf5iny, "I1": g.tf5iny, "S": g.tilo}
        elif t == "MUXCY":
            arcs = {"CI": g.carry_bit, "S": g.carry_in, "DI": g.carry_in}
        elif t == "XORCY":
            arcs = {"CI": g.xor_sum, "LI": g.xor_sum}
        else:
            raise FlannError(f"timing estimate: no delay model for cell type {t} ({name})")
        outs = [b for p, conn in conns.items() if p in _OUTPUT_PINS for b in _bits(conn)]
        for pin, delay in arcs.items():
            for b in _bits(conns.get(pin, [])):
                routed = not local(b, t, pin)
                for o in outs:
                    edges[b].append((o, delay + (ROUTE_NS if routed else 0.0), t in _LUTS, t == "MUXCY", routed))
                    indeg[o] += 1

    # abc's logic sharing can close a structural loop that is logically open (the comparator of a
    # swap reading its own muxed operands: x xor y = max xor min); yosys check refuses real ones.
    # Such edges are left out so the walk stays a DAG; how many is part of the result.
    back = _back_edges(edges)
    for b, k in back:
        indeg[edges[b][k][0]] -= 1
    edges = {b: [e for k, e in enumerate(es) if (b, k) not in back] for b, es in edges.items()}
    # longest arrival per bit (Kahn order); bits with no register upstream never become reachable
    nodes = set(edges) | set(indeg) | set(sources)
    arrival: dict[int, float] = {b: d for b, d in sources.items()}
    prev: dict[int, tuple] = {}
    queue = deque(b for b in nodes if indeg[b] == 0)
    done = 0
    while queue:
        b = queue.popleft()
        done += 1
        for o, d, is_lut, is_carry, routed in edges.get(b, ()):
            if b in arrival:
                a = arrival[b] + d
                if a > arrival.get(o, float("-inf")):
                    arrival[o] = a
                    prev[o] = (b, is_lut, is_carry, routed)
            indeg[o] -= 1
            if indeg[o] == 0:
                queue.append(o)
    if done < len(nodes):
        raise FlannError("timing estimate: the mapped netlist has a combinational loop")

    best = None
    for b, setup, routed, name in sinks:
        if b in arrival:
            total = arrival[b] + (ROUTE_NS if routed else 0.0) + setup
            if best is None or total > best[0]:
                best = (total, b, routed, name)
    if best is None:
        return None
    total, bit, routed, end = best
    levels, carry, nets = 0, 0, int(routed)
    b = bit
    while b in prev:
        b, is_lut, is_carry, r = prev[b]
        levels += is_lut
        carry += is_carry
        nets += r
    names = _bit_names(mod)
    return Timing(part.speed, total, levels, carry, nets, names.get(b, f"bit {b}"), names.get(bit, end),
                  len(back))


def _back_edges(edges: dict) -> set[tuple[int, int]]:
    """(bit, edge index) of every edge that closes a cycle in a depth-first walk (iterative:
    carry chains are thousands of bits deep)."""
    state: dict[int, int] = {}   # 1 on the stack, 2 done
    back = set()
    for root in list(edges):
        if root in state:
            continue
        state[root] = 1
        stack = [(root, 0)]
        while stack:
            b, k = stack[-1]
            es = edges.get(b, ())
            if k == len(es):
                state[b] = 2
                stack.pop()
                continue
            stack[-1] = (b, k + 1)
            o = es[k][0]
            s = state.get(o)
            if s == 1:
                back.add((b, k))
            elif s is None:
                state[o] = 1
                stack.append((o, 0))
    return back


def _bit_names(mod: dict) -> dict[int, str]:
    """A readable net name per bit (the shortest public one)."""
    out: dict[int, str] = {}
    for name, n in mod.get("netnames", {}).items():
        if n.get("hide_name"):
            continue
        for i, b in enumerate(n["bits"]):
            if isinstance(b, int):
                label = f"{name}[{i}]" if len(n["bits"]) > 1 else name
                if b not in out or len(label) < len(out[b]):
                    out[b] = label
    return out


def safe_clock_mhz(t: Timing, margin: float = MARGIN) -> float:
    """The highest whole-MHz clock the estimate meets with ``margin``."""
    return float(int(t.fmax_mhz / margin))


__all__ = ["GRADES", "ROUTE_NS", "MARGIN", "SOURCE", "Timing", "analyse", "safe_clock_mhz"]
