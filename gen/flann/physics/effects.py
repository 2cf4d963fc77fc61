"""Catalogue of non-ideal effects, each switched on in the sensor file with physical parameters.

Public API (stable; ``flann diagnose`` uses the same catalogue):

* :data:`EFFECTS` -- ordered ``name -> Effect``.  Names (exact): ``null_offset``,
  ``quadrature_null``, ``zero_shift``, ``secondary_imbalance``, ``backlash``,
  ``thermal_drift``, ``adc_clipping``, ``leadscrew_periodic``, ``secondary_loading``,
  ``thermal_construction``.
* :class:`Effect`: ``name``, ``stage``, ``description`` (one line of physics), ``params``
  (tuple of :class:`Param`: ``name`` with unit suffix, ``unit``, ``default`` (a typical
  size), ``neutral`` (the value at which the effect does nothing), ``lower``/``upper``
  bounds, ``description``), ``formula`` (text), ``defaults()``, ``neutral()``,
  ``bounds()`` and ``apply(params, ctx, signal) -> signal`` (pure, vectorised).
* :func:`thermal_coefficient_from_copper` (sensor) -> the thermal_drift coefficient the
  primary's copper resistance alone would cause.
* :class:`Context` (inputs per sample: displacement_mm, direction, temperature_c, time_s,
  sensor) and :class:`Signal` (state flowing through the stages).

Stages, applied in this order by :func:`flann.physics.simulate.simulate_output_v`:

1. ``position`` -- on the core position before the magnetics (zero_shift, backlash,
   leadscrew_periodic): ``core_mm``.
2. ``transformer`` -- on the primary drive and the secondaries (thermal_drift:
   ``drive_scale``; secondary_imbalance: ``s1_scale``/``s2_scale``; secondary_loading:
   ``load_ohm``; quadrature_null: ``quadrature_v``, output-referred, seen only by the
   amplitude detector; thermal_construction: ``resistance_scale``, ``source_ohm``,
   ``permeability_scale`` and the secondaries' balance).
3. the magnetics and the demodulator (:mod:`flann.physics.lvdt`) -> ``output_v``.
4. ``output`` -- on the demodulated volts (null_offset, then adc_clipping last).

Formulas (x = displacement, d = direction of travel +-1 (0 when unknown), T = temperature,
y = output, y0(x) = ideal output, v1/v2 = secondary e.m.f.s, G = demodulator gain):

* null_offset:        y += offset_v
* quadrature_null:    amplitude detector: y = G |v_d + j quadrature_v/G| = sqrt(y0^2 + q^2)
                      (phase-sensitive detector: rejected, no change)
* zero_shift:         core = x - shift_mm            (null moves to x = +shift_mm)
* secondary_imbalance v1 *= 1 + e/2, v2 *= 1 - e/2  -> y += G e (v1+v2)/2 (in phase)
* backlash:           core = x - d * deadband_mm / 2 (core lags the actuator)
* thermal_drift:      primary current *= 1 + k (T - reference_temperature_c)
* adc_clipping:       y = clip(y, -rail_v, +rail_v)
* leadscrew_periodic: core = x + a sin(2 pi x / period_mm + phase_rad)
* secondary_loading:  v_d -> v_d R_L / (R_L + 2 R_s + j w L_loop(core))
* thermal_construction: dT = T - T_ref; R_p, R_s *= 1 + a_cu dT (copper); Ip = V / (R_src +
                      R_p + j w Lp); core mu_r *= 1 + a_mu dT (inductances recomputed);
                      v1 *= 1 + e/2, v2 *= 1 - e/2 with e = balance_drift_per_c dT
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Mapping

import numpy as np

from .effect_params import SPECS, Param, validate_effects  # noqa: F401 (re-exported)
from .lvdt import inductances_h

STAGES = ("position", "transformer", "output")


@dataclass(frozen=True)
class Context:
    """Per-sample inputs (arrays broadcast to the displacement's shape)."""

    displacement_mm: np.ndarray
    direction: np.ndarray        # +1 increasing, -1 decreasing, 0 unknown
    temperature_c: np.ndarray | None   # None: at every effect's reference temperature
    time_s: np.ndarray
    sensor: object               # flann.physics.sensor.Sensor


@dataclass(frozen=True)
class Signal:
    core_mm: np.ndarray
    drive_scale: np.ndarray | float = 1.0
    s1_scale: np.ndarray | float = 1.0
    s2_scale: np.ndarray | float = 1.0
    quadrature_v: np.ndarray | float = 0.0
    load_ohm: float = math.inf
    resistance_scale: np.ndarray | float = 1.0     # winding resistances (copper, heated)
    source_ohm: float = 0.0                        # excitation source resistance
    permeability_scale: np.ndarray | float = 1.0   # core relative permeability
    output_v: np.ndarray | None = None


@dataclass(frozen=True)
class Effect:
    name: str
    stage: str
    description: str
    formula: str
    params: tuple[Param, ...]
    apply: Callable[[Mapping[str, float], Context, Signal], Signal]

    def defaults(self) -> dict[str, float]:
        return {p.name: p.default for p in self.params}

    def neutral(self) -> dict[str, float]:
        return {p.name: p.neutral for p in self.params}

    def bounds(self) -> dict[str, tuple[float, float]]:
        return {p.name: (p.lower, p.upper) for p in self.params}

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.params)


