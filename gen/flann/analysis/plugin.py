"""What a datapath's folder offers analysis (``flann trace``, ``flann explore``).

A datapath folder under ``hardware/`` may hold an ``analysis.py`` (it belongs to the analysis
layer) defining ``INSIGHT``, one :class:`Insight`: its stage model for ``flann trace`` (one-input
designs), or its own trace (a design with temperature), how ``flann trace --hdl`` simulates a
model's design, and its design space for ``flann explore``.  A folder without ``analysis.py``
has none of these, and the commands say so in one line.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..verify.plugin import folder_module



@dataclass(frozen=True)
class Insight:
    stages: Callable | None = None     # (spec, codes | None) -> Stages: the stage model of a one-input design
    trace: Callable | None = None      # spec -> its own trace result (a design with temperature)
    hdl: Callable | None = None        # (model path, options, build_dir, stage codes, design model) -> (codes, mm, mismatches, top, stages)
    stage_capture: bool = False        # its bench also captures internal stages at chosen codes (trace --hdl)
    explore: Callable | None = None    # (model path, device, lanes, styles, **options) -> rows of flann explore


def insight(dp) -> Insight:
    """The analysis ``dp``'s folder offers (an empty one when it has no ``analysis.py``)."""
    module = folder_module(dp, "analysis")
    return Insight() if module is None else module.INSIGHT


def traced(design) -> Insight:
    """The analysis of ``design``'s datapath, or the one-line refusal when it has no stage model."""
    found = insight(design.datapath)
    if found.stages is None and found.trace is None:
        raise design.datapath.lacking(design.directory, "stage model for flann trace")
    return found


__all__ = ["Insight", "insight", "traced"]
