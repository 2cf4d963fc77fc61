"""Typed fixed-point number format, carried from the error analysis to the templates.

One :class:`FixedFormat` answers "how wide", "what range" and "how to quantise" for a
signal, in the spirit of hls4ml's ``ap_fixed<W, I, Q, O>`` type: ``width`` bits, of which
``int_bits`` are left of the binary point (the sign bit counts as an integer bit when
``signed``), rounding ``"rnd"`` (round half up, i.e. add half an LSB then floor) or
``"trn"`` (floor), overflow ``"sat"`` (saturate) or ``"wrap"`` (modular; used only where
the mathematics is modular, e.g. a phase in units of pi mod 2).

Hardware integers are plain Python/numpy integers holding ``value * 2**frac_bits``.
The helpers here are the single definition of rounding and saturation used by the spec,
the bit-true twin and the benches, so all three do the same integer arithmetic.
"""

from __future__ import annotations

import re
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import SpecError

ROUNDING = ("rnd", "trn")
OVERFLOW = ("sat", "wrap")
_DESCRIBED = re.compile(r"([su])fix<(\d+),(-?\d+),(\w+),(\w+)>")


@dataclass(frozen=True)
class FixedFormat:
    width: int
    int_bits: int
    signed: bool = True
    rounding: str = "rnd"
    overflow: str = "sat"

    def __post_init__(self):
        if not isinstance(self.width, int) or self.width < 1 or self.width > 62:
            raise SpecError(f"fixed-point width {self.width!r} must be an integer in 1..62")
        if self.rounding not in ROUNDING:
            raise SpecError(f"rounding {self.rounding!r} must be one of {ROUNDING}")
        if self.overflow not in OVERFLOW:
            raise SpecError(f"overflow {self.overflow!r} must be one of {OVERFLOW}")

    # -- shape ------------------------------------------------------------------------
    @property
    def frac_bits(self) -> int:
        return self.width - self.int_bits

    @property
    def lsb(self) -> float:
        return 2.0 ** -self.frac_bits

    @property
    def min_int(self) -> int:
        return -(1 << (self.width - 1)) if self.signed else 0

    @property
    def max_int(self) -> int:
        return (1 << (self.width - 1)) - 1 if self.signed else (1 << self.width) - 1

    def fits(self, ints) -> bool:
        a = np.asarray(ints)
        return bool(a.size == 0 or (a.min() >= self.min_int and a.max() <= self.max_int))

    # -- quantisation -------------------------------------------------------------------
    def quantize(self, x) -> np.ndarray:
        """Float value(s) -> integer(s) of this format (rounding + overflow policy)."""
        scaled = np.asarray(x, dtype=float) * 2.0 ** self.frac_bits
        q = np.floor(scaled + 0.5) if self.rounding == "rnd" else np.floor(scaled)
        return self.overflow_policy(q.astype(np.int64))

    def overflow_policy(self, ints) -> np.ndarray:
        a = np.asarray(ints, dtype=np.int64)
        if self.overflow == "sat":
            return np.clip(a, self.min_int, self.max_int)
        return wrap(a, self.width, self.signed)

    def round_from(self, ints, frac_bits: int) -> np.ndarray:
        """Integers with ``frac_bits`` fraction bits -> this format's fraction bits, by its
        rounding (as the VHDL does: add half an LSB, shift); range is not touched."""
        return round_shift(ints, frac_bits - self.frac_bits, self.rounding)

    def saturate(self, ints) -> tuple[np.ndarray, np.ndarray]:
        """Clip to this format's range; returns (clipped, saturated flag)."""
        return saturate(ints, self.width, self.signed)

    def to_float(self, ints) -> np.ndarray:
        return np.asarray(ints, dtype=float) * self.lsb

    # -- text ---------------------------------------------------------------------------
    @property
    def vhdl_type(self) -> str:
        """The numeric_std type holding this format's integers, e.g. ``signed(19 downto 0)``."""
        return f"{'signed' if self.signed else 'unsigned'}({self.width - 1} downto 0)"

    def literal(self, value: int) -> str:
        """VHDL bit-string literal of ``value`` (checked to fit)."""
        return bits_literal(value, self.width, self.signed)

    def describe(self) -> str:
        s = "s" if self.signed else "u"
        return f"{s}fix<{self.width},{self.int_bits},{self.rounding},{self.overflow}>"

    @classmethod
    def parse(cls, text: str) -> FixedFormat:
        """The format :meth:`describe` wrote (a manifest's), or :class:`SpecError`."""
        m = _DESCRIBED.fullmatch(str(text).strip())
        if not m:
            raise SpecError(f"{text!r} is not a fixed-point format (sfix<W,I,rnd|trn,sat|wrap>)")
        return cls(int(m.group(2)), int(m.group(3)), m.group(1) == "s", m.group(4), m.group(5))

    def to_dict(self) -> dict:
        d = asdict(self)
        d["frac_bits"] = self.frac_bits
        return d


