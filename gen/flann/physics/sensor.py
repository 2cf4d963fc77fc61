"""Sensor description: the LVDT's construction, read from a TOML file with units in key names.

Public API (stable; ``flann diagnose`` builds on it):

* :class:`Sensor` -- frozen dataclass, one flat field per TOML key (``section_key``):
  geometry, windings, core, excitation, demodulator, ADC, and ``effects`` (a read-only
  mapping ``name -> {parameter: value}`` of the enabled non-ideal effects, see
  :mod:`flann.physics.effects`).  Constructing one validates every field and raises
  :class:`flann.errors.SensorError` naming the field and the allowed range.
* :meth:`Sensor.replace` -- a copy with some fields changed (validated again), e.g.
  ``sensor.replace(secondary_length_mm=28.0, effects={})``.
* :func:`load_sensor` (path) and :func:`parse_sensor` (text) -> :class:`Sensor`.
* :func:`default_sensor` -- the seed paper's LVDT (same as ``data/sensors/paper_lvdt.toml``).
* :func:`format_sensor` -- TOML text of a sensor (round-trips through :func:`parse_sensor`).

File format ``flann-sensor/1`` (every numeric key carries its unit as a suffix: ``_mm``,
``_hz``, ``_vpp``, ``_v``, ``_ohm``, ``_c``, ``_per_c``, ``_rad``, ``_ratio`` (dimensionless),
``_fraction``, or is itself a unit: ``turns``, ``bits``)::

    format = "flann-sensor/1"
    name = "paper_lvdt"
    stroke_mm = 30.0                     # rated half-stroke (travel is -stroke..+stroke)

    [core]                               # movable core: a tube (inner 0 = solid rod)
    inner_diameter_mm = 4.4
    outer_diameter_mm = 5.0
    length_mm = 60.0
    permeability_ratio = 220.0           # relative permeability of the core material
    # conductivity_s_per_m = 1.7e6       # optional: eddy currents (default 0 = none)

    [coil]                               # winding former and magnetic return (housing)
    inner_diameter_mm = 6.0
    outer_diameter_mm = 14.0
    housing_inner_diameter_mm = 20.0

    [primary]                            # centred on z = 0
    turns = 1500
    length_mm = 0.9375
    resistance_ohm = 60.0

    [secondary]                          # two identical windings, series opposition
    turns = 3300
    length_mm = 23.25
    gap_mm = 13.14                       # axial spacing primary end -> secondary start
    resistance_ohm = 200.0

    [excitation]
    amplitude_vpp = 10.0
    frequency_hz = 5000.0

    [demodulator]
    kind = "phase_sensitive"             # or "amplitude" (rectifier: unsigned output)
    gain_ratio = 2.272                   # V out per V peak differential (negative: reversed)

    [adc]
    bits = 16
    full_scale_v = 10.0                  # bipolar: codes span -full_scale..+full_scale

    [effects.null_offset]                # one table per enabled effect
    offset_v = 0.02

Coordinates: ``z`` along the axis, the primary centred on ``z = 0``, secondary 1 on the
``+z`` side (so positive displacement gives positive output for a positive gain).  The core
centre sits at ``z = displacement_mm`` (before the position effects).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np

from ..errors import SensorError
from ..inputs import parse_toml, read_text
from .effect_params import SPECS, validate_effects

FORMAT = "flann-sensor/1"
DEMODULATORS = ("phase_sensitive", "amplitude")

# Recognised unit suffixes (dimensionless quantities say so: _ratio, _fraction).
UNIT_SUFFIXES = ("_mm", "_hz", "_vpp", "_v", "_ohm", "_c", "_per_c", "_rad", "_deg", "_s_per_m",
                 "_ratio", "_fraction", "_s")
UNIT_WORDS = ("turns", "bits")

# TOML section -> {key -> (dataclass field, lower bound, lower inclusive?, upper bound)}.
# Bounds are the physically meaningful range; relations between fields are checked after.
_INF = math.inf
_SCHEMA: dict[str, dict[str, tuple[str, float, bool, float]]] = {
    "": {"stroke_mm": ("stroke_mm", 0.0, False, 1e4)},
    "core": {
        "inner_diameter_mm": ("core_inner_diameter_mm", 0.0, True, 1e3),
        "outer_diameter_mm": ("core_outer_diameter_mm", 0.0, False, 1e3),
        "length_mm": ("core_length_mm", 0.0, False, 1e4),
        "permeability_ratio": ("core_permeability_ratio", 1.0, True, 1e6),
        "conductivity_s_per_m": ("core_conductivity_s_per_m", 0.0, True, 1e9),
    },
    "coil": {
        "inner_diameter_mm": ("coil_inner_diameter_mm", 0.0, False, 1e3),
        "outer_diameter_mm": ("coil_outer_diameter_mm", 0.0, False, 1e3),
        "housing_inner_diameter_mm": ("housing_inner_diameter_mm", 0.0, False, 1e4),
    },
    "primary": {
        "turns": ("primary_turns", 0.0, False, 1e7),
        "length_mm": ("primary_length_mm", 0.0, False, 1e4),
        "resistance_ohm": ("primary_resistance_ohm", 0.0, True, 1e7),
    },
    "secondary": {
        "turns": ("secondary_turns", 0.0, False, 1e7),
        "length_mm": ("secondary_length_mm", 0.0, False, 1e4),
        "gap_mm": ("secondary_gap_mm", 0.0, True, 1e4),
        "resistance_ohm": ("secondary_resistance_ohm", 0.0, True, 1e7),
    },
    "excitation": {
        "amplitude_vpp": ("excitation_amplitude_vpp", 0.0, False, 1e4),
        "frequency_hz": ("excitation_frequency_hz", 0.0, False, 1e8),
    },
    "demodulator": {
        "gain_ratio": ("demodulator_gain_ratio", -1e6, True, 1e6),
    },
    "adc": {
        "bits": ("adc_bits", 1.0, True, 32.0),
        "full_scale_v": ("adc_full_scale_v", 0.0, False, 1e4),
    },
}
_STRING_KEYS = {("", "format"), ("", "name"), ("", "description"), ("demodulator", "kind")}
_OPTIONAL_SECTIONS = ("adc",)
# the range checks in schema order, and each field's (a copy checks only what changed)
_CHECKS = [(i, section, key, spec) for i, (section, key, spec) in enumerate(
    (section, key, spec) for section, keys in _SCHEMA.items() for key, spec in keys.items())]
_CHECK_OF = {c[3][0]: c for c in _CHECKS}
# Keys that may be omitted, with the value they then take.
_OPTIONAL_KEYS = {("core", "conductivity_s_per_m"): 0.0}


@dataclass(frozen=True)
class Sensor:
    """An LVDT's construction (SI-ish units in every field name; see module docstring)."""

    name: str
    stroke_mm: float
    core_inner_diameter_mm: float
    core_outer_diameter_mm: float
    core_length_mm: float
    core_permeability_ratio: float
    coil_inner_diameter_mm: float
    coil_outer_diameter_mm: float
    housing_inner_diameter_mm: float
    primary_turns: float
    primary_length_mm: float
    primary_resistance_ohm: float
    secondary_turns: float
    secondary_length_mm: float
    secondary_gap_mm: float
    secondary_resistance_ohm: float
    excitation_amplitude_vpp: float
    excitation_frequency_hz: float
    demodulator_kind: str = "phase_sensitive"
    demodulator_gain_ratio: float = 1.0
    adc_bits: int | None = None          # None: no converter (analog output recorded)
    adc_full_scale_v: float | None = None
    effects: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    core_conductivity_s_per_m: float = 0.0   # 0: no eddy currents in the core
    description: str = field(default="", compare=False)
    source: str = field(default="<memory>", compare=False)

    def __post_init__(self) -> None:
        _validate(self)
        object.__setattr__(self, "effects", _frozen_effects(self.effects))

    def __hash__(self) -> int:  # effects is a mapping: hash its items
        fields = tuple(getattr(self, f.name) for f in dataclasses.fields(self)
                       if f.compare and f.name != "effects")
        effects = tuple((k, tuple(sorted(v.items()))) for k, v in sorted(self.effects.items()))
        return hash((fields, effects))

    # -- convenience -----------------------------------------------------------------
    def replace(self, **changes: Any) -> "Sensor":
        """Copy with ``changes`` applied (validated; raises SensorError on bad values)."""
        unknown = [k for k in changes if k not in _FIELD_NAMES]
        if unknown:
            raise SensorError(f"Sensor.replace: unknown field(s) {', '.join(unknown)}")
        # what dataclasses.replace does (a new instance through __post_init__), checking only
        # what changed: this sensor passed every check, and a check of unchanged fields would
        # pass again (a fit's every evaluation replaces the gain and the effects)
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new.__dict__.update(changes)
        if "_magnetics_key" in new.__dict__ and not _KEY_FIELDS.isdisjoint(changes):
            del new.__dict__["_magnetics_key"]
        _validate(new, changed=changes.keys())
        if "effects" in changes:
            object.__setattr__(new, "effects", _frozen_effects(new.effects))
        return new

    def without_effects(self) -> "Sensor":
        return self.replace(effects={})

    def with_effect(self, name: str, **params: float) -> "Sensor":
        """Copy with effect ``name`` enabled (defaults for parameters not given)."""
        if name not in SPECS:
            raise SensorError(f"unknown effect '{name}' (known: {', '.join(SPECS)})")
        merged = {**SPECS[name].defaults(), **params}
        return self.replace(effects={**self.effects, name: merged})

    @property
    def excitation_peak_v(self) -> float:
        return self.excitation_amplitude_vpp / 2.0

    @property
    def omega_rad_s(self) -> float:
        return 2.0 * math.pi * self.excitation_frequency_hz

    @property
    def coil_span_mm(self) -> float:
        """Overall length of the winding assembly (secondary outer end to outer end)."""
        return self.primary_length_mm + 2.0 * (self.secondary_gap_mm + self.secondary_length_mm)

    def magnetics_key(self) -> tuple:
        """The fields the inductances depend on (cache key); the frequency only matters
        when the core conducts (eddy currents)."""
        key = self.__dict__.get("_magnetics_key")
        if key is None:   # kept on the instance (every simulated output asks, twice)
            key = tuple(getattr(self, f) for f in _MAGNETIC_FIELDS)
            if self.core_conductivity_s_per_m > 0:
                key += (self.excitation_frequency_hz,)
            self.__dict__["_magnetics_key"] = key
        return key


