"""The family datapath's analysis: its stage model is the fixed datapath's, of the design with
its memory as initialised."""

from __future__ import annotations

from ...analysis.plugin import Insight
from ...analysis.trace import Stages
from ..fixed.analysis import stages as fixed_stages
from .twin import FlannFamilyTop


def stages(fam, codes=None) -> Stages:
    """The family design with its memory as initialised: the fixed datapath's stages of those values."""
    return fixed_stages(FlannFamilyTop(fam).top().spec, codes)




INSIGHT = Insight(stages=stages)

__all__ = ["INSIGHT", "stages"]
