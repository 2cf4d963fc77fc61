"""Names, parameters, defaults and bounds of the non-ideal effects, and their validation.

The lowest layer of :mod:`flann.physics`: the sensor description validates its
``[effects.*]`` tables against these, and :mod:`.effects` attaches the physics (``apply``)
to the same entries.  Nothing here imports the rest of the package but its errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

from ..errors import SensorError

# the temperatures a sensor model is taken to (degC): absolute zero to a high-temperature
# LVDT's rating with margin; the effects' reference temperatures and every simulated one
TEMPERATURE_RANGE_C = (-273.15, 1000.0)


@dataclass(frozen=True)
class Param:
    name: str          # key in the sensor file, ends with its unit
    unit: str
    default: float     # a typical size (used by with_effect and examples)
    neutral: float     # value at which the effect does nothing
    lower: float
    upper: float
    description: str


@dataclass(frozen=True)
class EffectSpec:
    name: str
    stage: str
    description: str
    formula: str
    params: tuple[Param, ...]

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.params)

    def defaults(self) -> dict[str, float]:
        return {p.name: p.default for p in self.params}


_I = math.inf
SPECS: dict[str, EffectSpec] = {
    e.name: e for e in (
        EffectSpec("null_offset", "output",
               "electrical offset at null: in-phase residual or amplifier/demodulator DC offset",
               "y += offset_v",
               (Param("offset_v", "V", 0.01, 0.0, -1e3, 1e3, "output offset"),)),
        EffectSpec("quadrature_null", "transformer",
               "quadrature/harmonic null residual (capacitive coupling, phase mismatch) that an "
               "amplitude detector adds in quadrature; a phase-sensitive detector rejects it",
               "amplitude detector: y = sqrt(y0^2 + quadrature_v^2); phase-sensitive: y = y0",
               (Param("quadrature_v", "V", 0.02, 0.0, 0.0, 1e3,
                      "output-referred quadrature residual at null"),)),
        EffectSpec("zero_shift", "position",
               "mechanical null not at zero displacement (core or actuator origin offset)",
               "core = x - shift_mm",
               (Param("shift_mm", "mm", 0.5, 0.0, -1e3, 1e3, "displacement at which the core is centred"),)),
        EffectSpec("secondary_imbalance", "transformer",
               "unequal secondary coupling (turns or position mismatch) leaves part of the "
               "common-mode secondary voltage in the output",
               "v1 *= 1 + e/2, v2 *= 1 - e/2",
               (Param("imbalance_fraction", "1", 0.01, 0.0, -0.99, 0.99,
                      "relative coupling mismatch e of secondary 1 over secondary 2"),)),
        EffectSpec("backlash", "position",
               "lost motion of the actuator: the core lags behind the commanded position "
               "against the direction of travel",
               "core = x - direction * deadband_mm / 2",
               (Param("deadband_mm", "mm", 0.2, 0.0, 0.0, 1e3, "full dead band"),)),
        EffectSpec("thermal_drift", "transformer",
               "sensitivity changes with temperature, e.g. the primary's copper resistance "
               "(+0.39 %/degC) lowering the excitation current",
               "primary current *= 1 + coefficient_per_c * (T - reference_temperature_c)",
               (Param("coefficient_per_c", "1/degC", -0.001, 0.0, -0.5, 0.5,
                      "relative sensitivity change per degC"),
                Param("reference_temperature_c", "degC", 20.0, 20.0, *TEMPERATURE_RANGE_C,
                      "temperature at which the sensitivity is nominal"))),
        EffectSpec("adc_clipping", "output",
               "converter or amplifier rails: the output saturates at +-rail_v",
               "y = clip(y, -rail_v, rail_v)",
               (Param("rail_v", "V", 5.0, _I, 1e-9, _I, "rail (saturation) voltage"),)),
        EffectSpec("leadscrew_periodic", "position",
               "periodic position error of the actuator's lead screw (thread pitch, "
               "eccentricity): the core is displaced sinusoidally in the commanded position",
               "core = x + amplitude_mm * sin(2 pi x / period_mm + phase_rad)",
               (Param("amplitude_mm", "mm", 0.05, 0.0, -1e3, 1e3, "position error amplitude"),
                Param("period_mm", "mm", 2.54, 2.54, 1e-6, 1e6,
                      "period (lead of the screw; 2.54 mm = 10 threads per inch)"),
                Param("phase_rad", "rad", 0.0, 0.0, -1e3, 1e3, "phase at x = 0"))),
        EffectSpec("secondary_loading", "transformer",
               "finite load resistance on the series-opposed secondaries: their "
               "position-dependent inductance and resistance divide the e.m.f. (gain and phase)",
               "v_d *= R_L / (R_L + 2 R_s + j w L_loop(core))",
               (Param("load_ohm", "ohm", 100e3, _I, 1e-3, _I, "load resistance"),)),
        EffectSpec("thermal_construction", "transformer",
               "temperature from the construction: copper windings (+0.393 %/degC) against the "
               "source and load impedances, the core's permeability, and the secondaries' "
               "balance drifting apart",
               "R_p, R_s *= 1 + copper_tempco_per_c dT;  Ip = V / (source_ohm + R_p + j w Lp(mu)); "
               "mu_r *= 1 + permeability_tempco_per_c dT;  v1 *= 1 + e/2, v2 *= 1 - e/2 with "
               "e = balance_drift_per_c dT;  dT = T - reference_temperature_c",
               (Param("reference_temperature_c", "degC", 20.0, 20.0, *TEMPERATURE_RANGE_C,
                      "temperature of the sensor file's resistances and permeability"),
                Param("copper_tempco_per_c", "1/degC", 0.00393, 0.0, -0.1, 0.1,
                      "winding resistance temperature coefficient (copper: 0.00393 at 20 degC)"),
                Param("source_resistance_ohm", "ohm", 0.0, 0.0, 0.0, 1e7,
                      "excitation source output resistance in series with the primary "
                      "(not heated with the sensor)"),
                Param("permeability_tempco_per_c", "1/degC", 0.0002, 0.0, -0.1, 0.1,
                      "relative change of the core's permeability per degC"),
                Param("balance_drift_per_c", "1/degC", 2e-6, 0.0, -0.01, 0.01,
                      "change per degC of the coupling mismatch of secondary 1 over 2"))),
    )
}


def validate_effects(effects: Mapping[str, Mapping[str, float]], source: str = "<memory>") -> None:
    """Raise SensorError for an unknown effect, a missing/unknown parameter or a value
    outside the parameter's physical range."""
    for name, params in effects.items():
        if name not in SPECS:
            raise SensorError(f"{source}: unknown effect '{name}' (known: {', '.join(SPECS)})")
        eff = SPECS[name]
        for key in params:
            if key not in eff.param_names:
                raise SensorError(f"{source}: effects.{name}.{key}: unknown parameter "
                                  f"(allowed: {', '.join(eff.param_names)})")
        for p in eff.params:
            if p.name not in params:
                raise SensorError(f"{source}: effects.{name}.{p.name} missing")
            v = params[p.name]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or math.isnan(v):
                raise SensorError(f"{source}: effects.{name}.{p.name} must be a number, got {v!r}")
            if not p.lower <= v <= p.upper:
                raise SensorError(f"{source}: effects.{name}.{p.name} = {v:g} out of range "
                                  f"[{p.lower:g}, {p.upper:g}] {p.unit}")
