"""``flann calibrate`` on a family design with temperature: one sensor's check at every
calibration temperature (no HDL simulation: the design's twin stands for it).

1. train x = sum_j t_n^j f_j(v) with the design's temperature normalisation and terms
   (:func:`flann.hardware.family_thermal.build.fit_sensor`), the least ridge whose orders fit
   the design's formats;
2. quantise into the image (every order's memory) and check the twin holding it against the
   float model over every voltage code at the calibrated temperature codes' ends, middle and
   the recording's own temperatures;
3. the recording through the hardware: each row's voltage code and temperature code into
   the twin; the error, by temperature, and the drift figure ``drift_ppm_fs_per_c`` (the
   box method at every position: the largest change of the error across the calibration
   temperatures per degC of their range, in ppm of full scale, half the recorded span, as ``flann eval --json`` reports it:
   :func:`flann.golden.thermal_metrics.drift_ppm_fs_per_c`), for the hardware
   and the raw sensor (its one least-squares line over every temperature).
"""

from __future__ import annotations

import numpy as np

from ..golden.metrics import full_scale_mm, raw_output_mm
from ..golden.thermal import temperature_groups
from ..golden.thermal_metrics import by_temperature, drift_ppm_fs_per_c
from ..hardware.accuracy import adc_codes, physical_limit_mm, temperature_codes
from ..hardware.family.spec import FitError
from ..hardware.family_thermal.build import fit_sensor
from ..hardware.family_thermal.spec import FamilyThermalSpec
from ..hardware.family_thermal.twin import FlannFamilyThermalTop, encode_image
from .verdict import require_positions


def train_for_design(rec, spec: FamilyThermalSpec, ridges):
    """(model, image words): the least of ``ridges`` whose every order fits the design's formats."""
    last = None
    for ridge in ridges:
        model = fit_sensor(rec, spec.temp, spec.fam.terms, spec.orders, ridge)
        try:
            return model, encode_image(spec, model)
        except FitError as exc:
            last = exc
    raise last


def check_sensor_thermal(rec, spec: FamilyThermalSpec, ridges) -> dict:
    """Train (``ridges`` tried in order), quantise and check one sensor's multi-temperature
    recordings (see the module doc)."""
    levels, labels = temperature_groups(rec.temperature_c)
    for k, level in enumerate(levels):
        require_positions(np.asarray(rec.displacement_mm)[labels == k], spec.fam.terms, f" at {level:g} °C")
    model, words = train_for_design(rec, spec, ridges)
    twin = FlannFamilyThermalTop(spec, words)
    levels, labels = temperature_groups(rec.temperature_c)
    tcodes = temperature_codes(spec, rec.temperature_c)
    check_codes = sorted({spec.temp.lo, spec.temp.mid, spec.temp.hi, *temperature_codes(spec, levels).tolist()})
    twin_err = twin.error_vs_float(temp_codes=check_codes, model=model)["max_err_lsb"]
    s = spec.fam.spec
    q, lsb = spec.output_lsb_mm, s.input_lsb_v
    v, x, t = rec.voltage_v, rec.displacement_mm, np.asarray(rec.temperature_c, dtype=float)
    r = twin.process(adc_codes(spec, v), tcodes)
    err = r.out_data * q - x
    raw_err = raw_output_mm(v, x) - x
    limit = physical_limit_mm(model, v, lsb, t)
    fs = full_scale_mm(x)   # flann eval's full scale (half the span): one drift figure
    return {"model": model, "words": words, "twin_err_lsb": twin_err, "bound_lsb": float(spec.analysis["bound_lsb"]),
            "hw_err_mm": err, "raw_err_mm": raw_err, "limit_mm": limit, "rec": rec, "temperature_c": t,
            "temperatures_c": [float(a) for a in levels], "labels": labels, "full_scale_mm": fs,
            "by_temperature": by_temperature(err, t), "raw_by_temperature": by_temperature(raw_err, t),
            "drift_ppm_fs_per_c": drift_ppm_fs_per_c(err, x, t, fs),
            "raw_drift_ppm_fs_per_c": drift_ppm_fs_per_c(raw_err, x, t, fs),
            "temperature_checked_codes": check_codes}


__all__ = ["check_sensor_thermal", "train_for_design", "temperature_codes"]
