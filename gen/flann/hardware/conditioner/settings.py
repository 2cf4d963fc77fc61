"""The conditioner a model trained from waveforms sits behind: its settings, found from a
waveform recording (the calibration), kept in ``model.json`` and read back from it.

A model trained from waveforms takes the conditioner's ratio (A - B)/(A + B) as its input (in
fractions of one: the ratio code times ``2^-F``).  What the hardware needs to give that ratio
again is the carrier, the sample rate, the converters, the output rate (whole carrier periods a
window) and the reference phase; the widths follow from them (:func:`.spec.derive_conditioner`)
and are written beside them so that a reader sees them, and checked on read.

The reference phase is kept against the excitation (its phase at the record's first sample,
from ``exc_v``), as the hardware's NCO drives it; a record without ``exc_v`` gives it against
its first sample, which only a record taken from the NCO's phase zero matches.

Public API: :class:`ConditionerSettings` (``to_dict``/``from_dict``, ``spec``, ``reference_for``),
:func:`calibrate` (waveforms -> settings, conditioned windows), :func:`dwell_readings`,
:func:`of_model` (a model's settings, or None), :func:`flann_options` (the FLANN's generator
options behind the conditioner).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ...errors import FlannError, ModelFileError
from ...recordings import converter_of
from ...recordings.csvio import Recordings
from ...recordings.waveform import Waveforms, carrier_hz
from ..adc import top_bits
from ..options import GenOptions
from .condition import Conditioned, condition
from .spec import ConditionerSpec, Reference, derive_conditioner, reference

DEFAULT_OUTPUT_RATE_HZ = 500.0
# a temperature change (degC) within a window, or between two, that is a soak's step, not a drift
SOAK_STEP_C = 1.0
# the carrier found may differ from fs / N by this fraction (the FFT's interpolation, a DAQ's
# clock against the excitation's): beyond it the record is not a whole number of samples a period
CARRIER_TOLERANCE = 0.005
TABLE_BITS, SINE_BITS = 8, 12   # derive_conditioner's: one block RAM of 256 x 12


def _wrap(phase: float) -> float:
    return math.remainder(phase, 2 * math.pi)


def excitation_phase(wave: Waveforms, samples_per_period: int) -> float:
    """The excitation's phase at the record's first sample (rad; ``exc = cos(w t + phase)``),
    by a lock-in over whole carrier periods; 0 without ``exc_v``."""
    if wave.exc_v is None:
        return 0.0
    n = len(wave) // samples_per_period * samples_per_period
    k = np.arange(n)
    return float(np.angle(np.sum(wave.exc_v[:n] * np.exp(-2j * math.pi * k / samples_per_period))))


@dataclass(frozen=True)
class ConditionerSettings:
    """What the conditioner in front of a model is set to; the widths derive from these."""

    carrier_hz: float
    sample_rate_hz: float
    adc_bits: int
    adc_range_v: float
    output_rate_hz: float
    phase_rad: float                  # the secondaries' reference phase against the excitation
    against_excitation: bool = True   # False: against the record's first sample (no exc_v)
    table_bits: int = TABLE_BITS
    sine_bits: int = SINE_BITS

    @property
    def spec(self) -> ConditionerSpec:
        return derive_conditioner(adc_bits=self.adc_bits, carrier_hz=self.carrier_hz,
                                  sample_rate_hz=self.sample_rate_hz, output_rate_hz=self.output_rate_hz,
                                  table_bits=self.table_bits, sine_bits=self.sine_bits)

    @property
    def reference(self) -> Reference:
        """The phase registers of the hardware, whose NCO starts the excitation at phase 0."""
        return reference(self.spec, self.phase_rad)

    @property
    def ratio_lsb(self) -> float:
        return 2.0 ** -self.spec.ratio_frac_bits

    @property
    def ratio_converter(self) -> tuple[int, float]:
        """(bits, value per code) of the ratio code: the converter in front of the FLANN."""
        return self.spec.ratio_bits, self.ratio_lsb

    @property
    def window_rate_hz(self) -> float:
        """The ratio's rate: one a window of whole carrier periods."""
        return self.carrier_hz / self.spec.periods_per_output

    def reference_for(self, wave: Waveforms) -> Reference:
        """The registers that demodulate ``wave`` as the hardware would: the reference phase
        turned by the excitation's phase at the record's first sample (a phase calibrated
        against a record's first sample is taken as it is)."""
        turn = excitation_phase(wave, self.spec.samples_per_period) if self.against_excitation else 0.0
        return reference(self.spec, self.phase_rad + turn)

    def line(self) -> str:
        s, ref = self.spec, self.reference
        against = "the excitation" if self.against_excitation else "the record's first sample (no exc_v)"
        return (f"carrier {self.carrier_hz:g} Hz, {s.samples_per_period} samples per period at "
                f"{self.sample_rate_hz:g} Hz, {self.adc_bits}-bit +-{self.adc_range_v:g} V converters; "
                f"reference phase {math.degrees(self.phase_rad):.3f} deg against {against} (table step "
                f"{ref.offset}, tan {ref.tan}); ratio (A-B)/(A+B) at {self.window_rate_hz:g} Hz "
                f"({s.periods_per_output} periods a window), {s.ratio_bits} bits ({s.ratio_frac_bits} fraction)")

    # -- model.json ---------------------------------------------------------------------------
    def to_dict(self) -> dict:
        s, ref = self.spec, self.reference
        return {"carrier_hz": self.carrier_hz, "sample_rate_hz": self.sample_rate_hz,
                "adc_bits": self.adc_bits, "adc_range_v": self.adc_range_v,
                "output_rate_hz": self.output_rate_hz, "phase_rad": self.phase_rad,
                "against_excitation": self.against_excitation,
                "table_bits": self.table_bits, "sine_bits": self.sine_bits,
                # derived, for the reader; checked on read
                "spec": s.to_dict(), "reference": {"offset": ref.offset, "tan": ref.tan},
                "ratio_bits": s.ratio_bits, "ratio_lsb": self.ratio_lsb}

    @classmethod
    def from_dict(cls, d: dict, source: str = "model.json") -> "ConditionerSettings":
        where = f"{source}: conditioner"
        kinds = {"carrier_hz": float, "sample_rate_hz": float, "adc_bits": int, "adc_range_v": float,
                 "output_rate_hz": float, "phase_rad": float, "against_excitation": bool,
                 "table_bits": int, "sine_bits": int}
        values = {}
        for key, kind in kinds.items():
            if key not in d:
                raise ModelFileError(f"{where}: missing field {key!r}")
            v = d[key]
            ok = isinstance(v, bool) if kind is bool else (
                isinstance(v, int) and not isinstance(v, bool) if kind is int else
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v))
            if not ok:
                raise ModelFileError(f"{where}: field {key!r} must be "
                                     + {bool: "true or false", int: "an integer", float: "a number"}[kind]
                                     + f", got {v!r}")
            values[key] = float(v) if kind is float else v
        if not values["adc_range_v"] > 0:
            raise ModelFileError(f"{where}: field 'adc_range_v' must be > 0, got {values['adc_range_v']!r}")
        settings = cls(**values)
        try:
            derived = settings.to_dict()
        except FlannError as exc:
            raise ModelFileError(f"{where}: {exc}") from None
        for key in ("spec", "reference", "ratio_bits"):
            if key in d and d[key] != derived[key]:
                raise ModelFileError(f"{where}: field {key!r} differs from what its settings derive "
                                     "(edited, or written by another version of flann): retrain the model")
        return settings


