"""A waveform recording through the conditioner's twin: what the hardware will output.

The secondaries' volts become the converter's straight-binary codes (the one converter rule,
:func:`flann.numeric.fixed.nearest_codes`), the reference phase is calibrated from the
record (the phase of the difference's slope against the displacement: a table step and a
fine rotation), and the chain
(:class:`~.twin.ConditionerChain`) gives one ratio per window of whole carrier periods.

Public API: :func:`adc_codes`, :func:`calibrate_reference`, :func:`condition` -> :class:`Conditioned`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...errors import FlannError
from ...numeric.fixed import nearest_codes, signed_range
from ...recordings.waveform import Waveforms
from .spec import ConditionerSpec, Reference, identity, reference
from .twin import ConditionerChain


@dataclass(frozen=True)
class Conditioned:
    """One row per window: the ratio (fraction of one), its saturation flag, the in-phase
    difference in volts at the secondaries (``(I_A - I_B)`` scaled back), the window's mean
    displacement and whether the displacement stayed put over it."""

    ratio: np.ndarray
    sat: np.ndarray
    difference_v: np.ndarray
    displacement_mm: np.ndarray
    steady: np.ndarray
    ref: Reference
    phase_rad: float


def adc_lsb_v(bits: int, range_v: float) -> float:
    """Volts per code of a ``bits``-bit converter of +-``range_v``."""
    return 2.0 * range_v / (1 << bits)


def window_sum_v(spec: ConditionerSpec, adc_range_v: float) -> float:
    """Volts at a secondary per code of a window's in-phase sum (M/2 A |V| cos(...) in codes)."""
    return adc_lsb_v(spec.adc_bits, adc_range_v) / (spec.window / 2 * spec.amplitude)


def adc_codes(volts, bits: int, range_v: float) -> np.ndarray:
    """Straight-binary codes of a ``bits``-bit converter of +-``range_v`` (saturating)."""
    lo, hi = signed_range(bits)
    return nearest_codes(np.asarray(volts, dtype=float), adc_lsb_v(bits, range_v), lo, hi).astype(np.int64) - lo


def converted(wave: Waveforms, spec: ConditionerSpec, adc_range_v: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(codes of A, codes of B, the displacement of each sample in whole windows, one row a
    window): what the conditioner and its calibration read from a recording."""
    ca = adc_codes(wave.sec_a_v, spec.adc_bits, adc_range_v)
    cb = adc_codes(wave.sec_b_v, spec.adc_bits, adc_range_v)
    n = len(wave) // spec.window * spec.window
    return ca, cb, wave.displacement_mm[:n].reshape(-1, spec.window)


def calibrate_reference(spec: ConditionerSpec, chain_at_zero, displacement_mm=None) -> tuple[Reference, float]:
    """(reference registers, phase) from the chain's windows at offset 0.  With the windows'
    displacements: the phase of the difference A - B's slope at the null (a line through the
    complex differences at the three positions nearest it: a constant quadrature residual
    does not turn it, and the primary current's phase, which moves with the core, is taken
    where the detector's reference is trimmed); without them: the phase of A + B."""
    diff = (chain_at_zero.i_a - chain_at_zero.i_b) + 1j * (chain_at_zero.q_a - chain_at_zero.q_b)
    x = None if displacement_mm is None else np.asarray(displacement_mm, dtype=float)[: diff.size]
    if x is not None and np.unique(x).size >= 3:
        # a line through the three positions nearest the null (the smallest |A - B|)
        at = np.unique(x)
        null = at[np.argmin([np.mean(np.abs(diff[x == v])) for v in at])]
        near = np.isin(x, at[np.argsort(np.abs(at - null))[:3]])
        total = np.polyfit(x[near], diff[near], 1)[0]
        # a difference falling with x turns the slope's phase by pi: keep A + B positive
        if np.real(total * np.conj(np.sum(chain_at_zero.i_a + chain_at_zero.i_b)
                                    + 1j * np.sum(chain_at_zero.q_a + chain_at_zero.q_b))) < 0:
            total = -total
    else:
        total = (np.sum(chain_at_zero.i_a) + np.sum(chain_at_zero.i_b)
                 + 1j * (np.sum(chain_at_zero.q_a) + np.sum(chain_at_zero.q_b)))
    if total == 0:
        raise FlannError("the secondaries carry no carrier: nothing to calibrate the reference phase on")
    phase = float(np.angle(total))
    return reference(spec, phase), phase


def condition(wave: Waveforms, spec: ConditionerSpec, adc_range_v: float, ref: Reference | None = None) -> Conditioned:
    """``wave`` through the conditioner (``ref`` None: calibrated from ``wave`` itself)."""
    carrier = wave.sample_rate_hz / spec.samples_per_period
    if not math.isclose(carrier * spec.samples_per_period, wave.sample_rate_hz, rel_tol=1e-6):
        raise FlannError("the recording's sample rate does not match the conditioner's")
    if len(wave) < spec.window:
        raise FlannError(f"{wave.source}: {len(wave)} samples, fewer than one window of {spec.window}")
    ca, cb, x = converted(wave, spec, adc_range_v)
    chain = ConditionerChain(spec)
    phase = float("nan")
    if ref is None:
        ref, phase = calibrate_reference(spec, chain.process(ca, cb, identity(spec)), x.mean(axis=1))
    out = chain.process(ca, cb, ref)
    scale = window_sum_v(spec, adc_range_v)
    return Conditioned(ratio=out.out_ratio / float(1 << spec.ratio_frac_bits), sat=out.out_sat,
                       difference_v=(out.rot_a - out.rot_b) * scale, displacement_mm=x.mean(axis=1),
                       steady=np.ptp(x, axis=1) == 0, ref=ref, phase_rad=phase)
