"""What every bit-true twin offers, whatever its datapath.

A twin has the name of the VHDL entity it mirrors (``entity``), its latency in clock
cycles where it is fixed (``latency``), and ``process(...)`` returning a record whose
fields are named after the entity's output ports (``out_data``, ``out_sat``, ...), plus
the internal values a test bench or ``flann trace`` compares stage by stage.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


class Record:
    """Base of twin outputs.  ``rec["theta"]`` reads ``rec.out_theta``: benches index the
    records by the stage's short name; ``ALIASES`` maps names that are not ``out_`` + name."""

    ALIASES: dict = {}

    def __getitem__(self, key: str):
        key = self.ALIASES.get(key, key)
        return getattr(self, key) if hasattr(self, key) else getattr(self, "out_" + key)


@dataclass(frozen=True)
class TopOut(Record):
    """Output ports of a top-level entity; unpacks (and indexes) as ``out_data, out_sat``."""

    out_data: np.ndarray
    out_sat: np.ndarray

    ALIASES = {"out": "out_data", "sat": "out_sat"}

    def __iter__(self):
        return iter((self.out_data, self.out_sat))

    def __getitem__(self, key):
        return (self.out_data, self.out_sat)[key] if isinstance(key, int) else super().__getitem__(key)


__all__ = ["Record", "TopOut"]
