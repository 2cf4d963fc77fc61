"""An independent LVDT forward model, for proving ``flann diagnose`` on curves it did not make.

Nothing here shares code or formulation with :mod:`.lvdt` (transmission-line magnetics) or
:mod:`.effects` (the catalogue), and the diagnosis never calls it: it only generates
recordings for the demonstration and the tests.

Formulation (magnetostatic, reciprocity):

* Each winding is a multi-layer solenoid, split into coaxial current sheets at a few radii
  between its inner and outer diameter.  The on-axis field of a sheet of radius R from
  z1 to z2, per ampere-turn per metre, is ``(mu0/2) [(z - z1)/hypot(z - z1, R) -
  (z - z2)/hypot(z - z2, R)]``.
* The core is a rod cut into short slices.  Each slice is magnetised by the primary's field
  with the apparent susceptibility of a prolate ellipsoid of the rod's aspect ratio
  (demagnetisation factor), tapered towards the rod's ends as an ellipsoid's cross-section
  is.  A slice is a dipole; by reciprocity the flux it puts through a secondary is its
  moment times that secondary's field per ampere at the slice.
* Primary current ``Ip = V / (R + j w L(x))``; ``L`` includes the core's contribution, so the
  drive falls as the core enters the primary.
* Output: the two secondary e.m.f.s are rectified separately and subtracted
  ("difference of amplitudes" conditioning), times a gain; or, for a rectified output,
  the amplitude of their difference with a quadrature residual added in quadrature.

Non-ideal effects are written out here again (on purpose not the catalogue's code):
offset, zero shift, secondary imbalance, backlash, thermal drift of the drive, rails
(asymmetric allowed), lead-screw error, quadrature at the null.

Waveform recordings (:func:`simulate_waveforms`): the same couplings and primary current
with its phase give each secondary's complex e.m.f.; the excitation and both secondaries are
sampled through 12-bit converters with noise, dwelling at stepped positions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..recordings import Recordings

MU0 = 4e-7 * math.pi


@dataclass(frozen=True)
class FilamentLVDT:
    """Construction of the independent model (lengths in mm)."""

    primary_length_mm: float = 10.0
    secondary_length_mm: float = 25.0
    gap_mm: float = 3.0
    coil_inner_radius_mm: float = 4.0
    coil_outer_radius_mm: float = 8.0
    core_length_mm: float = 60.0
    core_radius_mm: float = 2.5
    core_permeability: float = 1000.0
    primary_turns: float = 800.0
    secondary_turns: float = 1500.0
    primary_resistance_ohm: float = 40.0
    drive_v: float = 5.0
    frequency_hz: float = 3000.0
    gain: float = 1.0
    rectified: bool = False
    effects: dict = field(default_factory=dict)

    @property
    def half_length_mm(self) -> float:
        return self.primary_length_mm / 2 + self.gap_mm + self.secondary_length_mm

    def with_effects(self, **effects) -> "FilamentLVDT":
        return replace(self, effects=dict(effects))


def _sheet_field(z_m: np.ndarray, z1: float, z2: float, radii: np.ndarray) -> np.ndarray:
    """On-axis field per (ampere-turn per metre), averaged over the current sheets."""
    a = (z_m[..., None] - z1) / np.hypot(z_m[..., None] - z1, radii)
    b = (z_m[..., None] - z2) / np.hypot(z_m[..., None] - z2, radii)
    return 0.5 * MU0 * np.mean(a - b, axis=-1)


def _demag_factor(aspect: float) -> float:
    """Axial demagnetising factor of a prolate ellipsoid of length/diameter ``aspect``."""
    m = max(aspect, 1.0001)
    e = math.sqrt(1 - 1 / m ** 2)
    return (1 - e * e) / (e ** 3) * (math.atanh(e) - e)


def _couplings(m: FilamentLVDT, core_mm: np.ndarray):
    """Mutual inductances primary->secondary 1, ->secondary 2 and the primary's
    self-inductance (H) for the core centred at each ``core_mm``."""
    mm = 1e-3
    radii = np.linspace(m.coil_inner_radius_mm, m.coil_outer_radius_mm, 4) * mm
    lp = m.primary_length_mm * mm
    ls = m.secondary_length_mm * mm
    p1, p2 = -lp / 2, lp / 2
    s1a, s1b = lp / 2 + m.gap_mm * mm, lp / 2 + m.gap_mm * mm + ls
    n_p = m.primary_turns / lp
    n_s = m.secondary_turns / ls
    n_slices = 160
    half_core = m.core_length_mm * mm / 2
    s = (np.arange(n_slices) + 0.5) / n_slices * 2 - 1          # -1..1 along the rod
    z = np.asarray(core_mm, float)[:, None] * mm + s[None, :] * half_core
    taper = 1 - s ** 2                                           # ellipsoid cross-section
    nd = _demag_factor(m.core_length_mm / (2 * m.core_radius_mm))
    chi = (m.core_permeability - 1) / (1 + nd * (m.core_permeability - 1))
    area = math.pi * (m.core_radius_mm * mm) ** 2
    dv = area * (2 * half_core / n_slices) * taper               # slice volumes
    bp = _sheet_field(z, p1, p2, radii) * n_p                    # T per A in the primary
    b1 = _sheet_field(z, s1a, s1b, radii) * n_s                  # T per A in secondary 1
    b2 = _sheet_field(z, -s1b, -s1a, radii) * n_s
    moment = chi * bp / MU0 * dv                                  # A m^2 per A in the primary
    m1 = np.sum(moment * b1, axis=1)
    m2 = np.sum(moment * b2, axis=1)
    # air part of the primary's inductance (long-solenoid estimate) plus the core's share
    r_mean = float(np.mean(radii))
    l_air = MU0 * m.primary_turns ** 2 * math.pi * r_mean ** 2 / (lp + 0.9 * r_mean)
    l_p = l_air + np.sum(moment * bp, axis=1)
    return m1, m2, l_p


def output_v(m: FilamentLVDT, displacement_mm, direction=None, temperature_c=None,
             ) -> np.ndarray:
    """Noiseless output for commanded displacements (core centred at 0 mm)."""
    x = np.asarray(displacement_mm, float)
    d = np.zeros_like(x) if direction is None else np.asarray(direction, float)
    e = m.effects
    core = x.copy()
    if "leadscrew" in e:
        p = e["leadscrew"]
        core = core + p["amplitude_mm"] * np.sin(2 * math.pi * x / p["period_mm"] + p["phase_rad"])
    if "backlash" in e:
        core = core - d * e["backlash"]["deadband_mm"] / 2
    if "zero_shift" in e:
        core = core - e["zero_shift"]["shift_mm"]
    m1, m2, l_p = _couplings(m, core)
    w = 2 * math.pi * m.frequency_hz
    ip = m.drive_v / np.abs(m.primary_resistance_ohm + 1j * w * l_p)
    if "thermal" in e and temperature_c is not None:
        p = e["thermal"]
        ip = ip * (1 + p["coefficient_per_c"] * (np.asarray(temperature_c, float) - p["reference_c"]))
    if "imbalance" in e:
        f = e["imbalance"]["fraction"]
        m1, m2 = m1 * (1 + f / 2), m2 * (1 - f / 2)
    v1, v2 = w * m1 * ip, w * m2 * ip
    if m.rectified:
        q = e.get("quadrature", {}).get("quadrature_v", 0.0) / abs(m.gain)
        y = abs(m.gain) * np.hypot(v1 - v2, q)
    else:
        y = m.gain * (np.abs(v1) - np.abs(v2))
    if "offset" in e:
        y = y + e["offset"]["offset_v"]
    if "rails" in e:
        y = np.clip(y, e["rails"]["low_v"], e["rails"]["high_v"])
    return y


def monotonic_half_range(m: FilamentLVDT, fraction: float = 0.85) -> float:
    """Largest symmetric travel (mm) over which the ideal output is monotonic, times
    ``fraction`` (the recordings stay inside the linear-ish part and its roll-off)."""
    xs = np.linspace(0, 2.0 * m.half_length_mm, 801)
    y = output_v(replace(m, effects={}, rectified=False, gain=1.0), xs)
    dy = np.diff(y)
    bad = np.flatnonzero(dy <= 0)
    edge = xs[bad[0]] if bad.size else xs[-1]
    return fraction * float(edge)


def random_geometry(rng: np.random.Generator) -> FilamentLVDT:
    """A plausible LVDT drawn at random (primary 2-20 mm, secondaries 8-40 mm, ...)."""
    lp = rng.uniform(2, 20)
    ls = rng.uniform(8, 40)
    gap = rng.uniform(0.5, 8)
    ri = rng.uniform(2.5, 8)
    ro = ri + rng.uniform(2, 8)
    span = lp + 2 * gap + 2 * ls
    return FilamentLVDT(
        primary_length_mm=lp, secondary_length_mm=ls, gap_mm=gap,
        coil_inner_radius_mm=ri, coil_outer_radius_mm=ro,
        core_length_mm=span * rng.uniform(0.45, 0.8), core_radius_mm=ri * rng.uniform(0.5, 0.9),
        core_permeability=float(10 ** rng.uniform(1.5, 3.5)),
        primary_turns=rng.uniform(300, 2000), secondary_turns=rng.uniform(500, 4000),
        primary_resistance_ohm=rng.uniform(10, 150), drive_v=rng.uniform(2, 10),
        frequency_hz=rng.uniform(1e3, 1e4), gain=1.0)


def scaled_to(m: FilamentLVDT, peak_v: float, half_range_mm: float) -> FilamentLVDT:
    """Same sensor with the gain set so the output reaches ``peak_v`` at the travel's end."""
    g = replace(m, effects={}, rectified=False, gain=1.0)
    ref = float(np.max(np.abs(output_v(g, np.array([-half_range_mm, half_range_mm])))))
    sign = 1.0 if m.gain >= 0 else -1.0
    return replace(m, gain=sign * peak_v / ref)


