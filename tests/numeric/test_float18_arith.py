"""float18 arithmetic against exactly rounded results computed independently.

The reference here never calls the rounding code under test: it decodes codes from the
bit layout written out below, lists every representable positive value as a Fraction,
and rounds an exact rational to the nearest entry of that list by bisection (ties to the
entry whose fraction field is even), with the documented policies:
  * |q| above max finite -> +-max finite (saturate);
  * |q| below the rounding threshold of the smallest normal -> +0 (flush to zero), where
    the threshold is the midpoint between 2^-30 and its unbounded-exponent predecessor
    2^-30 - 2^-42 (a tie there goes to 2^-30, whose significand 2048 is even);
  * a zero result is the canonical code 0.
"""

from __future__ import annotations

import bisect
import random
from fractions import Fraction

import numpy as np
import pytest

from flann.errors import FlannError
from flann.numeric.float18 import FLOAT18, FlannF18Add, FlannF18Mul

F = FLOAT18
SEED = 20261122

# Layout written from the documented format, not read from the module.
W, EB, FB, BIAS = 18, 6, 11, 31


def ref_decode(code: int) -> Fraction:
    s, e, f = code >> 17, (code >> 11) & 63, code & 2047
    if e == 0:
        return Fraction(0)
    v = Fraction(2048 + f, 2048) * Fraction(2) ** (e - 31)
    return -v if s else v


POS_CODES = list(range(1 << 11, 1 << 17))          # every positive normal code, ascending
POS_VALUES = [ref_decode(c) for c in POS_CODES]
MAX = POS_VALUES[-1]
MIN = POS_VALUES[0]
FTZ_THRESHOLD = MIN - Fraction(1, 2 ** 43)         # midpoint of 2^-30 - 2^-42 and 2^-30


def ref_round(q: Fraction) -> Fraction:
    if q == 0:
        return Fraction(0)
    sign = -1 if q < 0 else 1
    a = abs(q)
    if a > MAX:
        return sign * MAX
    if a < FTZ_THRESHOLD:
        return Fraction(0)
    if a <= MIN:
        return sign * MIN
    i = bisect.bisect_left(POS_VALUES, a)
    if POS_VALUES[i] == a:
        return sign * a
    lo, hi = POS_VALUES[i - 1], POS_VALUES[i]
    if a - lo < hi - a:
        return sign * lo
    if hi - a < a - lo:
        return sign * hi
    # tie: the neighbour with an even fraction field
    return sign * (lo if POS_CODES[i - 1] % 2 == 0 else hi)


def is_tie(q: Fraction) -> bool:
    a = abs(q)
    if not MIN < a < MAX:
        return False
    i = bisect.bisect_left(POS_VALUES, a)
    return POS_VALUES[i] != a and a - POS_VALUES[i - 1] == POS_VALUES[i] - a


def check(code: int, exact: Fraction) -> None:
    want = ref_round(exact)
    got = ref_decode(code)
    assert got == want, f"exact {exact} ({float(exact)!r}): got {float(got)!r}, want {float(want)!r}"
    if want == 0:
        assert code == 0, f"zero result must be the canonical +0, got {code:#07x}"


def rand_code(rng: random.Random, exp_lo=1, exp_hi=63) -> int:
    return (rng.getrandbits(1) << 17) | (rng.randint(exp_lo, exp_hi) << 11) | rng.getrandbits(11)


# -- layout and decode ------------------------------------------------------------------
def test_layout_by_hand():
    assert F.width == 18 and F.exp_bits == 6 and F.frac_bits == 11 and F.bias == 31
    assert F.decode(0b0_011111_00000000000) == 1
    assert F.decode(0b1_100000_10000000000) == Fraction(-3)
    assert F.decode(0b0_000001_00000000000) == Fraction(1, 2 ** 30)
    assert F.decode(0b0_111111_11111111111) == 4095 * 2 ** 21
    # any exponent-0 code reads as zero, whatever the sign and fraction
    for c in (0, 1 << 17, 0x7FF, (1 << 17) | 0x7FF):
        assert F.decode(c) == 0
    assert np.array_equal(F.decode_array([0x1FFFF, 0x3FFFF, 0x207FF]),
                          [4095.0 * 2 ** 21, -4095.0 * 2 ** 21, 0.0])


def test_every_code_decodes_like_reference():
    codes = np.arange(1 << 18)
    got = F.decode_array(codes)
    want = np.array([float(ref_decode(int(c))) for c in codes[::97]])
    assert np.array_equal(got[::97], want)
    # scalar and vector agree on every code
    assert all(F.to_float(int(c)) == got[c] for c in range(0, 1 << 18, 331))


