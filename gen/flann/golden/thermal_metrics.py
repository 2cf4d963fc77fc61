"""Accuracy across temperature: the error at each recorded temperature and the drift figure.

* **by temperature**: rows grouped by temperature (:func:`.thermal.temperature_groups`);
  for each, ``max |e|`` and ``sqrt(mean e^2)`` with ``e = output - displacement`` (mm).
* **drift** (ppm of full scale per degC): the largest change of the error between two
  recorded temperatures, per degC of their difference, over every pair of temperatures and
  every position both hold::

      drift = max_{a, b} max_x |e_a(x) - e_b(x)| / |T_a - T_b| / FS * 1e6

  where ``e_T(x)`` is the error at temperature T at position x (forward and reverse
  readings of one position averaged; positions one temperature lacks are interpolated
  linearly in its error curve, within its span).  A constant offset common to all
  temperatures does not count: only what moves with temperature.  Noise in the readings
  adds to it (twice the noise over the closest pair's temperature difference): judge it on
  quiet or dense sweeps.  ``None`` when fewer than 2 temperatures have 2 positions each.
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
    worst = None
    for i, (ta, xa, ea) in enumerate(curves):
        for tb, xb, eb in curves[i + 1:]:
            inside = (xa >= xb[0]) & (xa <= xb[-1])
            if not inside.any():
                continue
            change = np.max(np.abs(ea[inside] - np.interp(xa[inside], xb, eb)))
            rate = float(change / abs(tb - ta) / fs_mm * 1e6)
            worst = rate if worst is None else max(worst, rate)
    return worst


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