def simulate_recording(m: FilamentLVDT, travel_mm: tuple[float, float], step_mm: float,
                       noise_v: float, seed: int, origin_mm: float = 0.0,
                       both_directions: bool = True, temperature=None,
                       source: str = "filament model"):
    """Bench recording: an outward sweep over ``travel_mm`` (core positions, null at 0)
    and, when ``both_directions``, the return sweep; white noise of ``noise_v``; the
    displacement column is the core position plus ``origin_mm``.  ``temperature`` is a
    function (time_s, duration_s) -> degC or None."""
    lo, hi = travel_mm
    n = int(math.floor((hi - lo) / step_mm + 1e-9)) + 1
    fwd = lo + step_mm * np.arange(n)
    x = np.concatenate([fwd, fwd[::-1]]) if both_directions else fwd
    d = np.concatenate([np.ones(n), -np.ones(n)]) if both_directions else np.ones(n)
    t = np.arange(x.size, dtype=float)
    temp = None if temperature is None else np.asarray(temperature(t, float(t[-1])), float)
    y = output_v(m, x, direction=d, temperature_c=temp)
    y = y + np.random.default_rng(seed).normal(0.0, noise_v, x.size)
    if "rails" in m.effects:
        r = m.effects["rails"]
        y = np.clip(y, r["low_v"], r["high_v"])
    return Recordings(displacement_mm=x + origin_mm, voltage_v=y, direction=d, time_s=t,
                      temperature_c=temp, source=source)