# -- encode -----------------------------------------------------------------------------
def _encode_cases(rng):
    cases = [Fraction(0), Fraction(1), Fraction(-1), MAX, -MAX, MIN, -MIN,
             MAX + 1, MAX * 2, -(MAX * 3), MAX + Fraction(2 ** 20),   # overflow
             FTZ_THRESHOLD, FTZ_THRESHOLD - Fraction(1, 2 ** 80), MIN / 2, -MIN / 3,
             FTZ_THRESHOLD + Fraction(1, 2 ** 80), Fraction(1, 10), Fraction(-7, 3)]
    # exact midpoints between neighbours (ties) and points next to them
    for _ in range(400):
        i = rng.randrange(1, len(POS_VALUES))
        mid = (POS_VALUES[i - 1] + POS_VALUES[i]) / 2
        eps = (POS_VALUES[i] - POS_VALUES[i - 1]) / 2 ** 20
        sign = rng.choice((1, -1))
        cases += [sign * mid, sign * (mid + eps), sign * (mid - eps)]
    for _ in range(600):
        cases.append(Fraction(rng.randint(-10 ** 12, 10 ** 12), rng.randint(1, 10 ** 9)))
        cases.append(Fraction(rng.getrandbits(40) or 1, 2 ** rng.randint(0, 90)))
    return cases


def test_encode_fraction_exactly_rounded():
    rng = random.Random(SEED)
    cases = _encode_cases(rng)
    assert sum(is_tie(q) for q in cases) >= 400        # ties really exercised
    for q in cases:
        check(F.encode(q), q)


def test_encode_float_scalar_and_vector_agree_with_reference():
    rng = random.Random(SEED + 1)
    xs = [0.0, -0.0, 1e300, -1e300, float("inf"), float("-inf"), 5e-324, 2.0 ** -30,
          2.0 ** -30 - 2.0 ** -43, 2.0 ** -30 - 2.0 ** -43 - 2.0 ** -60, 1 + 2.0 ** -12,
          1 + 3 * 2.0 ** -12, -(1 + 2.0 ** -12)]
    xs += [rng.uniform(-1, 1) * 2.0 ** rng.randint(-40, 40) for _ in range(3000)]
    vec = F.encode_array(xs)
    for x, cv in zip(xs, vec):
        c = F.encode(x)
        assert c == cv, x
        exact = Fraction(x) if np.isfinite(x) else (MAX * 2 if x > 0 else -MAX * 2)
        check(c, exact)
    assert F.encode(1 + 2.0 ** -12) == 0b0_011111_00000000000      # tie down to even
    assert F.encode(1 + 3 * 2.0 ** -12) == 0b0_011111_00000000010   # tie up to even
    assert F.encode(1e300) == 0x1FFFF and F.encode(-1e300) == 0x3FFFF
    assert F.encode(-0.0) == 0 and F.encode(-1e-20) == 0


def test_encode_nan_is_an_error():
    with pytest.raises(FlannError, match="NaN"):
        F.encode(float("nan"))
    with pytest.raises(FlannError, match="NaN"):
        F.encode_array([1.0, float("nan")])


# -- multiply ---------------------------------------------------------------------------
def test_mul_exactly_rounded_including_ties():
    rng = random.Random(SEED + 2)
    pairs = []
    # a few significands against every significand: products of 12-bit numbers hit ties
    for sa in (1024, 512, 1536, 1, rng.getrandbits(11)):  # trailing zeros -> ties
        for fb in range(2048):
            a = (rng.getrandbits(1) << 17) | (31 << 11) | sa
            b = (rng.getrandbits(1) << 17) | (rng.randint(20, 40) << 11) | fb
            pairs.append((a, b))
    pairs += [(rand_code(rng), rand_code(rng)) for _ in range(2000)]
    ties = 0
    for a, b in pairs:
        exact = ref_decode(a) * ref_decode(b)
        ties += is_tie(exact)
        check(F.mul(a, b), exact)
    assert ties >= 100


def test_mul_overflow_underflow_zero_sign():
    big = 0b0_111111_11111111111
    one = 0b0_011111_00000000000
    two = 0b0_100000_00000000000
    tiny = 0b0_000001_00000000000       # 2^-30
    half = 0b0_011110_00000000000
    assert F.mul(big, two) == big                          # saturate, sign kept
    assert F.mul(big, two | (1 << 17)) == big | (1 << 17)
    assert F.mul(big, big) == big
    assert F.mul(tiny, half) == 0                           # 2^-31: flush to +0
    assert F.mul(tiny | (1 << 17), half) == 0               # negative underflow is +0 too
    assert F.mul(tiny, one) == tiny
    # (2^-30 - 2^-42)-ish products that round up to 2^-30 are kept
    a = 0b0_011110_11111111111          # (2 - 2^-11) / 2
    check(F.mul(tiny | 0, a), ref_decode(tiny) * ref_decode(a))
    for z in (0, 1 << 17, 0x7FF, (1 << 17) | 5):
        assert F.mul(z, big) == 0 and F.mul(big | (1 << 17), z) == 0
    assert F.mul(one | (1 << 17), two | (1 << 17)) == two


