"""A formula sensor recorded at three temperatures, whose curve the simulation cannot follow
exactly: what the report says about its shape (the fitted curve with the named effects off
against the calibrated ideal simulation, never the shape term's own size), and no rail named
where the readings still rise."""

import re

import numpy as np
import pytest

from flann.diagnose import diagnose
from flann.diagnose.data import reduce_points
from flann.diagnose.report import format_text
from flann.recordings import Recordings


def formula_sensor_at_three_temperatures(seed: int = 0, widening: float = 2e-4) -> Recordings:
    """A tanh sensor out and back at -20, 25 and 80 degC: its gain falls 0.025 %/degC and
    its curve widens by ``widening`` per degC; 1 mV noise, 16 bits over +-10 V."""
    rng = np.random.default_rng(seed)
    xs = np.arange(-30, 30.0001, 0.5)
    x, d, t = [], [], []
    for temp in (-20.0, 25.0, 80.0):
        for sign, pas in ((1.0, xs), (-1.0, xs[::-1])):
            x.append(pas)
            d.append(np.full(pas.size, sign))
            t.append(np.full(pas.size, temp))
    x, d, t = map(np.concatenate, (x, d, t))
    v = ((5.3 * np.tanh(x / (24 * (1 + widening * (t - 25)))) * (1 - 0.01 * x / 30) - 0.001)
         * (1 - 2.5e-4 * (t - 25)) - 2e-5 * (t - 25) + rng.normal(0, 1e-3, x.size))
    lsb = 20 / 65536
    v = np.clip(np.round(v / lsb) * lsb, -10, 10 - lsb)
    return Recordings(displacement_mm=x, voltage_v=v, direction=d, temperature_c=t)


@pytest.fixture(scope="module")
def thermal():
    return diagnose(formula_sensor_at_three_temperatures())


def test_shape_is_the_curve_not_the_term(thermal):
    sd = thermal.shape_description
    # the curve beside the named effects is within a few mV of the calibrated simulation
    # (the shape term once took volts back off a doubled gain)
    assert sd["terms"] > 0
    assert sd["rms_v"] < 0.005 and sd["peak_v"] < 0.01
    assert sd["rms_v"] < thermal.ideal_rms
    text = format_text(thermal).splitlines()
    line = next(s for s in text if s.startswith("shape of this sensor"))
    assert "differs from the calibrated ideal simulation by" in line


def test_thermal_drift_is_quoted_of_the_recorded_output(thermal):
    (effect,) = [e for e in thermal.effects if e.name == "thermal_drift"]
    m = re.search(r"drifts by ([-+0-9.e]+) %/degC", effect.explanation)
    # the recorded gain falls 0.025 %/degC, and the widening lowers the slope further
    # near the null: between the two
    assert -0.045 <= float(m.group(1)) <= -0.025


@pytest.mark.parametrize("points", [250, None], ids=["bin-means", "every-point"])
def test_no_rail_where_the_readings_still_rise(points):
    # a curve widening 0.1 %/degC: the simulation overshoots its ends, and a "rail" cutting
    # it off lowered BIC (named on the 250 bin means flann calibrate diagnoses, and on all
    # 726 points) although the last readings still rise: 4.526 -> 4.556 -> 4.585 V at -20 degC
    rec = formula_sensor_at_three_temperatures(widening=1e-3)
    end = rec.voltage_v[(rec.temperature_c == -20) & (rec.direction > 0)][-3:]
    assert np.all(np.diff(end) > 0.02)
    rec, _ = reduce_points(rec, points)
    dg = diagnose(rec)
    assert "adc_clipping" not in dg.named
    assert "thermal_drift" in dg.named
    vetoed = [t for rnd in dg.trials for t in rnd if t.name == "adc_clipping" and t.vetoed]
    assert vetoed and all("rail" in t.note for t in vetoed)
    assert "adc_clipping" not in {c for s in dg.explanations for c in s}