# -- waveform recordings ------------------------------------------------------------------
#
# The same magnetics sampled as a DAQ records them: the excitation and the two secondaries'
# e.m.f.s at the carrier, each a complex amplitude from the couplings and the primary current
# Ip = V / (R + j w L(x)) with its phase kept.  What a waveform sees of the effects, in this
# model's own terms: ``imbalance`` scales the couplings (m1 by 1 + f/2, m2 by 1 - f/2);
# ``zero_shift`` moves the core; ``quadrature`` (output-referred, as for the rectified output)
# is q / |gain| in quadrature with the primary-induced e.m.f., added to the secondaries'
# difference, half on each secondary; ``excitation_drift`` (``drift_pct`` over the run)
# scales the drive.  ``offset`` and ``rails`` are made by a demodulator after the secondaries
# and are not in a waveform; ``backlash``, ``leadscrew`` and ``thermal`` are not modelled here.

# a DAQ's input ranges (V), the smallest at least 10 % above a channel's peak is used
DAQ_RANGES_V = (0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0)
WAVE_EFFECTS = ("zero_shift", "imbalance", "quadrature", "excitation_drift", "offset", "rails")


def secondary_emfs(m: FilamentLVDT, displacement_mm) -> tuple[np.ndarray, np.ndarray]:
    """Complex peak e.m.f.s of secondary 1 and secondary 2 (phase against the excitation
    ``drive_v cos(w t)``) for commanded displacements, with the effects a waveform shows
    (not the excitation drift, which is a function of time)."""
    bad = sorted(set(m.effects) - set(WAVE_EFFECTS))
    if bad:
        raise ValueError(f"not modelled in the filament waveforms: {', '.join(bad)}")
    e = m.effects
    core = np.asarray(displacement_mm, float).copy()
    if "zero_shift" in e:
        core = core - e["zero_shift"]["shift_mm"]
    m1, m2, l_p = _couplings(m, core)
    w = 2 * math.pi * m.frequency_hz
    ip = m.drive_v / (m.primary_resistance_ohm + 1j * w * l_p)          # complex, phase kept
    if "imbalance" in e:
        f = e["imbalance"]["fraction"]
        m1, m2 = m1 * (1 + f / 2), m2 * (1 - f / 2)
    v1, v2 = -1j * w * m1 * ip, -1j * w * m2 * ip                       # Faraday: -j w M Ip
    if "quadrature" in e:
        q = e["quadrature"]["quadrature_v"] / abs(m.gain)
        along = -1j * ip / np.abs(ip)                                    # the e.m.f.s' phase
        v1, v2 = v1 + 0.5j * q * along, v2 - 0.5j * q * along
    return v1, v2


