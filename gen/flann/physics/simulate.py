"""Simulated output with every enabled effect, and simulated bench recordings.

Public API (stable):

* :func:`simulate_output_v` (sensor, displacement_mm, direction=None, temperature_c=None,
  time_s=None) -> ndarray: noiseless analog output with all of ``sensor.effects`` applied
  in stage order (position -> transformer -> magnetics/demodulator -> output, clipping last;
  see :mod:`flann.physics.effects`).  ``direction`` None means unknown (backlash does
  nothing); ``temperature_c`` None means every effect's reference temperature.
* :func:`contributions_v` (same arguments) -> {effect name: output with only that effect
  minus the ideal output}, plus ``"all"`` (all effects minus ideal).
* :func:`adc_convert` (sensor, volts) -> volts: the sensor's converter (rails at its full
  scale, rounding to its LSB); identity when the sensor has no ``[adc]``.
* :func:`sweep_positions` and :func:`simulate_recordings` (sensor, sweeps=1, step_mm=1.0,
  noise_v=0.0, seed=0, temperature_profile=None, travel_mm=None, step_time_s=1.0) ->
  :class:`flann.recordings.Recordings` with direction, time_s and temperature_c columns,
  reproducible from ``seed``.
* :func:`parse_temperature_profile` ("20", "const:20", "ramp:20:45", "sine:25:5:600").
* :func:`simulate_calibration` (sensor, temperatures, ...) -> the sweeps of
  :func:`simulate_recordings` at each temperature in turn, one recording (``--temperatures``);
  :func:`parse_temperatures` ("-20,0,25,50,80").
* :func:`fold_back_mm` (sensor, travel) -> the first |displacement| in the travel beyond which
  the ideal output stops rising (the core leaving the secondaries), or None.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import FlannError
from ..numeric.fixed import nearest_codes, signed_range
from ..recordings import Recordings
from .effect_params import TEMPERATURE_RANGE_C
from .effects import EFFECTS, Context, Signal, _rep
from .lvdt import demodulate_v, inductances_h
from .sensor import Sensor

_ORDER = {name: i for i, name in enumerate(EFFECTS)}


def _ordered(effects, stage: str):
    names = [n for n in effects if EFFECTS[n].stage == stage]
    names.sort(key=lambda n: (n == "adc_clipping", _ORDER[n]))  # clipping always last
    return names


def _broadcast(value, shape, fill) -> np.ndarray | None:
    if value is None:
        return None if fill is None else np.full(shape, fill, dtype=float)
    return np.broadcast_to(np.asarray(value, dtype=float), shape)


def _front_stages(s: Sensor, displacement_mm, direction, temperature_c, time_s) -> tuple[Signal, Context]:
    """The effects' position and transformer stages, in order."""
    x = np.asarray(displacement_mm, dtype=float)
    ctx = Context(
        displacement_mm=x,
        direction=_broadcast(direction, x.shape, 0.0),
        temperature_c=_broadcast(temperature_c, x.shape, None),
        time_s=_broadcast(time_s, x.shape, 0.0),
        sensor=s,
    )
    sig = Signal(core_mm=x)
    for stage in ("position", "transformer"):
        for name in _ordered(s.effects, stage):
            sig = EFFECTS[name].apply(s.effects[name], ctx, sig)
    return sig, ctx


def simulate_output_v(s: Sensor, displacement_mm, direction=None, temperature_c=None,
                      time_s=None, physical: bool = False) -> np.ndarray:
    """Noiseless output (V) of ``s`` with all its enabled effects (see module docstring);
    ``physical``: refuse effects that turn a drive, winding or core factor non-positive (a
    fit's trial parameters may pass through such values, a simulated bench may not)."""
    sig, ctx = _front_stages(s, displacement_mm, direction, temperature_c, time_s)
    if physical:
        _check_scales(s, sig, ctx.temperature_c, ctx.displacement_mm.shape)
    sig = _transformer(s, sig)
    for name in _ordered(s.effects, "output"):
        sig = EFFECTS[name].apply(s.effects[name], ctx, sig)
    return np.asarray(sig.output_v, dtype=float)


_SCALES = ("drive_scale", "resistance_scale", "permeability_scale", "s1_scale", "s2_scale")