def of_model(model, source: str = "model.json") -> ConditionerSettings | None:
    """The conditioner a model was trained behind, or None (a model of demodulated recordings)."""
    d = getattr(model, "conditioner", None)
    return None if d is None else ConditionerSettings.from_dict(d, source)


def flann_options(model, options: GenOptions, given=(), source: str = "model.json") -> GenOptions:
    """The generator options of the FLANN behind the conditioner: its input is the ratio code
    (the converter in front of it); ``options`` unchanged for a model of demodulated readings.
    A converter given (``given`` holds the options named on the command line) is refused."""
    settings = of_model(model, source)
    if settings is None:
        return options
    named = [n for n in ("input_bits", "input_lsb_v") if n in given]
    if named:
        raise FlannError(f"{', '.join('--' + n.replace('_', '-') for n in named)}: {source} was trained from "
                         "waveforms; its input is the conditioner's ratio, "
                         f"{settings.spec.ratio_bits} bits x 2^-{settings.spec.ratio_frac_bits}")
    bits, lsb = settings.ratio_converter
    if len(model.inputs) > 1:
        # a two-input design takes the ratio's top bits here, as a one-input one's converter plan does
        bits, lsb, _dropped = top_bits(model, bits, lsb)
    return replace(options, input_bits=bits, input_lsb_v=lsb)


def _converter(wave: Waveforms, adc_bits, adc_range_v) -> tuple[int, float]:
    """The secondaries' converter: as given, else from the samples' grid (every sample a whole
    number of one step; the fewest bits that hold them)."""
    if adc_bits is not None and adc_range_v is not None:
        return int(adc_bits), float(adc_range_v)
    grid = converter_of(np.concatenate([wave.sec_a_v, wave.sec_b_v]))
    if grid is None:
        raise FlannError(f"{wave.source}: the secondaries' samples are on no converter's grid: give "
                         "--adc-bits and --adc-range-v (the converters the conditioner will have)")
    bits, lsb = grid
    if adc_bits is not None:
        return int(adc_bits), lsb * (1 << (int(adc_bits) - 1))
    if adc_range_v is not None:
        return max(bits, round(math.log2(2 * float(adc_range_v) / lsb))), float(adc_range_v)
    return bits, lsb * (1 << (bits - 1))


