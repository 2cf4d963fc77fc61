"""The conditioner chain's figures in a data sheet's terms, each judged against the AD598/AD698
(or the issue's) value, from a held-out waveform recording through the conditioner's bit-true
twin at the model's settings and the FLANN (docs/conditioner.md, "Figures").

The output is the chain's displacement: each window's ratio (the twin's, bit-true) through
``to_mm(ratio, temperature_c)`` (the FLANN, in float, so that shifts below the hardware's output
LSB still show; a two-input FLANN's at each dwell's or window's own temperature, or at the
recording's when None).
Full scale (FS) is ``fs_mm``, half the stroke, as ``linearity_pct_fs``; the output's span is
``2 fs_mm``.

* ``effective_bits``: ``log2(span / (sigma sqrt 12))``, sigma the rms of the windows' output
  about their dwell's mean (pooled over the dwells), at the output rate: one window a sample.
* ``noise_free_bits``: ``log2(span / p-p)``, p-p the largest peak-to-peak of a dwell's windows.
* ``bandwidth_hz``: -3 dB of the ratio's response to a sine of the secondaries' balance,
  synthesised at the model's carrier, sample rate, converters and reference phase, at the
  recording's own signal level (a held-out recording dwells: eval needs dwells).
* ``settling_time_s``: from each step of the recording to the end of the first window after
  which every window of the next dwell is within the AD598's linearity (0.05 % FS) of that
  dwell's mean; the worst step.  A synthesised full-scale step landing one sample into a window
  (the worst the integrate-and-dump can do) is given beside it.
* ``excitation_rejection_ppm_fs_per_pct``: the recording's secondaries scaled by +-STEP % (the
  excitation's amplitude, which both follow) before the converters: the largest systematic
  output shift over the scale change, per %.
* ``quadrature_rejection_ppm_fs``: a component of 10 % of the full-scale signal (the in-phase
  difference at the stroke's end), in quadrature with the secondaries' difference (its phase on
  this recording, found as calibration finds it), added to the secondaries in opposite signs
  (the null residual's form): the largest systematic output shift.  It passes through the
  model's reference as far as that is off the recording's phase.

* ``phase_tolerance_deg``: the largest reference-phase error (either sign) for which the output
  on the recording stays within the AD598's linearity of the true displacement, against the
  error calibration makes (the model's phase against this recording's, calibrated afresh).

The rejection figures change the secondaries before the converters (:meth:`Chain.analog`), so
the changed samples are rounded afresh; that rounding is noise on each dwell's shift, averaged
over eight dithers, and what remains the systematic shift (a quadratic in the ratio through the
dwells' ratio shifts, carried through the FLANN) leaves out and ``scatter_ppm_fs`` gives.

Public API: :class:`Figure`, :func:`chain_figures` -> ``list[Figure]``, :func:`plot_chain`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Callable

import numpy as np

from ..fileio import atomic_save_figure
from ..golden.verdict import Check
from ..hardware.conditioner.condition import adc_codes, adc_lsb_v, calibrate_reference, converted, window_sum_v
from ..hardware.conditioner.settings import ConditionerSettings, DwellReadings, temperature_rows
from ..hardware.conditioner.spec import (QUADRATURE_BUDGET, QUADRATURE_FRACTION, Reference, identity, reference,
                                         reference_phase)
from ..hardware.conditioner.twin import ConditionerChain
from ..recordings.waveform import Waveforms

# the references (AD598/AD698 data sheets, and the resolution target)
AD598_LINEARITY_PCT_FS = 0.05       # AD598 linearity, max
AD598_BANDWIDTH_HZ = 250.0          # AD598 bandwidth with its filter capacitor, typical
AD698_EXCITATION_PPM_FS_PER_PCT = 10.0   # a 10 % excitation change moves the output <= 100 ppm FS
QUADRATURE_PPM_FS = 1e6 * QUADRATURE_BUDGET   # the shift a 10 % FS quadrature component may cause
TARGET_BITS = 16.0                  # effective bits at a 250 Hz bandwidth with 12-bit converters
AD2S93_BITS = 14.0                  # the LVDT-to-digital converter's resolution
EXCITATION_STEP_PCT = 10.0          # the scale change, less when the converters lack the headroom
SQRT12 = math.sqrt(12.0)
DITHER_SEEDS = range(1, 9)   # the changed samples' rounding, averaged over eight dithers


@dataclass(frozen=True)
class Figure:
    """One figure: its value (None: not computable, ``reason`` says why), what it is judged
    against (``limit``: at most when ``at_most``, else at least) and where it comes from."""

    name: str
    value: float | None
    unit: str
    reference: str
    limit: float | None
    at_most: bool
    source: str
    reason: str = ""
    detail: dict = field(default_factory=dict)
    remedy: str = ""
    unmet: str = ""   # a condition of the reference the measurement does not meet: no pass

    @property
    def ok(self) -> bool | None:
        if self.value is None or self.limit is None:
            return None
        if self.unmet:
            return False
        return self.value <= self.limit if self.at_most else self.value >= self.limit

    def to_json(self) -> dict:
        return {"value": self.value, "unit": self.unit, "ok": self.ok, "reference": self.reference,
                "reference_value": self.limit, "at_most": self.at_most, "source": self.source,
                "reason": self.reason or None, "unmet": self.unmet or None, **self.detail}

    def text(self) -> str:
        if self.value is None:
            return f"{self.name} not computable: {self.reason}"
        met = self.value <= self.limit if self.at_most else self.value >= self.limit
        word = ("within" if met else "beyond") if self.at_most else ("at least" if met else "below")
        return (f"{self.name} {self.value:.4g} {self.unit}: {word} {self.limit:.4g} {self.unit}, the {self.reference}"
                + (f"; {self.unmet}" if self.unmet else ""))

    def check(self) -> Check:
        return Check(self.name, self.ok, self.text(), "" if self.ok is not False else self.remedy)


def window_temperature_c(wave: Waveforms, window: int) -> np.ndarray | None:
    """Each whole window's mean temperature (None for a recording without one)."""
    rows = temperature_rows(wave, window)
    return None if rows is None else rows.mean(axis=1)