def _check_scales(s: Sensor, sig: Signal, temperature_c, shape) -> None:
    """The effects' factors on the drive, the windings and the core stay positive: linear
    temperature coefficients taken far from their reference turn them negative, and the
    transformer would then simulate a sensor no one can build."""
    for field in _SCALES:
        a = np.broadcast_to(np.asarray(getattr(sig, field), dtype=float), shape)
        if a.size and not np.all(a > 0):
            i = int(np.argmin(a))
            at = "" if temperature_c is None else f" at {float(temperature_c.flat[i]):g} degC"
            raise FlannError(f"{s.name}: its effects make the {field.replace('_', ' ')} {float(a.flat[i]):.3g}"
                             f"{at}, not positive: the linear temperature and balance coefficients do not "
                             "reach that far; simulate nearer their reference temperature")


# Above this many distinct permeabilities (a temperature ramp) the inductances are
# interpolated (quadratically) between this many exact solutions spanning them.
_MU_NODES = 16


def _inductances(s: Sensor, core_mm, permeability_scale, loop: bool) -> tuple[np.ndarray, ...]:
    """inductances_h with the core's permeability scaled per sample (thermal_construction)."""
    core = np.asarray(core_mm, dtype=float)
    if isinstance(permeability_scale, float) and core.size:
        # one level for every sample (no thermal_construction): what np.unique would return
        levels = np.array([permeability_scale])
    else:
        scale = np.broadcast_to(np.asarray(permeability_scale, dtype=float), core.shape)
        levels = np.unique(scale)
    if levels.size == 1:
        if levels[0] == 1.0:
            return inductances_h(s, core, loop=loop)
        return inductances_h(s.replace(core_permeability_ratio=max(
            1.0, s.core_permeability_ratio * float(levels[0]))), core, loop=loop)
    nodes = levels if levels.size <= _MU_NODES else np.linspace(levels[0], levels[-1], _MU_NODES)
    at = [inductances_h(s.replace(core_permeability_ratio=max(1.0, s.core_permeability_ratio * float(k))),
                        core, loop=loop) for k in nodes]
    if nodes is levels:
        # every level a node (a calibration's few soaks): each sample takes its own, exactly
        at_level = np.searchsorted(levels, scale)[None]
        return tuple(np.take_along_axis(np.stack([np.broadcast_to(a[k], core.shape) for a in at]), at_level, 0)[0]
                     for k in range(len(at[0])))
    # quadratic (Lagrange) through the three nearest nodes: the inductances curve with mu
    lo = np.clip(np.searchsorted(nodes, scale) - 2, 0, nodes.size - 3)
    n0, n1, n2 = nodes[lo], nodes[lo + 1], nodes[lo + 2]
    weights = ((scale - n1) * (scale - n2) / ((n0 - n1) * (n0 - n2)),
               (scale - n0) * (scale - n2) / ((n1 - n0) * (n1 - n2)),
               (scale - n0) * (scale - n1) / ((n2 - n0) * (n2 - n1)))
    out = []
    for k in range(len(at[0])):
        stack = np.stack([np.broadcast_to(a[k], core.shape) for a in at])   # (nodes, *shape)
        out.append(sum(w * np.take_along_axis(stack, (lo + j)[None], 0)[0]
                       for j, w in enumerate(weights)))
    return tuple(out)


@dataclass(frozen=True)
class Secondaries:
    """The transformer's state for a drive: each secondary's e.m.f. is
    ``1j w m_h i_p loop_gain`` (complex peak volts), the two in series opposition give the
    demodulator's input."""

    m1_h: np.ndarray         # primary -> secondary 1, with the effects' balance factor
    m2_h: np.ndarray         # primary -> secondary 2, likewise
    i_p: np.ndarray          # complex peak primary current (A)
    loop_gain: np.ndarray | float   # R_L / Z_loop of loaded secondaries, 1 unloaded
    omega_rad_s: float