def calibrate(wave: Waveforms, output_rate_hz: float = DEFAULT_OUTPUT_RATE_HZ, adc_bits: int | None = None,
              adc_range_v: float | None = None) -> tuple[ConditionerSettings, Conditioned]:
    """The conditioner's settings found from ``wave`` (the carrier from its spectrum, the
    converters from the samples' grid unless given, the reference phase calibrated on the record)
    and the record through the conditioner's twin at those settings."""
    fs = float(f"{wave.sample_rate_hz:.9g}")   # the sample times as written (nine digits)
    found = carrier_hz(wave)
    if not 0 < found < fs / 2:
        raise FlannError(f"{wave.source}: no carrier found in the waveforms")
    n = 1 << max(0, round(math.log2(fs / found)))
    if n < 8 or abs(fs / n - found) > CARRIER_TOLERANCE * found:
        raise FlannError(f"{wave.source}: carrier {found:.6g} Hz at {fs:.6g} samples/s is {fs / found:.4g} samples "
                         "a period: the conditioner needs a power of two, at least 8 (sample at 2^k times the "
                         "carrier, e.g. flann simulate --waveforms --sample-rate-hz)")
    bits, range_v = _converter(wave, adc_bits, adc_range_v)
    settings = ConditionerSettings(carrier_hz=fs / n, sample_rate_hz=fs, adc_bits=bits, adc_range_v=range_v,
                                   output_rate_hz=float(output_rate_hz), phase_rad=0.0,
                                   against_excitation=wave.exc_v is not None)
    spec = settings.spec   # refuses an output rate or a converter the conditioner cannot take
    c = condition(wave, spec, range_v)
    phase = _wrap(c.phase_rad - excitation_phase(wave, spec.samples_per_period))
    settings = replace(settings, phase_rad=phase)
    return settings, c


def condition_with(settings: ConditionerSettings, wave: Waveforms) -> Conditioned:
    """``wave`` through the conditioner at ``settings`` (a record held out from its calibration):
    its carrier and sample rate must be the settings'; the reference turned by its excitation."""
    found = carrier_hz(wave)
    fs = float(f"{wave.sample_rate_hz:.9g}")
    if abs(found - settings.carrier_hz) > CARRIER_TOLERANCE * settings.carrier_hz or \
            not math.isclose(fs, settings.sample_rate_hz, rel_tol=1e-6):
        raise FlannError(f"{wave.source}: carrier {found:.6g} Hz at {fs:.6g} samples/s, but the conditioner was "
                         f"calibrated at {settings.carrier_hz:g} Hz and {settings.sample_rate_hz:g} samples/s")
    return condition(wave, settings.spec, settings.adc_range_v, settings.reference_for(wave))


@dataclass(frozen=True)
class DwellReadings:
    """One reading per dwell: the mean ratio over its steady, unsaturated windows."""

    recordings: Recordings
    windows: int        # windows averaged, over every dwell
    left_out: int       # windows moving or saturated
    groups: tuple = ()  # the windows of each dwell (index arrays), in the readings' order


def temperature_rows(wave: Waveforms, window: int) -> np.ndarray | None:
    """The temperature of each whole window of ``window`` samples, a row each (None for a
    recording without one)."""
    t = wave.temperature_c
    return None if t is None else t[: len(t) // window * window].reshape(-1, window)


def dwell_readings(c: Conditioned, wave: Waveforms, window: int, sha256: str = "") -> DwellReadings:
    """The conditioned windows averaged per dwell (a run of steady windows at one position,
    unsaturated), as the DC path's readings: displacement_mm and voltage_v (the ratio)."""
    keep = c.steady & (c.sat == 0)
    per = None
    temps = temperature_rows(wave, window)
    if temps is not None:
        # a soak's step within a window leaves it out, and starts a new dwell; a slow drift and a
        # DAQ's noisy column (under SOAK_STEP_C a window) do neither
        temps = temps[: c.ratio.size]
        per = temps.mean(axis=1)
        keep &= np.ptp(temps, axis=1) <= SOAK_STEP_C
    if not np.any(keep):
        raise FlannError(f"{wave.source}: no window of whole carrier periods dwells at one position unsaturated: "
                         "training needs dwell at stepped positions (flann simulate --waveforms --trajectory "
                         "steps:DWELL)")
    idx = np.flatnonzero(keep)
    # a new dwell where a kept window does not follow the last, or the position changes
    new = (np.diff(idx) != 1) | (np.diff(c.displacement_mm[idx]) != 0)
    if per is not None:
        new |= np.abs(np.diff(per[idx])) > SOAK_STEP_C
    starts = np.flatnonzero(np.r_[True, new])
    groups = np.split(idx, starts[1:])
    x = np.array([c.displacement_mm[g[0]] for g in groups])
    v = np.array([np.mean(c.ratio[g]) for g in groups])
    temp = None if per is None else np.array([np.mean(per[g]) for g in groups])
    rec = Recordings(displacement_mm=x, voltage_v=v, temperature_c=temp, source=wave.source, sha256=sha256,
                     comments=wave.comments)
    return DwellReadings(rec, int(idx.size), int(c.ratio.size - idx.size), tuple(groups))


__all__ = ["ConditionerSettings", "DwellReadings", "DEFAULT_OUTPUT_RATE_HZ", "calibrate", "condition_with", "dwell_readings",
           "excitation_phase", "flann_options", "of_model", "temperature_rows"]