@dataclass(frozen=True)
class Chain:
    """The recording through a conditioner twin and the FLANN: what each figure re-runs."""

    settings: ConditionerSettings
    wave: Waveforms
    dwells: DwellReadings
    to_mm: Callable[..., np.ndarray]
    fs_mm: float
    twin: ConditionerChain

    @property
    def spec(self):
        return self.settings.spec

    @cached_property
    def ref(self) -> Reference:
        return self.settings.reference_for(self.wave)

    @cached_property
    def signal_phase(self) -> float:
        """The phase of the secondaries' difference on this recording (rad, the record's own
        frame), as calibration finds it (the slope of A - B at the null), by the plain twin."""
        s = self.spec
        ca, cb, x = converted(self.wave, s, self.settings.adc_range_v)
        return calibrate_reference(s, ConditionerChain(s).process(ca, cb, identity(s)), x.mean(axis=1))[1]

    @cached_property
    def calibration_error_rad(self) -> float:
        """The model's reference against this recording's own phase: the calibration's error."""
        return math.remainder(reference_phase(self.spec, self.ref) - self.signal_phase, 2 * math.pi)

    def ratio(self, a_v, b_v, ref: Reference | None = None):
        """(ratio per window, the twin's record) of the secondaries' volts ``a_v``, ``b_v``."""
        s = self.spec
        ca = adc_codes(a_v, s.adc_bits, self.settings.adc_range_v)
        cb = adc_codes(b_v, s.adc_bits, self.settings.adc_range_v)
        out = self.twin.process(ca, cb, self.ref if ref is None else ref)
        return out.out_ratio / float(1 << s.ratio_frac_bits), out

    def analog(self, seed: int) -> tuple[np.ndarray, np.ndarray]:
        """The secondaries as the converters saw them before rounding, as far as the recording
        tells: each sample plus a uniform dither of one LSB (``seed``).  Scaling or adding to the
        rounded samples themselves would round a grid again, whose error repeats with the code
        (a gain error of its own); these round back to the recording's samples."""
        lsb = adc_lsb_v(self.spec.adc_bits, self.settings.adc_range_v)
        rng = np.random.default_rng(seed)
        half = 0.5 * lsb * (1 - 1e-9)
        return (self.wave.sec_a_v + rng.uniform(-half, half, len(self.wave)),
                self.wave.sec_b_v + rng.uniform(-half, half, len(self.wave)))

    def per_dwell(self, ratio) -> np.ndarray:
        """Each dwell's mean ratio, as eval's readings."""
        return np.array([np.mean(ratio[g]) for g in self.dwells.groups])

    def per_dwell_mm(self, ratio) -> np.ndarray:
        """The output per dwell: its windows' mean ratio through the FLANN."""
        return self.dwell_mm(self.per_dwell(ratio))

    def dwell_mm(self, dwell_ratio) -> np.ndarray:
        """A ratio per dwell through the FLANN, at each dwell's temperature."""
        return self.to_mm(dwell_ratio, self.dwells.recordings.temperature_c)

    @cached_property
    def window_temperature_c(self) -> np.ndarray | None:
        return window_temperature_c(self.wave, self.spec.window)

    def volts_per_code_sum(self) -> float:
        """A window's in-phase sum (codes) back to the amplitude in volts at a secondary."""
        return window_sum_v(self.spec, self.settings.adc_range_v)

    def carrier(self, n: int, phase: float | None = None) -> np.ndarray:
        """The carrier's phase at each of ``n`` samples for a signal that demodulates at ``phase``
        (default: the reference's, the table's angle plus the rotation): the table's lag taken off."""
        start = reference_phase(self.spec, self.ref) if phase is None else phase
        return 2 * math.pi * np.arange(n) / self.spec.samples_per_period + start - self.spec.table_lag_rad


