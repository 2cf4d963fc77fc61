"""Accuracy across temperature: the error at each recorded temperature and the drift figure.

* **by temperature**: rows grouped by temperature (:func:`.thermal.temperature_groups`);
  for each, ``max |e|`` and ``sqrt(mean e^2)`` with ``e = output - displacement`` (mm).
* **drift** (ppm of full scale per degC), the data-sheet box method applied at every
  position: the largest change of the error across the recorded temperatures, per degC of
  the temperatures' range::

      drift = max_x (max_T e_T(x) - min_T e_T(x)) / (T_max - T_min) / FS * 1e6

  where ``e_T(x)`` is the error at temperature T at position x (forward and reverse
  readings of one position averaged; positions one temperature lacks are interpolated
  linearly in its error curve, within its span; T_min and T_max are those of the
  temperatures holding x).  A constant offset common to all temperatures does not count:
  only what moves with temperature.  A linear drift gives its slope; the converter's steps
  and the readings' noise add at most their spread over the whole range (not over the
  closest pair of temperatures, which made a perfect compensator behind a 16-bit converter
  read 5-15 ppm FS/degC).  ``None`` when fewer than 2 temperatures have 2 positions each.
"""

from __future__ import annotations

import numpy as np

from .thermal import temperature_groups

MIN_POSITIONS_PER_TEMPERATURE = 2


def error_curves(error_mm, displacement_mm, temperature_c):
    """[(temperature, positions, mean error at each)] in rising temperature."""
    e = np.asarray(error_mm, dtype=float)
    x = np.asarray(displacement_mm, dtype=float)
    levels, labels = temperature_groups(temperature_c)
    curves = []
    for g, temp in enumerate(levels):
        rows = labels == g
        pos, inv = np.unique(np.round(x[rows], 9), return_inverse=True)
        mean = np.bincount(inv, weights=e[rows], minlength=pos.size) / np.bincount(inv, minlength=pos.size)
        curves.append((float(temp), pos, mean))
    return curves


def by_temperature(error_mm, temperature_c) -> list[dict]:
    e = np.asarray(error_mm, dtype=float)
    levels, labels = temperature_groups(temperature_c)
    out = []
    for g, temp in enumerate(levels):
        eg = e[labels == g]
        out.append({"temperature_c": float(round(temp, 6)), "points": int(eg.size),
                    "max_error_mm": float(np.max(np.abs(eg))),
                    "rms_error_mm": float(np.sqrt(np.mean(eg ** 2)))})
    return out


def drift_ppm_fs_per_c(error_mm, displacement_mm, temperature_c, fs_mm: float) -> float | None:
    curves = [c for c in error_curves(error_mm, displacement_mm, temperature_c)
              if c[1].size >= MIN_POSITIONS_PER_TEMPERATURE]
    if len(curves) < 2:
        return None
    at = np.unique(np.concatenate([pos for _, pos, _ in curves]))
    errors = np.full((len(curves), at.size), np.nan)
    temps = np.full((len(curves), at.size), np.nan)
    for k, (temp, pos, err) in enumerate(curves):
        inside = (at >= pos[0]) & (at <= pos[-1])
        errors[k, inside] = np.interp(at[inside], pos, err)
        temps[k, inside] = temp
    held = np.sum(np.isfinite(errors), axis=0) >= 2
    if not held.any():
        return None
    errors, temps = errors[:, held], temps[:, held]
    change = np.nanmax(errors, axis=0) - np.nanmin(errors, axis=0)
    span = np.nanmax(temps, axis=0) - np.nanmin(temps, axis=0)
    return float(np.max(change / span) / fs_mm * 1e6)


def temperature_report(errors: dict, displacement_mm, temperature_c, fs_mm: float) -> dict:
    """``{"by_temperature": {name: [...]}, "drift_ppm_fs_per_c": {name: value}}`` for each
    named error array (``raw``, ``float``, ``hardware``); a name whose errors are None gets
    None."""
    by, drift = {}, {}
    for name, err in errors.items():
        if err is None:
            by[name], drift[name] = None, None
            continue
        by[name] = by_temperature(err, temperature_c)
        drift[name] = drift_ppm_fs_per_c(err, displacement_mm, temperature_c, fs_mm)
    return {"by_temperature": by, "drift_ppm_fs_per_c": drift}


__all__ = ["by_temperature", "drift_ppm_fs_per_c", "error_curves", "temperature_report"]
