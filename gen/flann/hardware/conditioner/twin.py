"""Bit-true twins of the conditioner's entities (same names, same integer arithmetic).

Each class has the entity's name (``entity``) and ``process(...)`` returning a record whose
fields are named after the entity's output ports.  The NCO is modelled cycle by cycle (its
sigma-delta bit runs at the clock); the other blocks by the values they deliver, in order
(their cycle timing is the bench's to check against the spec's ``latency``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..twin import Record
from .spec import ConditionerSpec, Reference


@dataclass(frozen=True)
class NcoOut(Record):
    out_phase: np.ndarray   # the phase of the sample (T bits, unsigned)
    out_dac: np.ndarray     # the table's word at that phase (W bits, signed)
    out_sd: np.ndarray      # first-order sigma-delta bit of out_dac (per clock)


class FlannCondNco:
    """Phase accumulator, cosine table and DAC port; ``in_en`` steps the phase by one sample."""

    entity = "flann_cond_nco"
    latency = 1

    def __init__(self, spec: ConditionerSpec):
        self.spec = spec
        self.table = spec.table()

    def process(self, en) -> NcoOut:
        """Registered outputs after each clock, for the ``in_en`` value of each clock (from reset)."""
        s = self.spec
        en = np.asarray(en, dtype=np.int64)
        mask, full, drop = (1 << s.phase_bits) - 1, 1 << s.sine_bits, s.phase_bits - s.table_bits
        acc = phase = dac = err = 0
        out = np.zeros((3, en.size), dtype=np.int64)
        for i, e in enumerate(en):
            total = err + dac + (full >> 1)   # the DAC word, offset to unsigned, into the modulator
            bit, err = total >> s.sine_bits, total & (full - 1)
            if e:
                phase = acc >> drop
                dac = int(self.table[phase])
                acc = (acc + s.step) & mask
            out[:, i] = phase, dac, bit
        return NcoOut(*out)


@dataclass(frozen=True)
class AdcOut(Record):
    out_sample: np.ndarray


class FlannCondAdc:
    """ADC input port: a straight-binary code in, a two's complement sample out."""

    entity = "flann_cond_adc"
    latency = 1

    def __init__(self, spec: ConditionerSpec):
        self.spec = spec

    def process(self, codes) -> AdcOut:
        return AdcOut(np.asarray(codes, dtype=np.int64) - (1 << (self.spec.adc_bits - 1)))


@dataclass(frozen=True)
class DemodOut(Record):
    out_i: np.ndarray   # per window: sum of x c[phase + offset]
    out_q: np.ndarray   # per window: sum of x c[phase + offset + quarter]


class FlannCondDemod:
    """Synchronous I/Q demodulation of one secondary and integration over a window of whole
    carrier periods (integrate and dump)."""

    entity = "flann_cond_demod"

    def __init__(self, spec: ConditionerSpec):
        self.spec = spec
        self.table = spec.table()

    @property
    def latency(self) -> int:
        """Clocks from a window's last sample strobe to its output (table read, serial product)."""
        return self.spec.adc_bits + 3

    def process(self, samples, phases, offset: int) -> DemodOut:
        """Every whole window of ``samples`` (the NCO's ``phases`` of each sample)."""
        s = self.spec
        x = np.asarray(samples, dtype=np.int64)
        mask = (1 << s.table_bits) - 1
        idx = (np.asarray(phases, dtype=np.int64) + int(offset)) & mask
        n = x.size // s.window * s.window
        i = (x * self.table[idx])[:n].reshape(-1, s.window).sum(axis=1)
        q = (x * self.table[(idx + s.quarter) & mask])[:n].reshape(-1, s.window).sum(axis=1)
        return DemodOut(i, q)


@dataclass(frozen=True)
class RotateOut(Record):
    out_a: np.ndarray   # per window: A's in-phase sum at the fine reference phase
    out_b: np.ndarray