def _ppm(chain: Chain, shift_mm) -> float:
    return 1e6 * float(np.max(np.abs(shift_mm))) / chain.fs_mm


def systematic_ppm(chain: Chain, base_ratio, moved_ratio) -> tuple[float, float, float]:
    """(the largest systematic output shift, the worst dwell's, the dwells' scatter about the
    systematic one), ppm FS.  Each dwell's ratio shift holds the converters' rounding of the
    changed samples too, noise that a figure of the chain should not count: the systematic shift
    is a quadratic in the ratio through the dwells' ratio shifts (a gain error moves the ratio in
    proportion, a quadrature leak by a constant), carried to the output through the FLANN."""
    r = np.asarray(base_ratio, dtype=float)
    shift = np.asarray(moved_ratio, dtype=float) - r
    base_mm = chain.dwell_mm(r)
    worst = _ppm(chain, chain.dwell_mm(r + shift) - base_mm)
    if np.unique(r).size < 4:
        return worst, worst, 0.0
    fit = np.polyval(np.polyfit(r, shift, 2), r)
    out = chain.dwell_mm(r + fit) - base_mm
    scatter = chain.dwell_mm(r + shift) - chain.dwell_mm(r + fit)
    return _ppm(chain, out), worst, 1e6 * float(np.std(scatter)) / chain.fs_mm


def pooled_rms(outs) -> float:
    """The rms of each dwell's outputs about the dwell's own mean, pooled over the dwells."""
    resid = np.concatenate([o - o.mean() for o in outs])
    return math.sqrt(float(np.sum(resid ** 2)) / sum(o.size - 1 for o in outs))


def hardware_bits(window_mm, groups, span_mm: float, lsb_mm: float) -> float | None:
    """Effective bits of a design's output words (one a window, in mm): their noise about each
    dwell's mean with the output word's own rounding (an ideal quantiser's LSB / sqrt 12) beside
    it, so that a word too coarse to move within a dwell counts its LSB, not zero."""
    outs = [np.asarray(window_mm, dtype=float)[g] for g in groups if g.size >= 2]
    if not outs:
        return None
    sigma = math.sqrt(pooled_rms(outs) ** 2 + lsb_mm ** 2 / 12)
    return math.log2(span_mm / (sigma * SQRT12))


