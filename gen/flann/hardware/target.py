"""The Spartan-II family: logic, block RAM and user I/O per device and package.

Source: Xilinx DS001 "Spartan-II FPGA Family Data Sheet" (v2.8, June 13, 2008):

* Module 1, Table 1 "Spartan-II FPGA Family Members": CLB array, total CLBs, maximum
  user I/O, block RAM bits;
* Module 1, "User I/O Chart" (available user I/O per device/package; the four global
  clock / user input pins are not counted in these numbers);
* Module 2, "Configurable Logic Block": a CLB is two slices, each with two 4-input LUTs
  and two flip-flops, so one CLB = 4 LUT4 = 4 flip-flops; "Block RAM": each block RAM
  holds 4096 bits.

Speed grades -5 and -6 (-6 commercial temperature range only).  The table is data, not
derived: tests check it against the per-CLB arithmetic above, never against itself.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..errors import SpecError

SOURCE = (
    'Xilinx DS001 "Spartan-II FPGA Family Data Sheet" v2.8 (2008-06-13), '
    "Module 1 Table 1 and User I/O Chart; Module 2 (CLB = 4 LUT4 + 4 FF, block RAM = 4096 bits)"
)

# The part `flann gen` targets unless told otherwise, and the clock every throughput figure
# (samples/s) and the ISE PERIOD constraint assume.
DEFAULT_PART = "xc2s200-pq208-5"
CLOCK_HZ = 50e6

LUTS_PER_CLB = 4
FFS_PER_CLB = 4
BRAM_BITS = 4096
SPEED_GRADES = ("5", "6")


@dataclass(frozen=True)
class Device:
    name: str  # "xc2s50"
    clb_rows: int
    clb_cols: int
    brams: int
    packages: tuple[tuple[str, int], ...]  # (package, user I/O), DS001 user I/O chart

    @property
    def clbs(self) -> int:
        return self.clb_rows * self.clb_cols

    @property
    def luts(self) -> int:
        return self.clbs * LUTS_PER_CLB

    @property
    def ffs(self) -> int:
        return self.clbs * FFS_PER_CLB

    @property
    def bram_bits(self) -> int:
        return self.brams * BRAM_BITS

    def user_io(self, package: str) -> int | None:
        return dict(self.packages).get(package)


DEVICES: tuple[Device, ...] = (
    Device("xc2s15", 8, 12, 4, (("vq100", 60), ("tq144", 86), ("cs144", 86))),
    Device("xc2s30", 12, 18, 6, (("vq100", 60), ("tq144", 92), ("cs144", 92), ("pq208", 132))),
    Device("xc2s50", 16, 24, 8, (("tq144", 92), ("pq208", 140), ("fg256", 176))),
    Device("xc2s100", 20, 30, 10, (("tq144", 92), ("pq208", 140), ("fg256", 176), ("fg456", 196))),
    Device("xc2s150", 24, 36, 12, (("pq208", 140), ("fg256", 176), ("fg456", 260))),
    Device("xc2s200", 28, 42, 14, (("pq208", 140), ("fg256", 176), ("fg456", 284))),
)

_BY_NAME = {d.name: d for d in DEVICES}


@dataclass(frozen=True)
class Part:
    """One orderable part: device, package and speed grade (``xc2s200-pq208-5``)."""

    device: Device
    package: str
    speed: str

    @property
    def name(self) -> str:
        return f"{self.device.name}-{self.package}-{self.speed}"

    @property
    def user_io(self) -> int:
        return self.device.user_io(self.package) or 0

    @property
    def ise_device(self) -> str:
        """ISE's spelling of the device (``xc2s200``)."""
        return self.device.name

    @property
    def ise_speed(self) -> str:
        return f"-{self.speed}"


def device(name: str) -> Device:
    d = _BY_NAME.get(name.lower())
    if d is None:
        raise SpecError(f"unknown Spartan-II device {name!r}; allowed: {', '.join(_BY_NAME)}")
    return d


