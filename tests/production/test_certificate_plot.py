"""The certificate's error plot keeps every point clear of its frame."""

from __future__ import annotations

import re
from types import SimpleNamespace

import numpy as np

from flann.production import plot


def test_the_worst_point_at_the_stroke_end_is_not_drawn_on_the_frame():
    """The certificate's max error (the verdict's figure) sat at +20 mm, the last tick: it was
    drawn on the right frame line, and so was a peak at a y tick on the top one, hidden by
    them.  Every point is now inside the frame by a margin."""
    x = np.linspace(-20, 20, 161)
    hw = 0.02 * np.sin(x)
    hw[-1] = 0.07                                  # the worst error, at the end, at a round value
    chk = {"rec": SimpleNamespace(displacement_mm=x), "raw_err_mm": 0.5 * (x / 20) ** 3,
           "hw_err_mm": hw, "limit_mm": np.full(x.size, 0.01)}
    svg = plot.error_plot_svg(chk, "s1")
    inner = plot.WIDTH - plot.RIGHT - plot.LEFT
    for points in re.findall(r'<polyline[^>]* points="([^"]+)"', svg):
        xy = np.array([[float(c) for c in p.split(",")] for p in points.split()])
        assert xy[:, 0].min() >= plot.LEFT + 0.01 * inner and xy[:, 0].max() <= plot.WIDTH - plot.RIGHT - 0.01 * inner
        # inside one of the two panels, not on a panel's top or bottom line
        tops = (plot.TOP, plot.TOP + plot.PANEL_H + plot.GAP)
        top = max(t for t in tops if t <= xy[:, 1].min())
        assert top + 1 < xy[:, 1].min() and xy[:, 1].max() < top + plot.PANEL_H - 1