def _rep(sig: Signal, **kw) -> Signal:
    """dataclasses.replace(sig, **kw) without its per-field walk (Signal has no
    __post_init__; every field is an init field): the same values in a new instance."""
    new = object.__new__(Signal)
    new.__dict__.update(sig.__dict__)
    new.__dict__.update(kw)
    return new


# -- position stage ---------------------------------------------------------------------

def _zero_shift(p, ctx, sig):
    return _rep(sig, core_mm=sig.core_mm - p["shift_mm"])


def _backlash(p, ctx, sig):
    return _rep(sig, core_mm=sig.core_mm - ctx.direction * (p["deadband_mm"] / 2.0))


def _leadscrew(p, ctx, sig):
    phase = 2 * math.pi * ctx.displacement_mm / p["period_mm"] + p["phase_rad"]
    return _rep(sig, core_mm=sig.core_mm + p["amplitude_mm"] * np.sin(phase))


# -- transformer stage -------------------------------------------------------------------

def _thermal(p, ctx, sig):
    if ctx.temperature_c is None:
        return sig
    scale = 1.0 + p["coefficient_per_c"] * (ctx.temperature_c - p["reference_temperature_c"])
    return _rep(sig, drive_scale=sig.drive_scale * scale)


def _construction(p, ctx, sig):
    if ctx.temperature_c is None:
        return sig
    dt = ctx.temperature_c - p["reference_temperature_c"]
    e = p["balance_drift_per_c"] * dt
    return _rep(sig, resistance_scale=sig.resistance_scale * (1.0 + p["copper_tempco_per_c"] * dt),
                source_ohm=sig.source_ohm + p["source_resistance_ohm"],
                permeability_scale=sig.permeability_scale * (1.0 + p["permeability_tempco_per_c"] * dt),
                s1_scale=sig.s1_scale * (1 + e / 2), s2_scale=sig.s2_scale * (1 - e / 2))


def _imbalance(p, ctx, sig):
    e = p["imbalance_fraction"]
    return _rep(sig, s1_scale=sig.s1_scale * (1 + e / 2), s2_scale=sig.s2_scale * (1 - e / 2))


def _quadrature(p, ctx, sig):
    return _rep(sig, quadrature_v=sig.quadrature_v + p["quadrature_v"])


def _loading(p, ctx, sig):
    return _rep(sig, load_ohm=p["load_ohm"])


# -- output stage ------------------------------------------------------------------------

def _null_offset(p, ctx, sig):
    return _rep(sig, output_v=sig.output_v + p["offset_v"])


def _clipping(p, ctx, sig):
    return _rep(sig, output_v=np.clip(sig.output_v, -p["rail_v"], p["rail_v"]))


_APPLY = {"null_offset": _null_offset, "quadrature_null": _quadrature, "zero_shift": _zero_shift,
          "secondary_imbalance": _imbalance, "backlash": _backlash, "thermal_drift": _thermal,
          "adc_clipping": _clipping, "leadscrew_periodic": _leadscrew,
          "secondary_loading": _loading, "thermal_construction": _construction}
EFFECTS: dict[str, Effect] = {
    spec.name: Effect(spec.name, spec.stage, spec.description, spec.formula, spec.params,
                      _APPLY[spec.name])
    for spec in SPECS.values()
}


COPPER_TEMPCO_PER_C = 0.00393   # resistance temperature coefficient of copper at 20 degC


def thermal_coefficient_from_copper(sensor, alpha_per_c: float = COPPER_TEMPCO_PER_C) -> float:
    """Sensitivity coefficient (1/degC) that the primary's copper alone causes at null:
    with ``Ip = V / Z``, ``Z = R_p + j w Lp`` and ``R_p(T) = R_p (1 + alpha dT)``,
    ``d ln|Ip| / dT = -alpha R_p Re(Z) / |Z|^2`` (= ``-alpha R_p^2 / |Z|^2`` for a lossless core).  A physical starting value for
    ``thermal_drift.coefficient_per_c`` (core permeability and secondary loading add more)."""
    lp = complex(inductances_h(sensor, [0.0])[2][0])   # complex with core eddy losses
    r = sensor.primary_resistance_ohm
    z = r + 1j * sensor.omega_rad_s * lp
    # d|Z|/dR = Re(Z)/|Z|, so d ln|Ip| / dT = -alpha R Re(Z) / |Z|^2
    return float(-alpha_per_c * r * z.real / abs(z) ** 2)