_PART_RE = re.compile(r"^(xc2s\d+)-?([a-z]{2}\d{3})-?(\d)$")


def parse_part(text: str) -> Part:
    """Parse ``xc2s200-pq208-5`` (also ``xc2s200pq208-5``) and check it is orderable."""
    m = _PART_RE.match(text.strip().lower())
    if not m:
        raise SpecError(
            f"--device {text!r}: expected DEVICE-PACKAGE-SPEED such as xc2s200-pq208-5 "
            f"(devices {', '.join(_BY_NAME)}; speed grades {', '.join('-' + s for s in SPEED_GRADES)})"
        )
    dev = device(m.group(1))
    package, speed = m.group(2), m.group(3)
    if dev.user_io(package) is None:
        offered = ", ".join(p for p, _ in dev.packages)
        raise SpecError(f"--device {text!r}: {dev.name} is not offered in {package}; packages: {offered}")
    if speed not in SPEED_GRADES:
        raise SpecError(f"--device {text!r}: speed grade -{speed} does not exist; allowed -5, -6")
    return Part(dev, package, speed)


def devices_in_package(package: str) -> list[Device]:
    return [d for d in DEVICES if d.user_io(package) is not None]


# --------------------------------------------------------------------------- iCE40
# A second target with a complete open-source flow (Yosys synth_ice40 -> nextpnr-ice40 ->
# icepack): real place and route, static timing and a bitstream.  Logic cells (one LUT4 + one
# flip-flop each) and 4 Kbit block RAMs (EBR) from Lattice's data sheets: iCE40 LP/HX family
# (FPGA-DS-02029), Table 1.1; iCE40 UltraPlus (FPGA-DS-02008), Table 1.1.  ``chipdb`` and
# ``pins`` name the IceStorm chip database and its package section (the pin names of the
# example .pcf); ``nextpnr`` is nextpnr-ice40's device flag.
ICE40_SOURCE = ("Lattice iCE40 LP/HX Family Data Sheet FPGA-DS-02029 Table 1.1; "
                "iCE40 UltraPlus Family Data Sheet FPGA-DS-02008 Table 1.1")


@dataclass(frozen=True)
class Ice40Part:
    name: str  # "ice40-hx8k-ct256"
    nextpnr: str  # nextpnr-ice40 device flag without "--": "hx8k"
    package: str  # nextpnr --package: "ct256"
    chipdb: str  # IceStorm chip database: chipdb-<chipdb>.txt
    pins: str  # its ".pins" section for this package
    logic_cells: int
    brams: int


ICE40_PARTS: tuple[Ice40Part, ...] = (
    Ice40Part("ice40-hx1k-vq100", "hx1k", "vq100", "1k", "vq100", 1280, 16),
    Ice40Part("ice40-hx1k-tq144", "hx1k", "tq144", "1k", "tq144", 1280, 16),
    Ice40Part("ice40-hx4k-tq144", "hx4k", "tq144", "8k", "tq144:4k", 3520, 20),
    Ice40Part("ice40-hx8k-cb132", "hx8k", "cb132", "8k", "cb132", 7680, 32),
    Ice40Part("ice40-hx8k-ct256", "hx8k", "ct256", "8k", "ct256", 7680, 32),
    Ice40Part("ice40-lp8k-cm81", "lp8k", "cm81", "8k", "cm81", 7680, 32),
    Ice40Part("ice40-up5k-sg48", "up5k", "sg48", "5k", "sg48", 5280, 30),
)
DEFAULT_ICE40_PART = "ice40-hx8k-ct256"
_ICE40_BY_NAME = {p.name: p for p in ICE40_PARTS}


def is_ice40(text: str) -> bool:
    return text.strip().lower().startswith("ice40-")


def parse_ice40(text: str) -> Ice40Part:
    p = _ICE40_BY_NAME.get(text.strip().lower())
    if p is None:
        raise SpecError(f"--device {text!r}: unknown iCE40 part; allowed: {', '.join(_ICE40_BY_NAME)}")
    return p