# -- add --------------------------------------------------------------------------------
def test_add_exactly_rounded_all_exponent_gaps():
    rng = random.Random(SEED + 3)
    pairs = []
    for _ in range(3000):
        ea = rng.randint(1, 63)
        eb = min(63, max(1, ea - rng.choice(range(-30, 31))))
        a = (rng.getrandbits(1) << 17) | (ea << 11) | rng.getrandbits(11)
        b = (rng.getrandbits(1) << 17) | (eb << 11) | rng.getrandbits(11)
        pairs.append((a, b))
    # ties by construction: b's significand shifted so one bit lands just below a's lsb
    for _ in range(800):
        ea = rng.randint(15, 50)
        d = rng.randint(1, 12)
        a = (rng.getrandbits(1) << 17) | (ea << 11) | rng.getrandbits(11)
        b = (rng.getrandbits(1) << 17) | ((ea - d) << 11) | (1 << (d - 1) if d <= 11 else 0)
        pairs.append((a, b))
    ties = cancel = 0
    for a, b in pairs:
        exact = ref_decode(a) + ref_decode(b)
        ties += is_tie(exact)
        if exact != 0 and abs(exact) < max(abs(ref_decode(a)), abs(ref_decode(b))) / 4:
            cancel += 1
        check(F.add(a, b), exact)
        assert F.add(a, b) == F.add(b, a)
        check(F.sub(a, b), ref_decode(a) - ref_decode(b))
    assert ties >= 50 and cancel >= 25


def test_add_cancellation_overflow_underflow_zero():
    big = 0b0_111111_11111111111
    one = 0b0_011111_00000000000
    tiny = 0b0_000001_00000000000
    tiny_up = 0b0_000001_00000000001
    for c in (one, big, tiny, 0b0_101010_10101010101):
        assert F.add(c, c | (1 << 17)) == 0                 # x + (-x) = +0
        assert F.add(c | (1 << 17), c) == 0
    assert F.add(big, big) == big and F.add(big | (1 << 17), big | (1 << 17)) == big | (1 << 17)
    assert F.add(tiny_up, tiny | (1 << 17)) == 0            # 2^-41: flush to +0
    assert F.add(tiny, tiny) == 0b0_000010_00000000000
    # massive cancellation is exact: (1 + 2^-11) - 1 = 2^-11
    assert F.decode(F.add(one | 1, one | (1 << 17))) == Fraction(1, 2 ** 11)
    # zero operands (including non-canonical zeros) leave the other operand unchanged
    for z in (0, 1 << 17, 0x3FF, (1 << 17) | 0x7FF):
        assert F.add(z, one | (1 << 17)) == one | (1 << 17)
        assert F.add(one, z) == one
        assert F.add(z, z) == 0
    # a far smaller addend only rounds: 1 + 2^-12 ties to 1, 1 + 2^-12 + 2^-30 rounds up
    assert F.add(one, 0b0_010011_00000000000) == one
    assert F.add(F.add(one, tiny), 0) == one


# -- vectorised = scalar ----------------------------------------------------------------
def test_vectorised_ops_equal_scalar_exact():
    rng = np.random.default_rng(SEED + 4)
    n = 20000
    a = rng.integers(0, 1 << 18, n)
    # half the b's share a's exponent region so that cancellation and ties are common
    near = (a & ~np.int64(0x7FF)) ^ rng.integers(0, 1 << 13, n)
    b = np.where(rng.random(n) < 0.5, rng.integers(0, 1 << 18, n), near & 0x3FFFF)
    vm, va = F.mul_array(a, b), F.add_array(a, b)
    for i in range(n):
        ai, bi = int(a[i]), int(b[i])
        assert vm[i] == F.mul(ai, bi), (ai, bi)
        assert va[i] == F.add(ai, bi), (ai, bi)


# -- twins' pipelines ---------------------------------------------------------------------
def test_twin_latency_and_valid():
    one, two = F.encode(1), F.encode(2)
    for twin, lat in ((FlannF18Mul(), 2), (FlannF18Add(), 3)):
        assert twin.latency == lat
        outs = [twin.step(True, one, two)] + [twin.step(False) for _ in range(lat + 1)]
        valid = [v for v, _ in outs]
        assert valid == [False] * (lat - 1) + [True] + [False] * 2, twin.entity
        assert outs[lat - 1][1] == (F.encode(2) if lat == 2 else F.encode(3))
        twin.reset()
        assert twin.step(False) == (False, None)
    assert FlannF18Mul().entity == "flann_f18_mul" and FlannF18Add().entity == "flann_f18_add"
