"""Every metric against values worked out by hand; the paper's raw 15.38 % on Table 1."""

import math

import numpy as np
import pytest

from flann.golden.metrics import (error_report, full_scale_mm, linearity_pct, raw_line,
                           raw_linearity_pct, stroke_fraction_within, stroke_weights)
from flann.recordings import read_recordings

X = np.array([-10.0, 0.0, 10.0])
Y = np.array([-9.0, 0.3, 10.5])         # errors +1, +0.3, +0.5 mm


def test_full_scale_is_half_the_span():
    assert full_scale_mm(X) == 10.0
    assert full_scale_mm([-30, 30]) == 30.0


def test_error_figures_by_hand():
    r = error_report(Y, X, tol_pct_fs=5.0, band_pct_fs=4.0)
    assert r["max_error_mm"] == pytest.approx(1.0)
    assert r["rms_error_mm"] == pytest.approx(math.sqrt((1 + 0.09 + 0.25) / 3))
    assert r["max_error_pct_fs"] == pytest.approx(10.0)
    assert r["rms_error_pct_fs"] == pytest.approx(10 * math.sqrt(1.34 / 3))
    # tol 5 % of 10 mm = 0.5 mm: 0.3 and 0.5 (on the boundary) are linear -> 2 of 3
    assert r["linearity_pct"] == pytest.approx(200 / 3)
    # band 4 % FS = 0.4 mm: only the middle point, which stands for 10 of the 20 mm
    assert r["stroke_fraction_within_band"] == pytest.approx(0.5)


def test_stroke_weights_uneven_sampling_by_hand():
    # x = 0, 1, 4: halves of the gaps 1 and 3 -> 0.5, 0.5 + 1.5, 1.5
    np.testing.assert_allclose(stroke_weights([4.0, 0.0, 1.0]), [1.5, 0.5, 2.0])
    # only x = 4 within the band -> 1.5 / 4
    out = np.array([4.0, 0.0 + 9, 1.0 + 9])
    assert stroke_fraction_within(out, [4.0, 0.0, 1.0], band_pct_fs=1.0) == pytest.approx(0.375)


def test_stroke_fraction_averages_the_two_sweeps():
    x = np.array([0.0, 1.0, 2.0, 0.0, 1.0, 2.0])
    out = x + np.array([0, 0, 0, 5, 5, 0])     # sweep 2: only x = 2 (weight 0.5 of 2) ok
    d = np.array([1, 1, 1, -1, -1, -1])
    assert stroke_fraction_within(out, x, 1.0, direction=d) == pytest.approx((1 + 0.25) / 2)


def test_stroke_fraction_does_not_depend_on_row_order_or_the_direction_column():
    """Repeated positions share their stretch of the stroke: the rows reversed, shuffled or
    without their direction column give the same fraction (by hand: sweep 1 has x = 0, 1
    within the band (weights 0.5, 1 of 2), sweep 2 only x = 1: (1.5 + 1) / 2 / 2)."""
    x = np.array([0.0, 1.0, 2.0, 2.0, 1.0, 0.0])
    out = x + np.array([0, 0, 5, 5, 0, 5])
    d = np.array([1, 1, 1, -1, -1, -1])
    want = (1.5 / 2 + 1 / 2) / 2
    for order in (np.arange(6), np.arange(6)[::-1], np.array([3, 0, 5, 1, 4, 2])):
        assert stroke_fraction_within(out[order], x[order], 1.0, direction=d[order]) == pytest.approx(want)
        assert stroke_fraction_within(out[order], x[order], 1.0) == pytest.approx(want)
    np.testing.assert_allclose(stroke_weights([2.0, 0.0, 2.0]), [0.5, 1.0, 0.5])


def test_raw_line_and_linearity_by_hand():
    v = np.array([0.0, 1.0, 2.0, 3.0])
    x = np.array([0.0, 1.0, 2.0, 4.0])
    # Sxy = 6.5, Sxx = 5 -> a = 1.3, b = 1.75 - 1.3 * 1.5 = -0.2; errors -0.2, 0.1, 0.4, -0.3
    assert raw_line(v, x) == pytest.approx((1.3, -0.2))
    # FS = 2 mm; tol 12 % = 0.24 mm -> 2 of 4; 16 % = 0.32 mm -> 3 of 4
    assert raw_linearity_pct(v, x, 12.0) == pytest.approx(50.0)
    assert raw_linearity_pct(v, x, 16.0) == pytest.approx(75.0)


def test_compensated_linearity_is_against_y_equals_x():
    assert linearity_pct(X + 0.1, X, 2.0) == 100.0      # offset 0.1 mm < 0.2 mm tol
    assert linearity_pct(X * 1.05, X, 2.0) == pytest.approx(100 / 3)   # gain error


def test_paper_raw_sensor_gives_15_38_percent():
    rec = read_recordings("data/paper_table1.csv")
    assert round(raw_linearity_pct(rec.voltage_v, rec.displacement_mm), 2) == 15.38