_FIELD_NAMES = {f.name for f in dataclasses.fields(Sensor)}
_MAGNETIC_FIELDS = (
    "core_inner_diameter_mm", "core_outer_diameter_mm", "core_length_mm",
    "core_permeability_ratio", "core_conductivity_s_per_m",
    "coil_inner_diameter_mm", "coil_outer_diameter_mm",
    "housing_inner_diameter_mm", "primary_turns", "primary_length_mm",
    "secondary_turns", "secondary_length_mm", "secondary_gap_mm",
)
# a change of any of these makes a copy's magnetics key anew (Sensor.replace)
_KEY_FIELDS = frozenset(_MAGNETIC_FIELDS + ("excitation_frequency_hz",))


def _bad(src: str, msg: str) -> SensorError:
    return SensorError(f"{src}: {msg}")


def _frozen_effects(effects) -> MappingProxyType:
    return MappingProxyType({str(k): MappingProxyType(dict(v)) for k, v in dict(effects).items()})


_RADIAL_FIELDS = frozenset(("core_inner_diameter_mm", "core_outer_diameter_mm", "coil_inner_diameter_mm",
                            "coil_outer_diameter_mm", "housing_inner_diameter_mm"))


# The construction parameters a production batch varies from unit to unit (windings, core and
# coil geometry, the conditioner's gain); ``flann simulate --spread`` draws them
SPREAD_FIELDS = ("core_length_mm", "core_permeability_ratio", "primary_turns", "primary_length_mm",
                 "secondary_turns", "secondary_length_mm", "secondary_gap_mm", "demodulator_gain_ratio")