def noise_figures(chain: Chain, ratio, bandwidth: Figure) -> list[Figure]:
    span = 2 * chain.fs_mm
    groups = [g for g in chain.dwells.groups if g.size >= 2]
    src = "the held-out recording's dwells, one output a window"
    ref16 = f"issue's target at a {AD598_BANDWIDTH_HZ:g} Hz bandwidth with 12-bit converters"
    if not groups:
        reason = "no dwell holds two windows (dwell longer than two windows of the output rate)"
        return [Figure("effective_bits", None, "bits", ref16, TARGET_BITS, False, src, reason),
                Figure("noise_free_bits", None, "bits", "AD2S93's resolution", AD2S93_BITS, False, src, reason)]
    temps = chain.window_temperature_c
    outs = [chain.to_mm(ratio[g], None if temps is None else temps[g]) for g in groups]
    sigma = pooled_rms(outs)
    ptp = max(float(np.ptp(o)) for o in outs)
    bw = bandwidth.value
    detail = {"rms_mm": sigma, "span_mm": span, "bandwidth_hz": bw, "dwells": len(groups)}
    quiet = "the output does not move within a dwell (no noise reaches it: its resolution is the ratio's LSB)"
    enob = Figure("effective_bits", math.log2(span / (sigma * SQRT12)) if sigma > 0 else None, "bits", ref16,
                  TARGET_BITS, False, src, "" if sigma > 0 else quiet, detail,
                  "a higher sample rate (more samples a window), converters' range matched to the secondaries' "
                  "peak, or quieter converters (docs/conditioner.md, 'Effective bits')")
    if enob.value is not None and bw is not None and bw < AD598_BANDWIDTH_HZ:
        # integrating longer than the reference's bandwidth allows flatters the figure
        enob = replace(enob, unmet=f"measured at a {bw:.4g} Hz bandwidth, narrower than {AD598_BANDWIDTH_HZ:g} Hz",
                       remedy="train with a higher --output-rate-hz (the bandwidth is 0.443 x the output rate)")
    nfb = Figure("noise_free_bits", math.log2(span / ptp) if ptp > 0 else None, "bits", "AD2S93's resolution",
                 AD2S93_BITS, False, src, "" if ptp > 0 else quiet, {"peak_to_peak_mm": ptp},
                 "as for effective_bits")
    return [enob, nfb]


def _stimulus_level(chain: Chain, ratio, out) -> tuple[float, float]:
    """(A + B amplitude in volts, the ratio's largest magnitude) of the recording."""
    s = (out.rot_a + out.rot_b) * chain.volts_per_code_sum()
    keep = chain.dwells.groups
    idx = np.concatenate(keep) if keep else np.arange(ratio.size)
    return float(np.median(s[idx])), float(np.max(np.abs(ratio[idx])))


def _synth(chain: Chain, total: float, r) -> tuple[np.ndarray, np.ndarray]:
    """Secondaries in phase with the reference whose balance ``(A - B)/(A + B)`` is ``r``
    (per sample), their sum ``total`` volts."""
    c = np.cos(chain.carrier(r.size))
    return 0.5 * total * (1 + r) * c, 0.5 * total * (1 - r) * c


