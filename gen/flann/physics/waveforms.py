"""Sampled waveforms of the excitation and both secondaries, from the simulator's magnetics.

Each sample is quasi-static: the core moves slowly against the carrier, so at each sample the
position, temperature and drive give the secondaries' complex e.m.f.s (magnitude and phase,
from the same magnetics, primary circuit and effects as the demodulated output of
:mod:`flann.physics.simulate`), and the sample is their real part at the carrier's phase:

    exc(t)   = E a(t) [cos(w t) + h cos(3 w t)]
    sec_A(t) = Re(V_A(x, T) a(t) e^{j w t}) + h Re(V_A3(x, T) a(t) e^{j 3 w t}) + q_A + noise
    sec_B(t) = likewise with V_B

``E`` is the sensor's excitation peak, ``a(t)`` the excitation-amplitude drift (linear over
the run), ``h`` the excitation's third-harmonic fraction, carried through the transformer at
three times the carrier (``V_A3``: the same windings at 3 w).  The ``quadrature_null``
effect's output-referred residual becomes half its size in quadrature with the detector's
reference on each secondary, in opposite signs (the null residual of the series-opposed
pair).  White Gaussian noise (``noise_v`` rms, independent per channel) is added before the
converter, which saturates at its range and rounds to its LSB.  The output-stage effects
(null_offset, adc_clipping) belong to an analog demodulator and are not in the waveforms.

Public API:

* :class:`WaveformSettings`, :func:`parse_trajectory` ("steps:DWELL_S", "ramp:DURATION_S",
  "sine:FREQ_HZ:DURATION_S") -> :class:`Trajectory`, :func:`trajectory_positions`.
* :func:`simulate_waveforms` (sensor, settings, trajectory, ...) -> :class:`flann.recordings.
  waveform.Waveforms`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import FlannError
from ..recordings.csvio import MAX_ROWS
from ..recordings.waveform import Waveforms
from .lvdt import reference_phase_rad
from .sensor import Sensor
from .simulate import adc_convert, parse_temperature_profile, sweep_positions, transformer_secondaries, \
    transformer_signal

# default sample rate: a whole number of samples per carrier period, enough for the third
# harmonic and for a demodulator that integrates over whole periods
SAMPLES_PER_CARRIER = 32
ADC_RANGES_V = (0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0)   # a DAQ's input ranges


@dataclass(frozen=True)
class WaveformSettings:
    """The converter and the carrier (None: the sensor's carrier, SAMPLES_PER_CARRIER samples
    per period, the smallest of ADC_RANGES_V above the secondaries' peak)."""

    carrier_hz: float | None = None
    sample_rate_hz: float | None = None
    adc_bits: int = 12
    adc_range_v: float | None = None
    noise_v: float = 0.0
    excitation_drift_pct: float = 0.0
    harmonic_pct: float = 0.0
    seed: int = 0

    def check(self) -> None:
        for name in ("carrier_hz", "sample_rate_hz", "adc_range_v"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and v > 0):
                raise FlannError(f"--{name.replace('_', '-')} {v:g}: must be > 0")
        if not 2 <= self.adc_bits <= 32:
            raise FlannError(f"--adc-bits {self.adc_bits}: must be 2..32")
        if not (math.isfinite(self.noise_v) and self.noise_v >= 0):
            raise FlannError(f"--noise-v {self.noise_v:g}: must be >= 0")
        if not (math.isfinite(self.excitation_drift_pct) and abs(self.excitation_drift_pct) < 100):
            raise FlannError(f"--excitation-drift-pct {self.excitation_drift_pct:g}: must be within +-100")
        if not (math.isfinite(self.harmonic_pct) and 0 <= self.harmonic_pct < 100):
            raise FlannError(f"--harmonic-pct {self.harmonic_pct:g}: must be 0..100")


@dataclass(frozen=True)
class Trajectory:
    """``steps``: dwell ``dwell_s`` at each position of the stepped sweeps; ``ramp``: from the
    start of travel to its end in ``duration_s``; ``sine``: about the travel's centre with
    half its span, at ``frequency_hz`` for ``duration_s``."""

    kind: str
    duration_s: float = 0.0
    dwell_s: float = 0.0
    frequency_hz: float = 0.0


_TRAJECTORY_HELP = "steps:DWELL_S, ramp:DURATION_S or sine:FREQ_HZ:DURATION_S"


def parse_trajectory(text: str) -> Trajectory:
    kind, _, rest = str(text).strip().partition(":")
    try:
        nums = [float(v) for v in rest.split(":")] if rest else []
    except ValueError:
        raise FlannError(f"--trajectory {text!r}: expected {_TRAJECTORY_HELP} (numbers)") from None
    want = {"steps": 1, "ramp": 1, "sine": 2}
    if kind not in want or len(nums) != want[kind] or not all(math.isfinite(v) and v > 0 for v in nums):
        raise FlannError(f"--trajectory {text!r}: expected {_TRAJECTORY_HELP} (positive numbers)")
    if kind == "steps":
        return Trajectory("steps", dwell_s=nums[0])
    if kind == "ramp":
        return Trajectory("ramp", duration_s=nums[0])
    return Trajectory("sine", frequency_hz=nums[0], duration_s=nums[1])


def trajectory_positions(traj: Trajectory, t: np.ndarray, travel_mm: tuple[float, float],
                         step_mm: float, sweeps: int) -> tuple[np.ndarray, np.ndarray]:
    """Displacement (mm) and direction of travel (+1, -1, 0 at rest) at the sample times."""
    lo, hi = travel_mm
    if traj.kind == "steps":
        pos, dirs = sweep_positions(travel_mm, step_mm, sweeps)
        k = np.minimum((t / traj.dwell_s).astype(np.int64), pos.size - 1)
        return pos[k], dirs[k]
    if traj.kind == "ramp":
        x = lo + (hi - lo) * t / traj.duration_s
        return x, np.ones_like(t)
    phase = 2 * math.pi * traj.frequency_hz * t
    x = 0.5 * (lo + hi) + 0.5 * (hi - lo) * np.sin(phase)
    return x, np.sign(np.cos(phase))


def duration_s(traj: Trajectory, travel_mm: tuple[float, float], step_mm: float, sweeps: int) -> float:
    if traj.kind == "steps":
        return traj.dwell_s * sweep_positions(travel_mm, step_mm, sweeps)[0].size
    return traj.duration_s


def _phasors(s: Sensor, sig) -> tuple[np.ndarray, np.ndarray]:
    """Complex peak e.m.f.s of secondaries A and B at unit drive."""
    sec = transformer_secondaries(s, sig)
    common = 1j * sec.omega_rad_s * sec.i_p * sec.loop_gain
    return common * sec.m1_h, common * sec.m2_h


def simulate_waveforms(s: Sensor, settings: WaveformSettings, trajectory: Trajectory,
                       travel_mm: tuple[float, float] | None = None, step_mm: float = 1.0,
                       sweeps: int = 1, temperature_profile=None, temperatures=None) -> Waveforms:
    """Waveforms of ``s`` along ``trajectory`` (see the module docstring), reproducible from
    ``settings.seed``.  ``temperatures``: a calibration at several temperatures, the trajectory
    once at each in turn (the sensor soaked at it), one record whose excitation runs on across
    them; it replaces ``temperature_profile``."""
    settings.check()
    if settings.carrier_hz is not None:
        s = s.replace(excitation_frequency_hz=float(settings.carrier_hz))
    carrier = s.excitation_frequency_hz
    fs = settings.sample_rate_hz or SAMPLES_PER_CARRIER * carrier
    highest = carrier * (3 if settings.harmonic_pct > 0 else 1)
    if fs <= 2 * highest:
        raise FlannError(f"--sample-rate-hz {fs:g}: must be above twice the highest frequency in the "
                         f"waveforms ({highest:g} Hz)")
    travel = travel_mm if travel_mm is not None else (-s.stroke_mm, s.stroke_mm)
    soaks = tuple(float(t) for t in temperatures) if temperatures else ()
    total = duration_s(trajectory, travel, step_mm, sweeps)
    per = int(math.floor(total * fs + 1e-9))   # the samples of one pass of the trajectory
    n = per * max(1, len(soaks))
    if n > MAX_ROWS:
        raise FlannError(f"{n / fs:g} s at {fs:g} samples/s is {n:,} samples, more than a recording holds "
                         f"({MAX_ROWS:,}): shorten the trajectory or lower --sample-rate-hz")
    if n < 2:
        raise FlannError(f"{total:g} s at {fs:g} samples/s is fewer than 2 samples")
    t = np.arange(n, dtype=float) / fs
    if soaks:
        # each pass at the times of the first, so that each soak dwells where the others do
        i = np.arange(n)
        x, direction = trajectory_positions(trajectory, (i % per) / fs, travel, step_mm, sweeps)
        temp = np.asarray(soaks)[i // per]
    else:
        x, direction = trajectory_positions(trajectory, t, travel, step_mm, sweeps)
        profile = (temperature_profile if callable(temperature_profile)
                   else parse_temperature_profile(temperature_profile))
        temp = np.asarray(profile(t, float(t[-1])), dtype=float)
    drive = 1.0 + settings.excitation_drift_pct / 100.0 * t / t[-1]
    sig = transformer_signal(s, x, direction=direction, temperature_c=temp, time_s=t)
    va, vb = _phasors(s, sig)
    carrier_phase = np.exp(1j * 2 * math.pi * carrier * t)
    q = np.broadcast_to(np.asarray(sig.quadrature_v, dtype=float), t.shape)
    # the output-referred quadrature residual, at the secondaries: +-q/(2G) off the reference
    quad = 1j * q / (2 * s.demodulator_gain_ratio) * np.exp(1j * reference_phase_rad(s))
    a = np.real((va * drive + quad) * carrier_phase)
    b = np.real((vb * drive - quad) * carrier_phase)
    exc = s.excitation_peak_v * drive * np.cos(2 * math.pi * carrier * t)
    h = settings.harmonic_pct / 100.0
    if h > 0:
        third = s.replace(excitation_frequency_hz=3 * carrier)
        va3, vb3 = _phasors(third, sig)
        carrier3 = carrier_phase ** 3
        a = a + h * np.real(va3 * drive * carrier3)
        b = b + h * np.real(vb3 * drive * carrier3)
        exc = exc + h * s.excitation_peak_v * drive * np.real(carrier3)
    rng = np.random.default_rng(settings.seed)
    if settings.noise_v > 0:
        a = a + rng.normal(0.0, settings.noise_v, t.shape)
        b = b + rng.normal(0.0, settings.noise_v, t.shape)
    full_scale = settings.adc_range_v or adc_range_for(max(np.max(np.abs(a)), np.max(np.abs(b))))
    converter = s.replace(adc_bits=int(settings.adc_bits), adc_full_scale_v=float(full_scale))
    return Waveforms(time_s=t, sec_a_v=adc_convert(converter, a), sec_b_v=adc_convert(converter, b),
                     displacement_mm=x, exc_v=exc, temperature_c=temp, source=f"simulate:{s.name}",
                     comments=(f"sample rate {fs:.9g} Hz, ADC {settings.adc_bits} bits +-{full_scale:g} V",))


def adc_range_for(peak_v: float) -> float:
    """The smallest DAQ range (ADC_RANGES_V) at least 10 % above ``peak_v``."""
    for r in ADC_RANGES_V:
        if r >= 1.1 * peak_v:
            return r
    raise FlannError(f"the secondaries reach {peak_v:.3g} V, beyond the largest ADC range "
                     f"{ADC_RANGES_V[-1]:g} V: give --adc-range-v")