def spread_unit(s: Sensor, spread: float, seed: int) -> tuple[Sensor, dict[str, float]]:
    """One unit of a production batch of ``s``: each of :data:`SPREAD_FIELDS` times
    (1 + N(0, ``spread``)), drawn from ``seed`` (the same seed, the same unit), and the
    factors drawn.  Refused (SensorError) when a draw leaves the sensor's valid range."""
    rng = np.random.default_rng([int(seed), 0x5eed])
    factors = {f: float(1.0 + spread * rng.standard_normal()) for f in SPREAD_FIELDS}
    try:
        unit = s.replace(**{f: getattr(s, f) * k for f, k in factors.items()})
    except SensorError as exc:
        raise SensorError(f"--spread {spread:g} with seed {seed} draws a unit outside the sensor's valid "
                          f"range ({exc}): use a smaller spread") from None
    return unit, factors


def _validate(s: Sensor, changed=None) -> None:
    """Raise SensorError for the first field out of its range or relation.  ``changed``: the
    only fields that may fail (the others are a valid sensor's): the checks of the others are
    skipped, the rest run in the same order, so the first failure is the same."""
    src = s.source
    every = changed is None
    checks = _CHECKS if every else sorted(_CHECK_OF[f] for f in changed if f in _CHECK_OF)
    for _order, section, key, (fname, lo, lo_incl, hi) in checks:
        value = getattr(s, fname)
        if value is None and section in _OPTIONAL_SECTIONS:
            continue
        label = f"{section}.{key}" if section else key
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise _bad(src, f"{label} must be a number, got {value!r}")
        if not math.isfinite(value):
            raise _bad(src, f"{label} must be finite, got {value!r}")
        ok_lo = value >= lo if lo_incl else value > lo
        if not ok_lo or value > hi:
            lo_txt = f"{'>=' if lo_incl else '>'} {lo:g}"
            raise _bad(src, f"{label} = {value:g} out of range (must be {lo_txt} and <= {hi:g})")
    if (every or "demodulator_kind" in changed) and s.demodulator_kind not in DEMODULATORS:
        raise _bad(src, f"demodulator.kind = {s.demodulator_kind!r}: allowed {', '.join(DEMODULATORS)}")
    if (every or "demodulator_gain_ratio" in changed) and s.demodulator_gain_ratio == 0:
        raise _bad(src, "demodulator.gain_ratio must be non-zero (negative means reversed wiring)")
    if every or "adc_bits" in changed or "adc_full_scale_v" in changed:
        if (s.adc_bits is None) != (s.adc_full_scale_v is None):
            raise _bad(src, "adc: give both bits and full_scale_v, or omit the [adc] table")
        if s.adc_bits is not None and float(s.adc_bits) != int(s.adc_bits):
            raise _bad(src, f"adc.bits = {s.adc_bits} must be an integer")
    if not every and _RADIAL_FIELDS.isdisjoint(changed):
        if "effects" in changed:
            validate_effects(s.effects, src)
        return
    # Radial order: core fits in the former, the winding has a build, the housing encloses it.
    if not s.core_inner_diameter_mm < s.core_outer_diameter_mm:
        raise _bad(src, f"core.inner_diameter_mm = {s.core_inner_diameter_mm:g} must be < "
                        f"core.outer_diameter_mm = {s.core_outer_diameter_mm:g}")
    if not s.core_outer_diameter_mm < s.coil_inner_diameter_mm:
        raise _bad(src, f"core.outer_diameter_mm = {s.core_outer_diameter_mm:g} must be < "
                        f"coil.inner_diameter_mm = {s.coil_inner_diameter_mm:g} (core must fit the bore)")
    if not s.coil_inner_diameter_mm < s.coil_outer_diameter_mm:
        raise _bad(src, f"coil.inner_diameter_mm = {s.coil_inner_diameter_mm:g} must be < "
                        f"coil.outer_diameter_mm = {s.coil_outer_diameter_mm:g}")
    if not s.coil_outer_diameter_mm < s.housing_inner_diameter_mm:
        raise _bad(src, f"coil.outer_diameter_mm = {s.coil_outer_diameter_mm:g} must be < "
                        f"coil.housing_inner_diameter_mm = {s.housing_inner_diameter_mm:g}")
    validate_effects(s.effects, src)


