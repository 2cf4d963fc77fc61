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
from scipy.special import fdtrc

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


# the positions the reference phase is calibrated on: |A - B| within this fraction of its largest
LINEAR_PART = 0.7
# a cubic in the quadrature part of A - B is kept when a line leaves this little chance to its gain
CUBIC_P = 1e-3


def _slope_at_null(x: np.ndarray, diff: np.ndarray) -> complex:
    """The complex slope of A - B against the displacement at the null, from the positions'
    mean differences over the stroke's linear part (the run around the null where |A - B| is
    within LINEAR_PART of its largest, and at least the three positions nearest it).  A line
    through them gives the phase where the secondaries' phase holds still; where it moves with
    the core (the primary current's phase), the quadrature part of A - B against that line
    bends as a cubic in x, and a cubic, kept only when it is significant (an F test), gives
    the slope at the null itself.  A constant quadrature residual turns neither."""
    at, inv = np.unique(x, return_inverse=True)
    count = np.bincount(inv)
    mean = (np.bincount(inv, diff.real) + 1j * np.bincount(inv, diff.imag)) / count
    size = np.abs(mean)
    centre = int(np.argmin(size))
    lo = hi = centre
    while lo > 0 and size[lo - 1] <= LINEAR_PART * size.max():
        lo -= 1
    while hi < at.size - 1 and size[hi + 1] <= LINEAR_PART * size.max():
        hi += 1
    used = np.union1d(np.arange(lo, hi + 1), np.argsort(np.abs(at - at[centre]))[:3])
    u, d = at[used] - at[centre], mean[used]
    line = np.polyfit(u, d, 1)[0]
    if used.size < 6 or line == 0:
        return complex(line)
    turn = line / abs(line)
    quad = (d / turn).imag     # the quadrature part against the line's phase: flat when the phase holds
    rss = [float(np.sum((quad - np.polyval(np.polyfit(u, quad, k), u)) ** 2)) for k in (1, 3)]
    free = used.size - 4
    if rss[1] > 0 and fdtrc(2, free, (rss[0] - rss[1]) / 2 / (rss[1] / free)) >= CUBIC_P:
        return complex(line)
    return complex(turn * (abs(line) + 1j * np.polyfit(u, quad, 3)[-2]))


def calibrate_reference(spec: ConditionerSpec, chain_at_zero, displacement_mm=None) -> tuple[Reference, float]:
    """(reference registers, phase) from the chain's windows at offset 0.  With the windows'
    displacements: the phase of the difference A - B's slope at the null (:func:`_slope_at_null`:
    the converters' rounding, a fixed error of each position when the noise is too small to
    dither it, averages over the positions of the linear part); without them: the phase of A + B."""
    diff = (chain_at_zero.i_a - chain_at_zero.i_b) + 1j * (chain_at_zero.q_a - chain_at_zero.q_b)
    x = None if displacement_mm is None else np.asarray(displacement_mm, dtype=float)[: diff.size]
    if x is not None and np.unique(x).size >= 3:
        total = _slope_at_null(x, diff)
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
