"""The LVDT conditioner's blocks and their widths, derived once from the user's choices.

Signal flow (one clock, one sample strobe at the ADC rate ``fs``)::

    NCO: phase += step (T bits, mod 2^T)  ->  table[phase] -> DAC: the word in parallel and a
                                                             first-order sigma-delta bit
    ADC port A, B: offset-binary code -> signed sample (B bits)
    demod A, B:   I += x c[phase + offset], Q += x c[phase + offset + 2^T/4] over M samples
    rotate:       I' = I + Q tan(d) for A and B: the fine reference phase d within the
                  table's step (I cos d + Q sin d without the cos d common to A and B, which
                  the ratio cancels), tan d in R fraction bits, calibrated
    ratio:        (I'_A - I'_B) / (I'_A + I'_B) by a serial restoring divider, F fraction bits

``c[k] = round(A cos(2 pi k / 2^T))`` with ``A = 2^(W-1) - 1``.  The carrier is ``fs /
N`` with ``N`` a power of two (``step = 2^T / N``), so a window of ``M = N K`` samples holds
``K`` whole carrier periods: the integrate-and-dump filter's nulls fall on the carrier's
harmonics (the demodulated 2f term and the excitation's harmonics cancel exactly).

Range analysis (no overflow is possible inside, so nothing in the demodulator saturates):
``|x c| <= 2^(B-1) A``, so an accumulator of ``B + W - 1 + ceil(log2 M)`` signed bits holds
every sum of M products; ``I_A +- I_B`` needs one bit more.  The divider's quotient saturates
at +-(1 - 2^-F) (a ratio beyond one means the secondaries are out of phase with the
reference, a fault) and flags it.

Error analysis: the table's rounding and the reference phase's step are common to both
secondaries and cancel in the ratio to first order, except that a quadrature residual q (a
fraction of the full-scale output) leaks through a reference phase error e as ``q sin e``.
The table alone sets the phase to half a step (0.7 deg with T = 8: 1.2 % of q); the rotation
after integration sets it to ``2^-(R+1)`` rad, so ``R = ceil(log2(q / budget)) + ROTATION_GUARD``
keeps a residual of ``QUADRATURE_FRACTION`` of full scale within ``QUADRATURE_BUDGET`` of it
with the calibration's own error beside it.  ``tan d`` within half a step needs few bits
(8 signed with T = 8, R = 13); ``I + Q tan d`` can exceed the sums' range, so the rotation
saturates at it.  The ratio's quantisation is the ADC's:
integrating M samples of a B-bit converter resolves ``~2^-(B-1) / sqrt(M/2)`` of full scale,
so ``F = B + ceil(log2(M) / 2) + GUARD_BITS`` keeps the divider's LSB below a quarter of it.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ...errors import SpecError

GUARD_BITS = 2
QUADRATURE_FRACTION = 0.1   # the quadrature residual the rotation is sized for, of full scale
QUADRATURE_BUDGET = 50e-6   # its largest move of the ratio, of full scale
ROTATION_GUARD = 2          # the rotation's step a quarter of the phase that budget tolerates
MAX_SAMPLES_PER_PERIOD = 1 << 16
MAX_ACC_BITS = 62   # the twin's int64, with a bit to spare for I_A + I_B


@dataclass(frozen=True)
class ConditionerSpec:
    adc_bits: int             # B: each secondary's converter, two's complement after the port
    table_bits: int           # T: phase resolution (the table has 2^T entries)
    sine_bits: int            # W: reference and DAC words (signed)
    samples_per_period: int   # N: fs / carrier, a power of two
    periods_per_output: int   # K: carrier periods integrated per output
    ratio_frac_bits: int      # F: the ratio's fraction bits
    rotation_bits: int        # R: fraction bits of the fine rotation's tan

    @property
    def phase_bits(self) -> int:
        """P: the NCO's phase accumulator; the table reads its top T bits (P > T when a period
        holds more samples than the table has entries: each entry then serves 2^(P-T) samples)."""
        return max(self.table_bits, self.samples_per_period.bit_length() - 1)

    @property
    def step(self) -> int:
        return (1 << self.phase_bits) // self.samples_per_period

    @property
    def table_lag_rad(self) -> float:
        """The phase by which the demodulator's reference lags the carrier: an entry serving
        2^(P-T) samples in turn is a staircase whose fundamental is (2^(P-T) - 1)/2 samples late
        (0 when P = T).  A secondary at phase p against the NCO's phase zero demodulates at
        p + lag; the calibration measures it there, so the hardware needs no correction, but a
        signal synthesised at a measured phase starts at the phase less the lag."""
        return math.pi * ((1 << (self.phase_bits - self.table_bits)) - 1) / self.samples_per_period

    def phases(self, count: int) -> np.ndarray:
        """The table index the NCO gives each of ``count`` samples from its phase 0."""
        acc = (np.arange(count, dtype=np.int64) * self.step) & ((1 << self.phase_bits) - 1)
        return acc >> (self.phase_bits - self.table_bits)

    @property
    def window(self) -> int:
        """M: samples integrated per output."""
        return self.samples_per_period * self.periods_per_output

    @property
    def amplitude(self) -> int:
        return (1 << (self.sine_bits - 1)) - 1

    @property
    def quarter(self) -> int:
        return 1 << (self.table_bits - 2)

    @property
    def acc_bits(self) -> int:
        bound = self.window * (1 << (self.adc_bits - 1)) * self.amplitude
        return (bound.bit_length()) + 1

    @property
    def sum_bits(self) -> int:
        """Width of I_A - I_B and I_A + I_B."""
        return self.acc_bits + 1

    @property
    def tan_bits(self) -> int:
        """Signed width of the rotation's tan: the tangent of half a table step, in R fraction bits."""
        most = math.floor((1 << self.rotation_bits) * math.tan(math.pi / (1 << self.table_bits)) + 0.5)
        return most.bit_length() + 1

    @property
    def ratio_bits(self) -> int:
        return self.ratio_frac_bits + 1

    def table(self) -> np.ndarray:
        k = np.arange(1 << self.table_bits)
        return np.floor(self.amplitude * np.cos(2 * np.pi * k / (1 << self.table_bits)) + 0.5).astype(np.int64)

    def to_dict(self) -> dict:
        return asdict(self)