class FlannCondRotate:
    """The fine reference phase: ``I + floor(Q tan / 2^R)`` of each secondary's window (the
    rotation without its cos, common to both secondaries), saturated to the sums' width."""

    entity = "flann_cond_rotate"

    def __init__(self, spec: ConditionerSpec):
        self.spec = spec

    @property
    def latency(self) -> int:
        """Clocks from the strobe to the result: the operands, one bit of tan a clock, the sum
        and saturation."""
        return self.spec.tan_bits + 2

    def one(self, i: int, q: int, tan: int) -> int:
        s = self.spec
        hi = (1 << (s.acc_bits - 1)) - 1
        return max(-hi - 1, min(hi, int(i) + ((int(q) * tan) >> s.rotation_bits)))

    def process(self, i_a, q_a, i_b, q_b, tan: int) -> RotateOut:
        a = [self.one(i, q, tan) for i, q in zip(np.asarray(i_a).tolist(), np.asarray(q_a).tolist())]
        b = [self.one(i, q, tan) for i, q in zip(np.asarray(i_b).tolist(), np.asarray(q_b).tolist())]
        return RotateOut(np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64))


@dataclass(frozen=True)
class RatioOut(Record):
    out_ratio: np.ndarray   # (A - B) / (A + B) in F fraction bits, truncated towards zero
    out_sat: np.ndarray     # 1: |A - B| >= A + B or A + B <= 0 (out of phase, or no signal)


class FlannCondRatio:
    """The ratiometric (A - B) / (A + B) by a serial restoring divider (one bit per clock)."""

    entity = "flann_cond_ratio"

    def __init__(self, spec: ConditionerSpec):
        self.spec = spec

    @property
    def latency(self) -> int:
        """Clocks from the strobe to the ratio: the operands, then one quotient bit a clock."""
        return self.spec.ratio_frac_bits + 3

    saturated_latency = 2   # a saturated ratio: the operands, then the judgement (no division)

    def process(self, a, b) -> RatioOut:
        f = self.spec.ratio_frac_bits
        out, sat = [], []
        for ia, ib in zip(np.asarray(a).tolist(), np.asarray(b).tolist()):
            num, den = ia - ib, ia + ib
            if den <= 0:
                out.append(0)
                sat.append(1)
            elif abs(num) >= den:
                out.append((1 if num > 0 else -1) * ((1 << f) - 1))
                sat.append(1)
            else:
                q = (abs(num) << f) // den
                out.append(q if num >= 0 else -q)
                sat.append(0)
        return RatioOut(np.asarray(out, dtype=np.int64), np.asarray(sat, dtype=np.int64))


@dataclass(frozen=True)
class ChainOut(Record):
    out_ratio: np.ndarray
    out_sat: np.ndarray
    i_a: np.ndarray
    q_a: np.ndarray
    i_b: np.ndarray
    q_b: np.ndarray
    rot_a: np.ndarray   # the in-phase sums at the fine reference phase (the divider's operands)
    rot_b: np.ndarray


class ConditionerChain:
    """The blocks composed as the hardware composes them: the two ADC ports, one NCO phase per
    sample from the start of the record, two demodulators with one reference offset, the fine
    rotation of both, the ratio."""

    entity = "flann_cond_top"

    def __init__(self, spec: ConditionerSpec):
        self.spec = spec
        self.adc, self.demod, self.ratio = FlannCondAdc(spec), FlannCondDemod(spec), FlannCondRatio(spec)
        self.rotate = FlannCondRotate(spec)

    @property
    def latency(self) -> int:
        """Clocks from a window's last converter strobe to its ratio: port, table, product,
        rotation, divider."""
        return self.adc.latency + self.demod.latency + self.rotate.latency + self.ratio.latency

    def process(self, codes_a, codes_b, ref: Reference) -> ChainOut:
        """The ratio of every whole window, at the reference phase ``ref`` (offset and rotation);
        ``i_*``, ``q_*`` are the demodulators' sums (at the offset, before the rotation)."""
        s = self.spec
        xa, xb = self.adc.process(codes_a).out_sample, self.adc.process(codes_b).out_sample
        phases = s.phases(xa.size)
        da, db = self.demod.process(xa, phases, ref.offset), self.demod.process(xb, phases, ref.offset)
        rot = self.rotate.process(da.out_i, da.out_q, db.out_i, db.out_q, ref.tan)
        r = self.ratio.process(rot.out_a, rot.out_b)
        return ChainOut(r.out_ratio, r.out_sat, da.out_i, da.out_q, db.out_i, db.out_q, rot.out_a, rot.out_b)