def signed_range(bits: int) -> tuple[int, int]:
    """(lowest, highest) code of a signed ``bits``-bit word: an ADC's or a temperature sensor's."""
    return -(1 << (bits - 1)), (1 << (bits - 1)) - 1


def nearest_codes(value, lsb, code_min: int, code_max: int) -> np.ndarray:
    """The converter's rule, for voltages and temperatures alike: the nearest code with a tie
    going up (``floor(value / lsb + 1/2)``), saturated to ``code_min..code_max``.

    The twins and the HDL take integer codes; the converter in front of them is this model of
    it, and the family designs are built with the same rule (their clamp codes and calibrated
    temperature codes are the codes the trained range's ends round to this way).  Every path
    from a reading to a code goes through here, so a reading exactly between two codes gets
    one code everywhere (round half to even would take the even one)."""
    c = np.floor(np.asarray(value, dtype=float) / lsb + 0.5)
    return np.clip(c, code_min, code_max).astype(np.int64)


def _code_bound(bits_field: str, end: int) -> property:
    """The lowest (end 0) or highest (end 1) code of the signed word ``spec.<bits_field>`` bits wide."""
    return property(lambda spec: signed_range(getattr(spec, bits_field))[end])


class InputCodes:
    """``code_min``/``code_max``: the range of a spec's signed ``input_bits``-bit input code."""

    code_min = _code_bound("input_bits", 0)
    code_max = _code_bound("input_bits", 1)


class TempCodes:
    """``temp_code_min``/``temp_code_max``: the range of a spec's signed ``temp_bits``-bit
    temperature code."""

    temp_code_min = _code_bound("temp_bits", 0)
    temp_code_max = _code_bound("temp_bits", 1)


def bits_needed(lo: int, hi: int, signed: bool = True) -> int:
    """Smallest width holding every integer in [lo, hi]."""
    lo, hi = int(lo), int(hi)
    if signed:
        n = 1
        while not (-(1 << (n - 1)) <= lo and hi <= (1 << (n - 1)) - 1):
            n += 1
        return n
    if lo < 0:
        raise ValueError("unsigned range with a negative bound")
    return max(1, int(hi).bit_length())


def wrap(ints, width: int, signed: bool = True) -> np.ndarray:
    """Two's complement wrap to ``width`` bits (only where the arithmetic is modular)."""
    a = np.asarray(ints, dtype=np.int64) & ((1 << width) - 1)
    if signed:
        a = np.where(a >= (1 << (width - 1)), a - (1 << width), a)
    return a


def round_shift(ints, shift: int, rounding: str = "rnd") -> np.ndarray:
    """Divide by 2**shift: ``rnd`` adds half an LSB then floors (as the VHDL does)."""
    a = np.asarray(ints, dtype=np.int64)
    if shift <= 0:
        return a << (-shift)
    if rounding == "rnd":
        a = a + (1 << (shift - 1))
    return a >> shift


def saturate(ints, width: int, signed: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Clip to ``width`` bits; returns (clipped, saturated flag)."""
    a = np.asarray(ints, dtype=np.int64)
    lo = -(1 << (width - 1)) if signed else 0
    hi = (1 << (width - 1)) - 1 if signed else (1 << width) - 1
    c = np.clip(a, lo, hi)
    return c, c != a


def bits_literal(value: int, width: int, signed: bool = True) -> str:
    """``"0101"`` style literal; raises SpecError if ``value`` does not fit."""
    value = int(value)
    lo = -(1 << (width - 1)) if signed else 0
    hi = (1 << (width - 1)) - 1 if signed else (1 << width) - 1
    if not lo <= value <= hi:
        raise SpecError(f"constant {value} does not fit {width} {'signed' if signed else 'unsigned'} bits")
    return '"' + format(value & ((1 << width) - 1), f"0{width}b") + '"'


__all__ = ["FixedFormat", "InputCodes", "TempCodes", "bits_needed", "signed_range", "wrap", "round_shift",
           "saturate", "bits_literal", "ROUNDING", "OVERFLOW"]
