"""Gross outliers left out of a recording before a fit: the one rule of ``flann train
--terms auto``, a family's members (``flann gen --family``) and ``flann calibrate``.

A reading is left out when it is further from the smooth fit of the others than
``OUTLIER_K`` robust noise units (:func:`flann.golden.forward.screen_outliers`); more than
``MAX_OUTLIER_SHARE`` of such readings is not a glitch but a bad recording, refused.
"""

from __future__ import annotations

import numpy as np

from ..errors import FlannError
from ..recordings import converter_step, prepare_for_fit
from .forward import MAX_OUTLIER_SHARE, OUTLIER_K, OutlierShareError, screen_outliers, screens


def screen_recording(rec, step_v: float) -> tuple[object, dict, str]:
    """(the readings kept, the training record's entries, one sentence naming the outliers
    left out or ''); refused (FlannError) above the stated share.  ``step_v``: the converter's
    step (the noise is at least its quantisation)."""
    try:
        sc = screen_outliers(rec.displacement_mm, rec.voltage_v, rec.direction, step_v)
    except OutlierShareError as exc:
        raise FlannError(
            f"{rec.source}: {exc.n_out} of {exc.n} readings are more than {OUTLIER_K:g} noise units "
            f"from the smooth fit of the others (more than {100 * MAX_OUTLIER_SHARE:g} % are refused): "
            f"worst {rec.line_of(exc.row)}, {exc.units:.3g} noise units (noise {exc.sigma:.3g} V); "
            "not isolated glitches: look at the recording (flann diagnose)") from None
    if sc is None:   # too few or too many positions to judge outliers: every reading is used
        return rec, {"positions_used": int(np.unique(rec.displacement_mm).size), "readings_used": len(rec),
                     "outliers_checked": False}, ""
    record = {"positions_used": sc.positions, "readings_used": int(sc.keep.sum()),
              "noise_v": float(f"{sc.noise_v:.4g}"), "noise_from": sc.noise_from}
    said = ""
    if sc.outliers:
        record["outliers_left_out"] = [{"line": rec.line_of(i), "noise_units": round(u, 1)}
                                       for i, u in sc.outliers]
        listed = ", ".join(f"{rec.line_of(i)} ({u:.3g} noise units)" for i, u in sc.outliers[:5])
        more = f" and {len(sc.outliers) - 5} more" if len(sc.outliers) > 5 else ""
        said = (f"{rec.source}: left out {len(sc.outliers)} gross outlier reading(s) of {len(rec)}: "
                f"{listed}{more} (noise {sc.noise_v:.3g} V, {sc.noise_from})")
        rec = rec.subset(sc.keep)
    return rec, record, said


def ready_for_fit(raw) -> tuple[object, str]:
    """Recordings validated for a fit (:func:`flann.recordings.prepare_for_fit`, a glitch among
    repeats left to the screen) and screened: (the readings kept, the sentence naming the
    outliers left out or '')."""
    rec = prepare_for_fit(raw, can_trim=False, lone_glitches=screens(raw.displacement_mm))
    rec, _record, said = screen_recording(rec, converter_step(rec.voltage_v))
    return rec, said


__all__ = ["screen_recording", "ready_for_fit"]