def bandwidth_figure(chain: Chain, total: float, r0: float) -> Figure:
    s, settings = chain.spec, chain.settings
    fs, rate = settings.sample_rate_hz, settings.window_rate_hz
    src = (f"synthesised through the twin at the model's settings (carrier {settings.carrier_hz:g} Hz, "
           f"{fs:g} samples/s, window {s.window}), the recording's level: a sine of the balance, "
           f"amplitude {r0:.3g}")

    if not (r0 > 0 and total > 0):
        return Figure("bandwidth_hz", None, "Hz", "AD598's bandwidth (typical)", AD598_BANDWIDTH_HZ, False, src,
                      "the recording's secondaries carry no balance to synthesise a stimulus at (no signal, or "
                      "every dwell at the null)")

    def gain(f: float) -> float:
        windows = max(32, math.ceil(4 * rate / f))
        n = windows * s.window
        t = np.arange(n) / fs
        ratio, _ = chain.ratio(*_synth(chain, total, r0 * np.sin(2 * math.pi * f * t)))
        tc = (np.arange(ratio.size) + 0.5) * s.window / fs
        basis = np.column_stack([np.ones_like(tc), np.sin(2 * math.pi * f * tc), np.cos(2 * math.pi * f * tc)])
        c = np.linalg.lstsq(basis, ratio, rcond=None)[0]
        return math.hypot(c[1], c[2]) / r0

    dc = gain(rate / 64)
    half = 1 / math.sqrt(2)
    lo, hi = rate / 64, rate / 2
    if gain(hi) / dc > half:
        return Figure("bandwidth_hz", None, "Hz", "AD598's bandwidth (typical)", AD598_BANDWIDTH_HZ, False, src,
                      f"the response is above -3 dB up to half the output rate ({hi:g} Hz)")
    for _ in range(14):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if gain(mid) / dc > half else (lo, mid)
    return Figure("bandwidth_hz", 0.5 * (lo + hi), "Hz", "AD598's bandwidth (typical)", AD598_BANDWIDTH_HZ, False,
                  src, detail={"output_rate_hz": rate},
                  remedy="train with a higher --output-rate-hz (the bandwidth is 0.443 x the output rate)")


def _settled_after(out_mm, start: int, stop: int, final: float, band: float) -> int | None:
    """The first window from ``start`` after which every window up to ``stop`` is within band."""
    bad = np.flatnonzero(np.abs(out_mm[start:stop] - final) > band)
    return start if bad.size == 0 else (start + int(bad[-1]) + 1 if bad[-1] + 1 < stop - start else None)


def settling_figure(chain: Chain, ratio, total: float, r0: float) -> Figure:
    s, fs = chain.spec, chain.settings.sample_rate_hz
    band = AD598_LINEARITY_PCT_FS / 100 * chain.fs_mm
    span = 2 * chain.fs_mm
    one_pole = math.log(span / band) / (2 * math.pi * AD598_BANDWIDTH_HZ)
    reference = f"AD598's {AD598_BANDWIDTH_HZ:g} Hz one-pole filter settling a full-scale step to 0.05 % FS"
    # the worst case: a full-scale step one sample into a window, synthesised
    worst = None
    if r0 > 0 and total > 0:
        k = 4 * s.window + 1
        r = np.where(np.arange(8 * s.window) < k, -r0, r0)
        syn_ratio, _ = chain.ratio(*_synth(chain, total, r))
        syn_mm = chain.to_mm(syn_ratio)
        at = _settled_after(syn_mm, 4, syn_ratio.size, float(syn_mm[-1]), band)
        worst = None if at is None else ((at + 1) * s.window - k) / fs
    # the recording's steps
    x = chain.wave.displacement_mm
    steps = np.flatnonzero(np.diff(x) != 0) + 1
    out_mm = chain.to_mm(ratio, chain.window_temperature_c)
    found, unsettled = [], 0
    for g in chain.dwells.groups:
        first = int(g[0]) * s.window
        before = steps[steps <= first]
        if before.size == 0 or (found and before[-1] == found[-1][0]):
            continue
        step = int(before[-1])   # the last step before the dwell: the position it holds
        start = step // s.window
        final = float(np.mean(out_mm[g]))
        at_w = _settled_after(out_mm, start, int(g[-1]) + 1, final, band)
        if at_w is None:
            unsettled += 1
        else:
            found.append((step, ((at_w + 1) * s.window - step) / fs))
    detail = {"band_mm": band, "worst_case_s": worst, "reference_s": one_pole}
    remedy = "train with a higher --output-rate-hz (a step settles within two windows)"
    if found:
        value = max(t for _, t in found)
        return Figure("settling_time_s", value, "s", reference, one_pole, True,
                      f"the held-out recording's {len(found)} steps, within {band:.3g} mm (0.05 % FS)",
                      detail={**detail, "unsettled_steps": unsettled}, remedy=remedy,
                      unmet=f"{unsettled} more step(s) did not settle within their dwell" if unsettled else "")
    if unsettled:
        return Figure("settling_time_s", None, "s", reference, one_pole, True, "the held-out recording's steps",
                      f"none of its {unsettled} steps settles within its dwell (dwell longer, or a higher "
                      "--output-rate-hz)", detail=detail)
    if worst is None:
        return Figure("settling_time_s", None, "s", reference, one_pole, True, "synthesised",
                      "the recording holds no step, and a synthesised step does not settle within the band "
                      "(or the recording carries no signal to synthesise one at)", detail=detail)
    return Figure("settling_time_s", worst, "s", reference, one_pole, True,
                  "synthesised through the twin at the model's settings: a full-scale step one sample into a "
                  "window (the recording holds no step)", detail=detail, remedy=remedy)