# -- TOML ------------------------------------------------------------------------------

def _has_unit(key: str) -> bool:
    return key in UNIT_WORDS or any(key.endswith(u) for u in UNIT_SUFFIXES)


def sensor_from_dict(doc: Mapping[str, Any], source: str = "<memory>") -> Sensor:
    """Validate a parsed TOML document and build the :class:`Sensor`."""
    fmt = doc.get("format", FORMAT)
    if fmt != FORMAT:
        raise _bad(source, f"format = {fmt!r}: expected {FORMAT!r}")
    values: dict[str, Any] = {"source": source}
    known_sections = set(_SCHEMA) | {"effects"}
    for key, val in doc.items():
        if isinstance(val, dict):
            if key not in known_sections:
                raise _bad(source, f"unknown table [{key}] (known: "
                                   f"{', '.join(sorted(k for k in known_sections if k))})")
            continue
        if ("", key) in _STRING_KEYS:
            continue
        if key in known_sections:
            raise _bad(source, f"{key} must be a table ([{key}] ...), got {val!r}")
        if key not in _SCHEMA[""]:
            raise _bad(source, _unknown_key_msg("", key))
    for section, keys in _SCHEMA.items():
        table = doc if section == "" else doc.get(section)
        if table is None:
            if section in _OPTIONAL_SECTIONS:
                continue
            raise _bad(source, f"missing table [{section}]")
        if section:
            for key in table:
                if (section, key) in _STRING_KEYS:
                    continue
                if key not in keys:
                    raise _bad(source, _unknown_key_msg(section, key))
        for key, (fname, *_rest) in keys.items():
            if key not in table and (section, key) in _OPTIONAL_KEYS:
                values[fname] = _OPTIONAL_KEYS[(section, key)]
                continue
            if key not in table:
                raise _bad(source, f"missing key {section + '.' if section else ''}{key}")
            values[fname] = table[key]
    if "adc" in doc:
        values["adc_bits"] = doc["adc"]["bits"]
    values["name"] = str(doc.get("name", Path(source).stem))
    values["description"] = str(doc.get("description", ""))
    demod = doc["demodulator"]
    values["demodulator_kind"] = demod.get("kind", "phase_sensitive")
    effects = doc.get("effects", {})
    if not isinstance(effects, dict):
        raise _bad(source, "effects must be a table of tables ([effects.NAME])")
    for name, params in effects.items():
        if not isinstance(params, dict):
            raise _bad(source, f"effects.{name} must be a table ([effects.{name}])")
        for pkey in params:
            if not _has_unit(pkey):
                raise _bad(source, f"effects.{name}.{pkey}: key has no unit suffix "
                                   f"(one of {', '.join(UNIT_SUFFIXES)})")
    filled = {}
    for name, params in effects.items():
        if name in SPECS:
            filled[name] = {**SPECS[name].defaults(), **params}
        else:
            filled[name] = dict(params)  # validate_effects names the unknown effect
    values["effects"] = filled
    return Sensor(**values)