def transformer_secondaries(s: Sensor, sig: Signal) -> Secondaries:
    """Magnetics and primary circuit (with the reflected load of the secondaries) for the
    core positions and factors of ``sig``."""
    loaded = math.isfinite(sig.load_ohm)
    m1, m2, lp, *rest = _inductances(s, sig.core_mm, sig.permeability_scale, loaded)
    w = s.omega_rad_s
    m1 = sig.s1_scale * m1
    m2 = sig.s2_scale * m2
    m_diff = m1 - m2
    z_primary = sig.source_ohm + s.primary_resistance_ohm * sig.resistance_scale + 1j * w * lp
    loop_gain = 1.0
    if loaded:
        z_loop = (sig.load_ohm + 2 * s.secondary_resistance_ohm * sig.resistance_scale
                  + 1j * w * rest[0])
        # Secondary current reflects an impedance (w M)^2 / Z_loop into the primary.
        z_primary = z_primary + (w * m_diff) ** 2 / z_loop
        loop_gain = sig.load_ohm / z_loop
    i_p = s.excitation_peak_v * sig.drive_scale / z_primary
    return Secondaries(m1, m2, i_p, loop_gain, w)


def _transformer(s: Sensor, sig: Signal) -> Signal:
    """Magnetics, primary circuit, (loaded) secondaries and demodulator -> output_v."""
    sec = transformer_secondaries(s, sig)
    v_diff = 1j * sec.omega_rad_s * (sec.m1_h - sec.m2_h) * sec.i_p
    if math.isfinite(sig.load_ohm):
        v_diff = v_diff * sec.loop_gain
    out = demodulate_v(s, v_diff, quadrature_v=sig.quadrature_v)
    return _rep(sig, output_v=out)


def transformer_signal(s: Sensor, displacement_mm, direction=None, temperature_c=None,
                       time_s=None) -> Signal:
    """The effects' position and transformer stages applied to ``displacement_mm`` (the
    state the magnetics see; see :func:`simulate_output_v` for the arguments)."""
    sig, ctx = _front_stages(s, displacement_mm, direction, temperature_c, time_s)
    _check_scales(s, sig, ctx.temperature_c, ctx.displacement_mm.shape)
    return sig


def contributions_v(s: Sensor, displacement_mm, direction=None, temperature_c=None,
                    time_s=None) -> dict[str, np.ndarray]:
    """Per enabled effect: output with only that effect on minus the ideal output; and
    ``"all"``: output with every effect minus the ideal output."""
    ideal = simulate_output_v(s.without_effects(), displacement_mm)
    out = {}
    for name, params in s.effects.items():
        only = s.replace(effects={name: params})
        out[name] = simulate_output_v(only, displacement_mm, direction, temperature_c, time_s) - ideal
    out["all"] = simulate_output_v(s, displacement_mm, direction, temperature_c, time_s) - ideal
    return out


def adc_convert(s: Sensor, volts) -> np.ndarray:
    """The sensor's converter: saturate at its bipolar full scale (never wrap) and round to
    its LSB, ``2 full_scale / 2**bits``, by the one converter rule the hardware's paths use
    (:func:`flann.numeric.fixed.nearest_codes`)."""
    v = np.asarray(volts, dtype=float)
    if s.adc_bits is None:
        return v
    lsb = 2.0 * s.adc_full_scale_v / 2 ** int(s.adc_bits)
    lo, hi = signed_range(int(s.adc_bits))
    return nearest_codes(v, lsb, lo, hi) * lsb


_RANGE_TEXT = f"{TEMPERATURE_RANGE_C[0]:g}..{TEMPERATURE_RANGE_C[1]:g} degC"


def _in_range(t: float) -> bool:
    return math.isfinite(t) and TEMPERATURE_RANGE_C[0] <= t <= TEMPERATURE_RANGE_C[1]