def excitation_figure(chain: Chain) -> Figure:
    w, rng = chain.wave, chain.settings.adc_range_v
    peak = max(float(np.max(np.abs(w.sec_a_v))), float(np.max(np.abs(w.sec_b_v))))
    headroom = 100 * (rng / peak - 1) if peak > 0 else EXCITATION_STEP_PCT
    step = max(1.0, min(EXCITATION_STEP_PCT, math.floor(headroom * 10) / 10))
    ups, downs = [], []
    for seed in DITHER_SEEDS:
        a, b = chain.analog(seed)
        ups.append(chain.per_dwell(chain.ratio(a * (1 + step / 100), b * (1 + step / 100))[0]))
        downs.append(chain.per_dwell(chain.ratio(a * (1 - step / 100), b * (1 - step / 100))[0]))
    shift, worst, scatter = systematic_ppm(chain, np.mean(downs, axis=0), np.mean(ups, axis=0))
    value = shift / (2 * step)
    note = "" if step == EXCITATION_STEP_PCT else f" (the converters' headroom: {headroom:.3g} %)"
    return Figure("excitation_rejection_ppm_fs_per_pct", value, "ppm FS/%",
                  "AD698-class limit (10 % of excitation moves the output <= 100 ppm FS)",
                  AD698_EXCITATION_PPM_FS_PER_PCT, True,
                  f"the held-out recording with its secondaries scaled by +-{step:g} %{note}, through the twin",
                  detail={"scale_pct": step, "shift_ppm_fs": shift, "worst_dwell_ppm_fs": worst,
                          "scatter_ppm_fs": scatter},
                  remedy="the ratio (A-B)/(A+B) cancels the excitation: check the divider and the converters' range")


def full_scale_signal_v(chain: Chain, out) -> float:
    """The in-phase difference A - B (volts) at the stroke's end: the largest of a dwell's."""
    diff = (out.rot_a - out.rot_b) * chain.volts_per_code_sum()
    return max(abs(float(np.mean(diff[g]))) for g in chain.dwells.groups)