def _unknown_key_msg(section: str, key: str) -> str:
    where = f"[{section}]" if section else "top level"
    label = f"{section}.{key}" if section else key
    allowed = sorted(list(_SCHEMA[section]) + [k for s, k in _STRING_KEYS if s == section])
    if not _has_unit(key):
        return (f"{label}: key has no unit suffix and is not known in {where} "
                f"(allowed: {', '.join(allowed)})")
    return f"unknown key {label} in {where} (allowed: {', '.join(allowed)})"


def parse_sensor(text: str, source: str = "<memory>") -> Sensor:
    return sensor_from_dict(parse_toml(text, source, SensorError), source)


def load_sensor(path: str | Path) -> Sensor:
    """Read and validate a sensor TOML file (raises SensorError with one clear line)."""
    return parse_sensor(read_text(path, SensorError, "a sensor TOML file"), str(path))


# The seed paper's LVDT.  Core, turns and excitation are the paper's; winding lengths, gap,
# core permeability and demodulator gain were calibrated to its Table 1 with
# ``flann simulate --fit data/paper_table1.csv``; former/housing diameters, resistances and
# the ADC are assumptions (docs/physics.md).  data/sensors/paper_lvdt.toml is the same
# sensor as a file (a test keeps the two equal).
PAPER_LVDT: dict[str, Any] = {
    "format": FORMAT,
    "name": "paper_lvdt",
    "description": "Misra et al. LVDT: core 4.4/5.0 mm x 60 mm, 1500/3300 turns, 5 kHz, 10 Vpp",
    "stroke_mm": 30.0,
    "core": {"inner_diameter_mm": 4.4, "outer_diameter_mm": 5.0, "length_mm": 60.0,
             "permeability_ratio": 220.0},
    "coil": {"inner_diameter_mm": 6.0, "outer_diameter_mm": 14.0,
             "housing_inner_diameter_mm": 20.0},
    "primary": {"turns": 1500, "length_mm": 0.9375, "resistance_ohm": 60.0},
    "secondary": {"turns": 3300, "length_mm": 23.25, "gap_mm": 13.14, "resistance_ohm": 200.0},
    "excitation": {"amplitude_vpp": 10.0, "frequency_hz": 5000.0},
    "demodulator": {"kind": "phase_sensitive", "gain_ratio": 2.272},
    "adc": {"bits": 16, "full_scale_v": 10.0},
}