def parse_temperature_profile(spec: str | float | None) -> Callable[[np.ndarray, float], np.ndarray]:
    """A function (time_s, duration_s) -> temperature_c from a text spec.

    ``"25"`` or ``"const:25"``: constant; ``"ramp:20:45"``: linear from 20 to 45 degC over
    the run; ``"sine:25:5:600"``: 25 + 5 sin(2 pi t / 600 s).
    """
    if spec is None:
        spec = "const:20"
    text = str(spec).strip()
    kind, _, rest = text.partition(":")
    if not rest:
        kind, rest = "const", text
    try:
        nums = [float(v) for v in rest.split(":")]
    except ValueError:
        raise FlannError(f"--temperature-profile {text!r}: expected const:T, ramp:T0:T1 or "
                         "sine:MEAN:AMPLITUDE:PERIOD_S (numbers)") from None
    want = {"const": 1, "ramp": 2, "sine": 3}
    if kind not in want or len(nums) != want[kind] or not all(map(math.isfinite, nums)):
        raise FlannError(f"--temperature-profile {text!r}: expected const:T, ramp:T0:T1 or "
                         "sine:MEAN:AMPLITUDE:PERIOD_S")
    reached = nums[:2] if kind != "sine" else [nums[0] - abs(nums[1]), nums[0] + abs(nums[1])]
    if not all(_in_range(t) for t in reached) or (kind == "sine" and nums[2] <= 0):
        raise FlannError(f"--temperature-profile {text!r}: temperatures must be within {_RANGE_TEXT} "
                         "and the period > 0")
    if kind == "const":
        return lambda t, dur: np.full_like(t, nums[0])
    if kind == "ramp":
        return lambda t, dur: nums[0] + (nums[1] - nums[0]) * (t / dur if dur > 0 else 0 * t)
    return lambda t, dur: nums[0] + nums[1] * np.sin(2 * math.pi * t / nums[2])


def sweep_positions(travel_mm: tuple[float, float], step_mm: float,
                    sweeps: int) -> tuple[np.ndarray, np.ndarray]:
    """Commanded positions and directions of ``sweeps`` forward+reverse passes.

    Forward: from..to (direction +1); reverse: to-step..from (direction -1); later forward
    passes start at from+step: each turning point is sampled once, in the direction that
    reached it.  The first forward
    pass is assumed to be approached from below (dead band already taken up).
    """
    lo, hi = travel_mm
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        raise FlannError(f"travel {lo:g}..{hi:g} mm: the end must be above the start")
    if not math.isfinite(step_mm) or step_mm <= 0:
        raise FlannError(f"--step-mm {step_mm:g}: must be > 0")
    n = int(math.floor((hi - lo) / step_mm + 1e-9))
    if n < 1:
        raise FlannError(f"--step-mm {step_mm:g}: larger than the travel {hi - lo:g} mm")
    if n > 1_000_000:
        raise FlannError(f"--step-mm {step_mm:g}: {n} steps per pass is too many (max 1e6)")
    if not 1 <= sweeps <= 1000:
        raise FlannError(f"--sweeps {sweeps}: must be 1..1000")
    fwd = lo + step_mm * np.arange(n + 1)
    rev = fwd[-2::-1]
    pos, dirs = [], []
    for k in range(sweeps):
        f = fwd if k == 0 else fwd[1:]   # the turning point at `from` was taken in reverse
        pos += [f, rev]
        dirs += [np.ones(f.size), -np.ones(rev.size)]
    return np.concatenate(pos), np.concatenate(dirs)


MAX_SAMPLES = 10_000_000
_CHUNK = 200_000


def simulate_recordings(s: Sensor, sweeps: int = 1, step_mm: float = 1.0, noise_v: float = 0.0,
                        seed: int = 0, temperature_profile=None,
                        travel_mm: tuple[float, float] | None = None,
                        step_time_s: float = 1.0, progress: bool = False) -> Recordings:
    """Bench recordings: forward and reverse sweeps over ``travel_mm`` (default the rated
    stroke), every enabled effect, white Gaussian noise of ``noise_v`` (V rms) added before
    the ADC, reproducible from ``seed``.  ``temperature_profile`` is a spec string (see
    :func:`parse_temperature_profile`) or a function (time_s, duration_s) -> degC."""
    if not math.isfinite(noise_v) or noise_v < 0:
        raise FlannError(f"--noise-v {noise_v:g}: must be >= 0")
    if not math.isfinite(step_time_s) or step_time_s <= 0:
        raise FlannError(f"step time {step_time_s:g} s: must be > 0")
    travel = travel_mm if travel_mm is not None else (-s.stroke_mm, s.stroke_mm)
    per_pass = math.floor((travel[1] - travel[0]) / step_mm + 1e-9) + 1 if step_mm > 0 else 0
    if per_pass * 2 * sweeps > MAX_SAMPLES:
        raise FlannError(f"{sweeps} sweeps of {per_pass} steps is more than {MAX_SAMPLES} samples")
    x, d = sweep_positions(travel, step_mm, sweeps)
    t = step_time_s * np.arange(x.size, dtype=float)
    profile = (temperature_profile if callable(temperature_profile)
               else parse_temperature_profile(temperature_profile))
    temp = np.asarray(profile(t, float(t[-1])), dtype=float)
    y = np.empty(x.size)
    for start in range(0, x.size, _CHUNK):
        sl = slice(start, start + _CHUNK)
        y[sl] = simulate_output_v(s, x[sl], direction=d[sl], temperature_c=temp[sl], time_s=t[sl], physical=True)
        if progress and x.size > _CHUNK:
            print(f"simulate: {min(start + _CHUNK, x.size)}/{x.size} samples", file=sys.stderr)
    rng = np.random.default_rng(seed)
    if noise_v > 0:
        y = y + rng.normal(0.0, noise_v, size=y.shape)
    y = adc_convert(s, y)
    return Recordings(displacement_mm=x, voltage_v=y, direction=d, time_s=t, temperature_c=temp,
                      source=f"simulate:{s.name}")