def daq_range_v(peak_v: float) -> float:
    for r in DAQ_RANGES_V:
        if r >= 1.1 * peak_v:
            return r
    raise ValueError(f"peak {peak_v:.3g} V beyond the largest DAQ range {DAQ_RANGES_V[-1]:g} V")


def _daq(v: np.ndarray, range_v: float, bits: int) -> np.ndarray:
    """Bipolar converter: saturate at +-range, round to its LSB."""
    lsb = 2 * range_v / 2 ** bits
    codes = np.clip(np.round(v / lsb), -2 ** (bits - 1), 2 ** (bits - 1) - 1)
    return codes * lsb


def dwell_positions(half_range_mm: float, step_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """Stepped positions -h..h forward and back (each turning point once) and directions."""
    n = int(math.floor(half_range_mm / step_mm + 1e-9))
    fwd = step_mm * np.arange(-n, n + 1)
    back = fwd[-2::-1]
    return np.concatenate([fwd, back]), np.concatenate([np.ones(fwd.size), -np.ones(back.size)])


def simulate_waveforms(m: FilamentLVDT, half_range_mm: float, step_mm: float, noise_v: float,
                       seed: int, dwell_s: float = 0.003, samples_per_carrier: int = 32,
                       adc_bits: int = 12, source: str = "filament model waveforms"):
    """A waveform recording (:class:`flann.recordings.waveform.Waveforms`): dwells of
    ``dwell_s`` at positions stepped by ``step_mm`` over +-``half_range_mm`` forward and back;
    ``exc_v = drive a(t) cos(w t)``, ``sec_a_v, sec_b_v = Re(V a(t) e^{j w t})`` (secondary 1,
    secondary 2), ``a(t)`` the excitation drift (linear over the run); white noise of
    ``noise_v`` rms on every channel per sample; ``adc_bits`` converters, the excitation on its
    own range, both secondaries on one, each the smallest DAQ range 10 % above the peak."""
    from ..recordings.waveform import Waveforms

    pos, _dirs = dwell_positions(half_range_mm, step_mm)
    fc = m.frequency_hz
    fs = samples_per_carrier * fc
    per = int(round(dwell_s * fs))
    t = np.arange(pos.size * per) / fs
    x = np.repeat(pos, per)
    v1, v2 = secondary_emfs(m, pos)
    drift = m.effects.get("excitation_drift", {}).get("drift_pct", 0.0) / 100.0
    a = 1.0 + drift * t / t[-1]
    ph = np.exp(1j * 2 * math.pi * fc * t)
    sec_a = np.real(np.repeat(v1, per) * a * ph)
    sec_b = np.real(np.repeat(v2, per) * a * ph)
    exc = m.drive_v * a * np.real(ph)
    rng = np.random.default_rng(seed)
    sec_a, sec_b, exc = (v + rng.normal(0.0, noise_v, t.size) for v in (sec_a, sec_b, exc))
    r_sec = daq_range_v(max(np.max(np.abs(v1)), np.max(np.abs(v2))) * max(1.0, np.max(a)))
    r_exc = daq_range_v(m.drive_v * max(1.0, np.max(a)))
    return Waveforms(time_s=t, sec_a_v=_daq(sec_a, r_sec, adc_bits), sec_b_v=_daq(sec_b, r_sec, adc_bits),
                     displacement_mm=x, exc_v=_daq(exc, r_exc, adc_bits), source=source,
                     comments=(f"filament model, carrier {fc:.9g} Hz, sample rate {fs:.9g} Hz, ADC "
                               f"{adc_bits} bits, secondaries +-{r_sec:g} V, excitation +-{r_exc:g} V",))


def waveform_draw(seed: int, positions: int = 33) -> tuple[FilamentLVDT, float, float]:
    """A random sensor for a waveform recording (:func:`random_geometry`, output scaled to
    2-8 V at the travel's end, either sign), its half travel (60-100 % of the monotonic
    range, centred on 0 mm as the waveform diagnosis' mirrored pairs need) and a stage step
    in whole micrometres giving ``positions`` dwell positions per pass."""
    rng = np.random.default_rng(20_000 + seed)
    m = random_geometry(rng)
    h = monotonic_half_range(m) * rng.uniform(0.6, 1.0)
    m = scaled_to(m, rng.uniform(2.0, 8.0), h)
    if rng.random() < 0.5:
        m = replace(m, gain=-m.gain)
    step = round(2 * h / (positions - 1), 3)
    return m, step * ((positions - 1) // 2), step