def quadrature_figure(chain: Chain, out) -> Figure:
    w = chain.wave
    q = QUADRATURE_FRACTION * full_scale_signal_v(chain, out)
    if not q > 0:
        return Figure("quadrature_rejection_ppm_fs", None, "ppm FS", f"{QUADRATURE_FRACTION:.0%} FS quadrature budget",
                      QUADRATURE_PPM_FS, True, "the held-out recording",
                      "its secondaries' difference is zero at every dwell: no full-scale signal to take 10 % of")
    error = chain.calibration_error_rad
    # in quadrature with the signal (what the sensor's null residual is), not with the reference:
    # the reference's error against it is what lets the quadrature through
    quad = 0.5 * q * np.cos(chain.carrier(len(w), chain.signal_phase) + math.pi / 2)
    base, moved = [], {1: [], -1: []}
    for seed in DITHER_SEEDS:
        a, b = chain.analog(seed)
        base.append(chain.per_dwell(chain.ratio(a, b)[0]))
        for sign, runs in moved.items():
            runs.append(chain.per_dwell(chain.ratio(a + sign * quad, b - sign * quad)[0]))
    fits = [systematic_ppm(chain, np.mean(base, axis=0), np.mean(runs, axis=0)) for runs in moved.values()]
    value = max(f[0] for f in fits)
    return Figure("quadrature_rejection_ppm_fs", value, "ppm FS",
                  f"{QUADRATURE_FRACTION:.0%} FS quadrature budget", QUADRATURE_PPM_FS, True,
                  f"the held-out recording with {q * 1e3:.4g} mV peak ({QUADRATURE_FRACTION:.0%} of the full-scale "
                  "difference) in quadrature with its difference A - B (its phase calibrated afresh; the model's "
                  f"reference {math.degrees(error):+.3f} deg from it), +- on the secondaries, through the twin",
                  detail={"quadrature_v": q, "calibration_error_deg": math.degrees(error),
                          "worst_dwell_ppm_fs": max(f[1] for f in fits),
                          "scatter_ppm_fs": max(f[2] for f in fits)},
                  remedy="recalibrate the reference phase (flann train on a recording of the sensor as wired)")


def phase_tolerance_figure(chain: Chain, base_mm) -> Figure:
    s = chain.spec
    x = chain.dwells.recordings.displacement_mm
    limit_mm = AD598_LINEARITY_PCT_FS / 100 * chain.fs_mm
    step = math.degrees(2.0 ** -(s.rotation_bits + 1))
    error = abs(math.degrees(chain.calibration_error_rad))
    resolution = max(step, error)
    src = "the held-out recording through the twin with its reference phase turned, the FLANN unchanged"
    reference_name = ("calibration's error on this recording (its phase calibrated afresh against the model's; "
                      "at least the registers' step)")
    theta = reference_phase(s, chain.ref)

    def worst(err_deg: float) -> float:
        mm = chain.per_dwell_mm(chain.ratio(chain.wave.sec_a_v, chain.wave.sec_b_v,
                                            reference(s, theta + math.radians(err_deg)))[0])
        return float(np.max(np.abs(mm - x)))

    if float(np.max(np.abs(base_mm - x))) > limit_mm:
        return Figure("phase_tolerance_deg", None, "deg", reference_name, resolution, False, src,
                      "the chain misses the AD598's linearity at the calibrated phase already")

    def holds(e: float) -> bool:
        return worst(e) <= limit_mm and worst(-e) <= limit_mm

    lo, hi = 0.0, 0.01
    while hi < 90 and holds(hi):
        lo, hi = hi, 2 * hi
    if hi >= 90:
        # secondaries in phase with each other: the error's cos is common and cancels in the ratio
        return Figure("phase_tolerance_deg", 90.0, "deg", reference_name, resolution, False,
                      src + " (holds to the search's 90 deg: the secondaries are in phase)",
                      detail={"linearity_limit_mm": limit_mm, "capped": True, "calibration_error_deg": error,
                              "register_step_deg": step})
    for _ in range(12):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if holds(mid) else (lo, mid)
    return Figure("phase_tolerance_deg", lo, "deg", reference_name, resolution, False, src,
                  detail={"linearity_limit_mm": limit_mm, "calibration_error_deg": error, "register_step_deg": step},
                  remedy="a finer rotation (more rotation bits) or a sensor with less quadrature")


def chain_figures(settings: ConditionerSettings, wave: Waveforms, dwells: DwellReadings,
                  to_mm: Callable[..., np.ndarray], fs_mm: float,
                  twin: ConditionerChain | None = None) -> list[Figure]:
    """Every figure of the module docstring, in its order after linearity."""
    chain = Chain(settings, wave, dwells, to_mm, float(fs_mm), twin or ConditionerChain(settings.spec))
    ratio, out = chain.ratio(wave.sec_a_v, wave.sec_b_v)
    base_mm = chain.per_dwell_mm(ratio)
    total, r0 = _stimulus_level(chain, ratio, out)
    bandwidth = bandwidth_figure(chain, total, r0)
    return [*noise_figures(chain, ratio, bandwidth), bandwidth, settling_figure(chain, ratio, total, r0),
            excitation_figure(chain), quadrature_figure(chain, out),
            phase_tolerance_figure(chain, base_mm)]


