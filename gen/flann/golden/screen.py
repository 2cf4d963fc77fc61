"""Recordings made ready for a fit by the one shared reading (:mod:`flann.golden.reading`):
the rule of ``flann train``, a family's members (``flann gen --family``) and ``flann calibrate``.
"""

from __future__ import annotations

from .reading import read_usable


def ready_for_fit(raw, outliers: str | None = None) -> tuple[object, str]:
    """(the readings kept, what was left out in one sentence or '')."""
    reading = read_usable(raw, outliers)
    return reading.rec, "; ".join(reading.said)


__all__ = ["ready_for_fit"]