def _power_of_two(n: int) -> bool:
    return n >= 1 and n & (n - 1) == 0


def derive_conditioner(adc_bits: int = 12, carrier_hz: float = 5000.0, sample_rate_hz: float | None = None,
                       output_rate_hz: float = 500.0, table_bits: int = 8, sine_bits: int = 12) -> ConditionerSpec:
    """The spec for a carrier, a sample rate (default 32 x the carrier) and an output rate
    (one ratio per whole number of carrier periods), checked; each refusal names the option."""
    if not 4 <= adc_bits <= 24:
        raise SpecError(f"adc bits {adc_bits}: must be 4..24")
    if not 4 <= sine_bits <= 18:
        raise SpecError(f"sine bits {sine_bits}: must be 4..18")
    if not (math.isfinite(carrier_hz) and carrier_hz > 0):
        raise SpecError(f"carrier {carrier_hz:g} Hz: must be > 0")
    fs = sample_rate_hz if sample_rate_hz is not None else 32 * carrier_hz
    n = fs / carrier_hz
    if abs(n - round(n)) > 1e-6 * n or not _power_of_two(int(round(n))) or round(n) < 8:
        raise SpecError(f"sample rate {fs:g} Hz over carrier {carrier_hz:g} Hz = {n:g}: must be a power of "
                        "two, at least 8 (the NCO steps a whole table per carrier period)")
    n = int(round(n))
    if not (math.isfinite(output_rate_hz) and 0 < output_rate_hz <= carrier_hz):
        raise SpecError(f"output rate {output_rate_hz:g} Hz: must be > 0 and at most the carrier "
                        f"{carrier_hz:g} Hz (a ratio integrates whole carrier periods)")
    k = max(1, int(round(carrier_hz / output_rate_hz)))
    if not 2 <= table_bits <= 16:
        raise SpecError(f"table bits {table_bits}: must be 2..16")
    if n > MAX_SAMPLES_PER_PERIOD:
        raise SpecError(f"sample rate {fs:g} Hz over carrier {carrier_hz:g} Hz = {n}: at most "
                        f"{MAX_SAMPLES_PER_PERIOD} samples a period (the NCO's accumulator)")
    frac = adc_bits + math.ceil(math.log2(n * k) / 2) + GUARD_BITS
    spec = ConditionerSpec(adc_bits=adc_bits, table_bits=table_bits, sine_bits=sine_bits,
                           samples_per_period=n, periods_per_output=k, ratio_frac_bits=frac,
                           rotation_bits=rotation_bits())
    if spec.sum_bits > MAX_ACC_BITS:
        raise SpecError(f"{k} periods of {n} samples need a {spec.sum_bits}-bit accumulator, more than "
                        f"{MAX_ACC_BITS}: raise the output rate")
    return spec


def rotation_bits() -> int:
    """R: the rotation's angle step 2^-R rad within the phase error the quadrature budget
    tolerates (``asin(budget / residual)``), with ROTATION_GUARD bits to spare."""
    tolerated = math.asin(QUADRATURE_BUDGET / QUADRATURE_FRACTION)
    return math.ceil(math.log2(1.0 / tolerated)) + ROTATION_GUARD


def output_rate_hz(spec: ConditionerSpec, carrier_hz: float) -> float:
    return carrier_hz / spec.periods_per_output


def bandwidth_hz(spec: ConditionerSpec, carrier_hz: float) -> float:
    """-3 dB bandwidth of integrating over the window (a boxcar: 0.443 / window time)."""
    return 0.4429 * output_rate_hz(spec, carrier_hz)


@dataclass(frozen=True)
class Reference:
    """The calibrated reference phase as the hardware holds it: the table's step (``offset``)
    and the rotation by the rest (its ``tan`` in R fraction bits)."""

    offset: int
    tan: int


def calibration_offset(spec: ConditionerSpec, phase_rad: float) -> int:
    """The reference-phase register for a secondary phase of ``phase_rad`` against the
    excitation: the table step nearest to it."""
    return int(np.floor(phase_rad / (2 * math.pi) * (1 << spec.table_bits) + 0.5)) % (1 << spec.table_bits)


def reference(spec: ConditionerSpec, phase_rad: float) -> Reference:
    """The registers for a reference phase: its nearest table step, then the rotation by the
    remainder (within half a step)."""
    offset = calibration_offset(spec, phase_rad)
    rest = math.remainder(phase_rad - 2 * math.pi * offset / (1 << spec.table_bits), 2 * math.pi)
    return Reference(offset, int(math.floor((1 << spec.rotation_bits) * math.tan(rest) + 0.5)))


def reference_phase(spec: ConditionerSpec, ref: Reference) -> float:
    """The phase (rad) the registers set: the table's step plus the rotation's angle."""
    return 2 * math.pi * ref.offset / (1 << spec.table_bits) + math.atan(ref.tan / (1 << spec.rotation_bits))


def identity(spec: ConditionerSpec, offset: int = 0) -> Reference:
    """The table's step alone, no rotation."""
    return Reference(int(offset), 0)