def plot_chain(path, settings: ConditionerSettings, wave: Waveforms, conditioned, dwells: DwellReadings, to_mm, fs_mm: float,
               hardware_mm=None) -> None:
    """The waveforms (three carrier periods mid-record, and the whole record's envelope), the
    demodulated ratio per window, and the displacement error in % FS per window (the float
    chain) and per dwell (float, and the hardware's when given), with the AD598's band (PNG)."""
    import matplotlib  # lazy: plotting is optional and slow to import

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fs, window, period = settings.sample_rate_hz, settings.spec.window, settings.spec.samples_per_period
    n = conditioned.ratio.size * window
    t_w = (np.arange(conditioned.ratio.size) + 0.5) * window / fs
    channels = [(c, getattr(wave, c)) for c in ("exc_v", "sec_a_v", "sec_b_v") if getattr(wave, c) is not None]
    fig, ax = plt.subplots(4, 1, figsize=(8, 9.5), gridspec_kw={"height_ratios": [1, 1, 1, 1.3]})
    mid = (wave.time_s.size // 2) // period * period
    zoom = slice(mid, min(wave.time_s.size, mid + 3 * period))
    for c, v in channels:
        ax[0].plot(1e3 * wave.time_s[zoom], v[zoom], lw=1, label=c)
    ax[0].set_xlabel("time (ms)")
    ax[0].set_ylabel("V")
    ax[0].set_title(f"{wave.source}: three carrier periods at {wave.displacement_mm[mid]:.3g} mm")
    ax[0].legend(loc="upper right", fontsize=7)
    for c, v in channels:
        rows = v[:n].reshape(-1, window)
        ax[1].fill_between(t_w, rows.min(axis=1), rows.max(axis=1), alpha=0.35, lw=0, label=f"{c} (envelope)")
    ax[1].set_ylabel("V")
    ax[1].legend(loc="upper right", fontsize=7)
    ax[2].plot(t_w, conditioned.ratio, ".", ms=2, color="C0", label="(A-B)/(A+B), one a window (the twin)")
    ax[2].set_ylabel("ratio")
    ax[2].legend(loc="upper left", fontsize=7)
    err = 100 * (to_mm(conditioned.ratio, window_temperature_c(wave, window)) - conditioned.displacement_mm) / fs_mm
    steady = conditioned.steady & (conditioned.sat == 0)
    ax[3].plot(t_w[steady], err[steady], ".", ms=2, color="0.6", label="float chain, each window")
    t_d = np.array([t_w[g].mean() for g in dwells.groups])
    x = dwells.recordings.displacement_mm
    ax[3].plot(t_d, 100 * (to_mm(dwells.recordings.voltage_v, dwells.recordings.temperature_c) - x) / fs_mm, "o",
               ms=4, color="C0",
               label="float chain, dwell mean")
    if hardware_mm is not None and len(hardware_mm) == t_d.size:
        ax[3].plot(t_d, 100 * (np.asarray(hardware_mm) - x) / fs_mm, "x", ms=5, color="C3",
                   label="hardware (the FLANN's twin), dwell mean")
    ax[3].axhspan(-AD598_LINEARITY_PCT_FS, AD598_LINEARITY_PCT_FS, color="C2", alpha=0.15, lw=0,
                  label=f"AD598 linearity +-{AD598_LINEARITY_PCT_FS:g} % FS")
    ax[3].set_ylabel("displacement error (% FS)")
    ax[3].set_xlabel("time (s)")
    ax[3].legend(loc="upper right", fontsize=7)
    for a in ax[1:3]:
        a.sharex(ax[3])
    fig.tight_layout()
    try:
        atomic_save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)


__all__ = ["AD598_LINEARITY_PCT_FS", "Figure", "chain_figures", "plot_chain"]