def default_sensor() -> Sensor:
    """The seed paper's LVDT (calibrated winding geometry; see docs/physics.md)."""
    return sensor_from_dict(PAPER_LVDT, "default sensor (paper LVDT)")


def _fmt_value(v: Any) -> str:
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, int) and not isinstance(v, bool):
        return str(v)
    return repr(float(v))


def format_sensor(s: Sensor, comments: tuple[str, ...] = ()) -> str:
    """TOML text of ``s`` in the ``flann-sensor/1`` format."""
    lines = [f"# {c}" for c in comments]
    lines.append(f'format = "{FORMAT}"')
    lines.append(f"name = {_fmt_value(s.name)}")
    if s.description:
        lines.append(f"description = {_fmt_value(s.description)}")
    lines.append(f"stroke_mm = {_fmt_value(s.stroke_mm)}")
    for section, keys in _SCHEMA.items():
        if not section:
            continue
        if section == "adc" and s.adc_bits is None:
            continue
        lines.append("")
        lines.append(f"[{section}]")
        if section == "demodulator":
            lines.append(f"kind = {_fmt_value(s.demodulator_kind)}")
        for key, (fname, *_r) in keys.items():
            v = getattr(s, fname)
            if (section, key) in _OPTIONAL_KEYS and v == _OPTIONAL_KEYS[(section, key)]:
                continue
            if key in ("turns", "bits"):
                v = int(v) if float(v).is_integer() else v
            lines.append(f"{key} = {_fmt_value(v)}")
    for name, params in s.effects.items():
        lines.append("")
        lines.append(f"[effects.{name}]")
        for k, v in params.items():
            lines.append(f"{k} = {_fmt_value(v)}")
    return "\n".join(lines) + "\n"
