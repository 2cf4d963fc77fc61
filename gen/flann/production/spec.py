"""The production specification a sensor is judged against (``--spec SPEC.toml`` or flags).

A spec file (every key optional except one tolerance)::

    name = "LVDT-20, line A"
    [tolerance]
    max_error_mm = 0.05            # or max_error_pct_fs = 0.25 (of the full scale, below)
    working_range_mm = [-8, 8]     # judged over this range; default: the whole stroke
    [limits]
    max_ratio_to_limit = 100       # compensated max error / physical limit
    fail_on_effects = ["adc_clipping", "backlash"]   # the diagnosis must not name these

Full scale (FS) is half the span of the working range, or of the recording's displacement when
no range is stated: a +-10 mm stroke has a 10 mm FS, as in ``flann eval``.  Flags override the
file's values one by one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

from ..errors import FlannError
from ..inputs import parse_toml, read_text
from ..physics.effects import EFFECTS

SPEC_KEYS = {"": {"name", "tolerance", "limits"},
             "tolerance": {"max_error_mm", "max_error_pct_fs", "working_range_mm"},
             "limits": {"max_ratio_to_limit", "fail_on_effects"}}


@dataclass(frozen=True)
class ProductionSpec:
    name: str = ""
    source: str = ""                               # the file, or "flags"
    max_error_mm: float | None = None
    max_error_pct_fs: float | None = None
    working_range_mm: tuple[float, float] | None = None
    max_ratio_to_limit: float | None = None
    fail_on_effects: tuple[str, ...] = ()

    @property
    def judges(self) -> bool:
        """Whether anything is judged beyond the calibration itself."""
        return any(v is not None for v in (self.max_error_mm, self.max_error_pct_fs,
                                            self.max_ratio_to_limit)) or bool(self.fail_on_effects)

    def tolerance_text(self) -> str:
        """The tolerance as one cell: "0.05 mm over -8..8 mm", "0.25 % FS over the stroke"."""
        parts = []
        where = (f" over {self.working_range_mm[0]:g}..{self.working_range_mm[1]:g} mm"
                 if self.working_range_mm else " over the recorded stroke")
        if self.max_error_mm is not None:
            parts.append(f"max error <= {self.max_error_mm:g} mm{where}")
        if self.max_error_pct_fs is not None:
            parts.append(f"max error <= {self.max_error_pct_fs:g} % FS{where}")
        if self.max_ratio_to_limit is not None:
            parts.append(f"ratio to the physical limit <= {self.max_ratio_to_limit:g}")
        if self.fail_on_effects:
            parts.append("diagnosis names none of " + ", ".join(self.fail_on_effects))
        return "; ".join(parts) if parts else "none (no specification given)"


def _number(value, what: str, positive: bool = True) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise FlannError(f"{what}: {value!r} is not a finite number")
    if positive and value <= 0:
        raise FlannError(f"{what}: {value!r} must be > 0")
    return float(value)


def _range(value, what: str) -> tuple[float, float]:
    if isinstance(value, str):
        lo, sep, hi = value.partition(":")
        if not sep:
            raise FlannError(f"{what}: {value!r} is not LO:HI (mm)")
        try:
            value = [float(lo), float(hi)]
        except ValueError:
            raise FlannError(f"{what}: {value!r} is not LO:HI (mm)") from None
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise FlannError(f"{what}: {value!r} must be two numbers [low, high] in mm")
    lo, hi = (_number(v, what, positive=False) for v in value)
    if not lo < hi:
        raise FlannError(f"{what}: low {lo:g} must be below high {hi:g}")
    return lo, hi


def _effects(value, what: str) -> tuple[str, ...]:
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
        raise FlannError(f"{what}: {value!r} must be a list of effect names")
    unknown = [v for v in value if v not in EFFECTS]
    if unknown:
        raise FlannError(f"{what}: unknown effect(s) {', '.join(unknown)}; known: "
                         f"{', '.join(EFFECTS)}")
    return tuple(dict.fromkeys(value))


def _check(spec: ProductionSpec, what: str) -> ProductionSpec:
    if spec.max_error_mm is not None and spec.max_error_pct_fs is not None:
        raise FlannError(f"{what}: give the tolerance in mm or in % FS, not both")
    return spec


def load_spec(path) -> ProductionSpec:
    """A spec file (TOML, keys as in the module's docstring); one-line errors name the key."""
    path = Path(path)
    raw = parse_toml(read_text(path, FlannError, "a production spec (TOML)"), str(path), FlannError)
    for table, keys in SPEC_KEYS.items():
        sub = raw if not table else raw.get(table, {})
        if not isinstance(sub, dict):
            raise FlannError(f"{path}: [{table}] must be a table")
        unknown = sorted(set(sub) - keys)
        if unknown:
            where = f"[{table}] " if table else ""
            raise FlannError(f"{path}: {where}unknown key(s) {', '.join(unknown)}; known: "
                             f"{', '.join(sorted(keys))}")
    tol, lim = raw.get("tolerance", {}), raw.get("limits", {})
    name = raw.get("name", path.stem)
    if not isinstance(name, str):
        raise FlannError(f"{path}: name must be a string")
    spec = ProductionSpec(
        name=name, source=str(path),
        max_error_mm=None if "max_error_mm" not in tol else
        _number(tol["max_error_mm"], f"{path}: tolerance.max_error_mm"),
        max_error_pct_fs=None if "max_error_pct_fs" not in tol else
        _number(tol["max_error_pct_fs"], f"{path}: tolerance.max_error_pct_fs"),
        working_range_mm=None if "working_range_mm" not in tol else
        _range(tol["working_range_mm"], f"{path}: tolerance.working_range_mm"),
        max_ratio_to_limit=None if "max_ratio_to_limit" not in lim else
        _number(lim["max_ratio_to_limit"], f"{path}: limits.max_ratio_to_limit"),
        fail_on_effects=_effects(lim.get("fail_on_effects", []), f"{path}: limits.fail_on_effects"))
    return _check(spec, str(path))


def build_spec(spec_path=None, *, max_error_mm=None, max_error_pct_fs=None, working_range=None,
               max_ratio_to_limit=None, fail_on_effects=()) -> ProductionSpec:
    """The spec file (if any) with the flags given on top of it."""
    spec = load_spec(spec_path) if spec_path else ProductionSpec(name="", source="")
    changes = {}
    if max_error_mm is not None:
        changes.update(max_error_mm=_number(max_error_mm, "--tolerance-mm"), max_error_pct_fs=None)
    if max_error_pct_fs is not None:
        changes.update(max_error_pct_fs=_number(max_error_pct_fs, "--tolerance-pct-fs"),
                       max_error_mm=None)
    if max_error_mm is not None and max_error_pct_fs is not None:
        raise FlannError("--tolerance-mm and --tolerance-pct-fs: give one of them")
    if working_range is not None:
        changes["working_range_mm"] = _range(working_range, "--working-range")
    if max_ratio_to_limit is not None:
        changes["max_ratio_to_limit"] = _number(max_ratio_to_limit, "--max-ratio-to-limit")
    if fail_on_effects:
        changes["fail_on_effects"] = _effects(list(fail_on_effects), "--fail-on-effect")
    if changes:
        changes["source"] = f"{spec.source} + flags" if spec.source else "flags"
    spec = _check(replace(spec, **changes), "spec")
    if spec_path and spec.max_error_mm is None and spec.max_error_pct_fs is None:
        # a spec that states no tolerance would pass every sensor while looking like a spec
        raise FlannError(f"{spec_path}: states no tolerance: give [tolerance] max_error_mm or "
                         "max_error_pct_fs (or --tolerance-mm / --tolerance-pct-fs)")
    return spec


__all__ = ["ProductionSpec", "load_spec", "build_spec"]
