"""The seed paper's 18-bit floating-point number format, and bit-true twins of its blocks.

The paper builds its multiplier and adder blocks "in 18-bit floating point" without giving
the split.  This module fixes it (see docs/float18.md)::

    bit 17      16 ........ 11   10 ............ 0
    sign        exponent (6)     fraction (11)        value = (-1)^s * 1.f * 2^(e - 31)

* **hidden bit**: every non-zero code is normal; the significand is ``1.f`` (12 bits).
* **bias 31**; exponent field 1..63 are ordinary exponents (there is no infinity and no NaN:
  the hardware saturates).  Range: min normal 2^-30 ~ 9.3e-10, max 4095 * 2^21 ~ 8.59e9.
* **zero**: any code whose exponent field is 0 *reads* as zero (sign and fraction ignored);
  every zero *result* is written as the canonical +0 (all 18 bits clear).
* **rounding**: round to nearest, ties to even, computed as if the exponent were unbounded;
  then the two range policies below are applied to the rounded value.
* **overflow**: a rounded magnitude above the max finite value saturates to +-max finite
  (sign kept).  The hardware saturates, it never wraps and never produces infinity.
* **underflow**: flush to zero.  A rounded magnitude below 2^-30 becomes +0 (no subnormals;
  a value that *rounds up* to 2^-30 is kept as 2^-30).

Two implementations of each operation, which the tests check against each other and
against an independent Fraction reference:

* scalar, exact: ``fmt.encode(x)`` (int, float or Fraction), ``fmt.mul(a, b)``,
  ``fmt.add(a, b)`` on Python integers (exact product/sum, then one rounding);
* vectorised: ``fmt.encode_array``, ``fmt.mul_array``, ``fmt.add_array`` on numpy int64 code
  arrays.  A product of two 12-bit significands is exact in float64, and a float64 sum is a
  correctly rounded sum; rounding that again to 12 bits equals rounding the exact sum once
  because 53 >= 2 * 12 + 2 (double rounding is innocuous for +, -, *; Figueroa 1995).

The twins :class:`FlannF18Mul` and :class:`FlannF18Add` carry the VHDL entities' names and latencies
and model their valid pipelines cycle by cycle (``reset`` / ``step``).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from fractions import Fraction
from numbers import Rational

import numpy as np

from ..errors import FlannError, SpecError


@dataclass(frozen=True)
class FloatFormat:
    """A sign / biased-exponent / hidden-bit-fraction format with RNE, saturation and FTZ."""

    exp_bits: int = 6
    frac_bits: int = 11
    bias: int = 31
    name: str = "f18"

    def __post_init__(self) -> None:
        if not 2 <= self.exp_bits <= 10:
            raise SpecError(f"float format: exp_bits is {self.exp_bits}, allowed 2..10")
        # 53 >= 2 p + 2 keeps the float64 fast path exactly rounded (p = frac_bits + 1).
        if not 1 <= self.frac_bits <= 24:
            raise SpecError(f"float format: frac_bits is {self.frac_bits}, allowed 1..24")
        if not 0 <= self.bias < (1 << self.exp_bits) - 1:
            raise SpecError(f"float format: bias is {self.bias}, allowed 0..{(1 << self.exp_bits) - 2}")

    # -- geometry ----------------------------------------------------------------------
    @property
    def width(self) -> int:
        return 1 + self.exp_bits + self.frac_bits

    @property
    def sig_bits(self) -> int:
        """Significand bits including the hidden one."""
        return self.frac_bits + 1

    @property
    def exp_max(self) -> int:
        """Largest exponent field (an ordinary exponent: no inf/NaN)."""
        return (1 << self.exp_bits) - 1

    @property
    def sign_mask(self) -> int:
        return 1 << (self.width - 1)

    @property
    def frac_mask(self) -> int:
        return (1 << self.frac_bits) - 1

    @property
    def max_code(self) -> int:
        """Largest positive finite code (all exponent and fraction bits set)."""
        return self.sign_mask - 1

    @property
    def min_normal_code(self) -> int:
        return 1 << self.frac_bits

    @property
    def max_value(self) -> Fraction:
        return self.decode(self.max_code)

    @property
    def min_normal(self) -> Fraction:
        return self.decode(self.min_normal_code)

    def describe(self) -> str:
        return (f"{self.name}: 1 sign, {self.exp_bits} exponent (bias {self.bias}), "
                f"{self.frac_bits} fraction bits + hidden bit; RNE; saturate to max finite; "
                f"flush to zero below 2^{1 - self.bias}; zero result is +0")

    def to_dict(self) -> dict:
        return {"kind": "float", "name": self.name, "width": self.width,
                "exp_bits": self.exp_bits, "frac_bits": self.frac_bits, "bias": self.bias,
                "rounding": "nearest-even", "overflow": "saturate", "underflow": "flush-to-zero"}

    # -- fields ------------------------------------------------------------------------
    def fields(self, code: int) -> tuple[int, int, int]:
        """(sign, exponent field, fraction field) of a code."""
        code = self._check_code(code)
        return (code >> (self.width - 1), (code >> self.frac_bits) & self.exp_max,
                code & self.frac_mask)

    def pack(self, sign: int, exp: int, frac: int) -> int:
        if not (0 <= exp <= self.exp_max and 0 <= frac <= self.frac_mask and sign in (0, 1)):
            raise ValueError(f"{self.name}: field out of range (s={sign}, e={exp}, f={frac})")
        return (sign << (self.width - 1)) | (exp << self.frac_bits) | frac

    def is_zero(self, code: int) -> bool:
        return self.fields(code)[1] == 0

    def neg(self, code: int) -> int:
        """Sign flip (the adder block subtracts this way); zero stays +0."""
        code = self._check_code(code)
        return 0 if self.is_zero(code) else code ^ self.sign_mask

    def _check_code(self, code) -> int:
        c = int(code)
        if not 0 <= c < (1 << self.width):
            raise ValueError(f"{self.name}: code {code!r} outside 0..{(1 << self.width) - 1}")
        return c

    # -- scalar, exact -----------------------------------------------------------------
    def decode(self, code: int) -> Fraction:
        """Exact value of a code."""
        s, e, f = self.fields(code)
        if e == 0:
            return Fraction(0)
        mag = Fraction((1 << self.frac_bits) | f) * Fraction(2) ** (e - self.bias - self.frac_bits)
        return -mag if s else mag

    def to_float(self, code: int) -> float:
        return float(self.decode(code))

    def _sig_exp(self, code: int) -> tuple[int, int, int]:
        """(sign, integer significand, k) with value (-1)^sign * sig * 2^k; sig = 0 for zero."""
        s, e, f = self.fields(code)
        if e == 0:
            return (0, 0, 0)
        return (s, (1 << self.frac_bits) | f, e - self.bias - self.frac_bits)

    def round_scaled(self, sign: int, m: int, k: int) -> int:
        """Code of (-1)^sign * m * 2^k (m >= 0 an integer), rounded once (RNE), then
        saturated / flushed to zero."""
        if m == 0:
            return 0
        shift = m.bit_length() - self.sig_bits
        if shift > 0:
            n = m >> shift
            rem = m & ((1 << shift) - 1)
            half = 1 << (shift - 1)
            if rem > half or (rem == half and n & 1):
                n += 1
            if n >> self.sig_bits:          # rounding carried into a new bit
                n >>= 1
                shift += 1
        else:
            n = m << -shift
        unbiased = k + shift + self.frac_bits     # value = (n / 2^F) * 2^unbiased
        e = unbiased + self.bias
        if e < 1:
            return 0
        if e > self.exp_max:
            return self.pack(sign, self.exp_max, self.frac_mask)
        return self.pack(sign, e, n & self.frac_mask)

    def encode(self, x) -> int:
        """Code nearest to x (int, float or Fraction); RNE, saturate, flush to zero."""
        if isinstance(x, float):
            if math.isnan(x):
                raise FlannError(f"{self.name}: cannot encode NaN")
            if math.isinf(x):
                return self.pack(int(x < 0), self.exp_max, self.frac_mask)
            x = Fraction(x)
        elif isinstance(x, (int, np.integer)):
            x = Fraction(int(x))
        elif not isinstance(x, Rational):
            raise TypeError(f"{self.name}: cannot encode {type(x).__name__}")
        q = Fraction(x)
        if q == 0:
            return 0
        sign = int(q < 0)
        q = abs(q)
        # Scale to an integer with at least sig_bits + 2 bits, keeping the rest as sticky.
        num, den = q.numerator, q.denominator
        extra = self.sig_bits + 2 + den.bit_length() - num.bit_length()
        k = -max(extra, 0)
        scaled_num = num << -k
        m, r = divmod(scaled_num, den)
        # m * 2^k <= q < (m + 1) * 2^k; fold a non-zero remainder into a sticky bit below m.
        return self.round_scaled(sign, (m << 1) | (r != 0), k - 1)

    def mul(self, a: int, b: int) -> int:
        """Exactly rounded product of two codes."""
        sa, ma, ka = self._sig_exp(a)
        sb, mb, kb = self._sig_exp(b)
        return self.round_scaled(sa ^ sb, ma * mb, ka + kb)

    def add(self, a: int, b: int) -> int:
        """Exactly rounded sum of two codes."""
        sa, ma, ka = self._sig_exp(a)
        sb, mb, kb = self._sig_exp(b)
        if ma == 0:
            ka = kb
        if mb == 0:
            kb = ka
        k = min(ka, kb)
        total = (-1) ** sa * (ma << (ka - k)) + (-1) ** sb * (mb << (kb - k))
        return self.round_scaled(int(total < 0), abs(total), k)

    def sub(self, a: int, b: int) -> int:
        return self.add(a, self.neg(b))

    # -- vectorised ----------------------------------------------------------------------
    def decode_array(self, codes) -> np.ndarray:
        """float64 values of an array of codes (exact: every value fits float64)."""
        c = np.asarray(codes, dtype=np.int64)
        if c.size and (c.min() < 0 or c.max() >= (1 << self.width)):
            raise ValueError(f"{self.name}: code outside 0..{(1 << self.width) - 1}")
        s = (c >> (self.width - 1)) & 1
        e = (c >> self.frac_bits) & self.exp_max
        f = c & self.frac_mask
        mag = np.ldexp((f | (1 << self.frac_bits)).astype(float), e - self.bias - self.frac_bits)
        return np.where(e == 0, 0.0, np.where(s == 1, -mag, mag))

    def encode_array(self, x) -> np.ndarray:
        """int64 codes of float64 values (RNE, saturate, flush to zero)."""
        x = np.asarray(x, dtype=float)
        if np.isnan(x).any():
            raise FlannError(f"{self.name}: cannot encode NaN")
        sign = (x < 0).astype(np.int64)
        a = np.abs(x)
        finite = np.isfinite(a)
        m, e = np.frexp(np.where(finite, a, 1.0))       # a = m 2^e, m in [0.5, 1)
        n = np.rint(m * float(1 << self.sig_bits))       # ties to even
        carry = n >= float(1 << self.sig_bits)
        n = np.where(carry, float(1 << self.frac_bits), n).astype(np.int64)
        eb = e.astype(np.int64) - 1 + carry + self.bias
        code = (sign << (self.width - 1)) | (eb << self.frac_bits) | (n & self.frac_mask)
        sat = (sign << (self.width - 1)) | self.max_code
        code = np.where((eb > self.exp_max) | ~finite, sat, code)
        code = np.where((eb < 1) | (a == 0), 0, code)
        return code.astype(np.int64)

    def quantise(self, x) -> np.ndarray:
        """float64 -> nearest representable value (float64)."""
        return self.decode_array(self.encode_array(x))

    def mul_array(self, a, b) -> np.ndarray:
        return self.encode_array(self.decode_array(a) * self.decode_array(b))

    def add_array(self, a, b) -> np.ndarray:
        return self.encode_array(self.decode_array(a) + self.decode_array(b))

    def ulp(self, x) -> np.ndarray:
        """Spacing of the format at |x| (for error budgets); min normal spacing near 0."""
        a = np.maximum(np.abs(np.asarray(x, dtype=float)), float(self.min_normal))
        _, e = np.frexp(a)
        return np.ldexp(1.0, e - 1 - self.frac_bits)


FLOAT18 = FloatFormat()


# -- twins of the VHDL blocks ----------------------------------------------------------
@dataclass(frozen=True)
class FloatOut:
    """Output port of a float block twin (``out_y``), the result its ``process`` returns."""

    out_y: np.ndarray


class _PipelinedTwin:
    """Cycle model of a fixed-latency pipeline with a valid flag (data is not reset)."""

    latency = 1
    suffix = ""

    def __init__(self, fmt: FloatFormat = FLOAT18) -> None:
        self.fmt = fmt
        self.reset()

    @property
    def entity(self) -> str:
        return f"flann_{self.fmt.name}_{self.suffix}"

    def reset(self) -> None:
        self._pipe: deque[tuple[bool, int | None]] = deque([(False, None)] * self.latency)

    def compute(self, a: int, b: int) -> int:
        raise NotImplementedError

    def process(self, in_a, in_b) -> FloatOut:
        """Every (in_a, in_b) pair, vectorised; ``out_y`` as the entity gives it ``latency`` cycles later."""
        return FloatOut(out_y=self._compute_array(in_a, in_b))

    def step(self, in_valid: bool, a: int = 0, b: int = 0) -> tuple[bool, int | None]:
        """One rising edge: returns (out_valid, out_y) after the edge."""
        self._pipe.append((bool(in_valid), self.compute(a, b) if in_valid else None))
        self._pipe.popleft()
        return self._pipe[0]


class FlannF18Mul(_PipelinedTwin):
    """Twin of ``flann_f18_mul``: out_y = RNE(in_a * in_b), 2 clock cycles later."""

    latency = 2
    suffix = "mul"

    def compute(self, a: int, b: int) -> int:
        return self.fmt.mul(a, b)

    def _compute_array(self, a, b) -> np.ndarray:
        return self.fmt.mul_array(a, b)


class FlannF18Add(_PipelinedTwin):
    """Twin of ``flann_f18_add``: out_y = RNE(in_a + in_b), 3 clock cycles later."""

    latency = 3
    suffix = "add"

    def compute(self, a: int, b: int) -> int:
        return self.fmt.add(a, b)

    def _compute_array(self, a, b) -> np.ndarray:
        return self.fmt.add_array(a, b)


__all__ = ["FloatOut", "FLOAT18", "FlannF18Add", "FlannF18Mul", "FloatFormat"]