MAX_TEMPERATURES = 64


def parse_temperatures(text: str) -> tuple[float, ...]:
    """``"-20,0,25,50,80"`` -> (-20.0, 0.0, 25.0, 50.0, 80.0): distinct, within TEMPERATURE_RANGE_C."""
    try:
        temps = tuple(float(t) for t in str(text).split(",") if t.strip())
    except ValueError:
        raise FlannError(f"--temperatures {text!r}: expected comma-separated degC, "
                         "e.g. -20,0,25,50,80") from None
    if not temps or len(temps) > MAX_TEMPERATURES:
        raise FlannError(f"--temperatures {text!r}: give 1 to {MAX_TEMPERATURES} temperatures")
    if not all(_in_range(t) for t in temps):
        raise FlannError(f"--temperatures {text!r}: temperatures must be within {_RANGE_TEXT}")
    if len(set(temps)) != len(temps):
        raise FlannError(f"--temperatures {text!r}: a temperature is repeated")
    return temps


def simulate_calibration(s: Sensor, temperatures, sweeps: int = 1, step_mm: float = 1.0,
                         noise_v: float = 0.0, seed: int = 0,
                         travel_mm: tuple[float, float] | None = None,
                         step_time_s: float = 1.0, progress: bool = False) -> Recordings:
    """A calibration at several temperatures: at each (in the order given, the sensor soaked
    at it) the sweeps of :func:`simulate_recordings`, one after the other in one recording.
    The noise of temperature k is drawn from ``seed + k``; time runs on across them."""
    parts = []
    t0 = 0.0
    for k, temp in enumerate(temperatures):
        rec = simulate_recordings(s, sweeps=sweeps, step_mm=step_mm, noise_v=noise_v,
                                  seed=seed + k, temperature_profile=f"const:{float(temp)!r}",
                                  travel_mm=travel_mm, step_time_s=step_time_s, progress=progress)
        parts.append((rec, t0))
        t0 += step_time_s * len(rec)
    if sum(len(r) for r, _ in parts) > MAX_SAMPLES:
        raise FlannError(f"{len(parts)} temperatures x {len(parts[0][0])} samples is more than "
                         f"{MAX_SAMPLES} samples")
    cat = np.concatenate
    return Recordings(displacement_mm=cat([r.displacement_mm for r, _ in parts]),
                      voltage_v=cat([r.voltage_v for r, _ in parts]),
                      direction=cat([r.direction for r, _ in parts]),
                      time_s=cat([r.time_s + t for r, t in parts]),
                      temperature_c=cat([r.temperature_c for r, _ in parts]),
                      source=f"simulate:{s.name}")


def fold_back_mm(s: Sensor, travel_mm: tuple[float, float], n: int = 2001) -> float | None:
    """Smallest |x| in the travel where the ideal output stops being monotonic (its slope
    changes sign relative to the null slope), or None if it is monotonic throughout."""
    x = np.linspace(travel_mm[0], travel_mm[1], n)
    y = simulate_output_v(s.without_effects(), x)
    slope = np.diff(y)
    centre = int(np.argmin(np.abs(0.5 * (x[1:] + x[:-1]))))   # the slope nearest the null
    sign = np.sign(slope[centre]) or 1.0
    bad = slope * sign <= 0
    if not bad.any():
        return None
    mids = 0.5 * (x[1:] + x[:-1])
    return float(np.min(np.abs(mids[bad])))
