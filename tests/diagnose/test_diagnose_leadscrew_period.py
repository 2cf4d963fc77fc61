"""A lead screw is named only with a period in its range (a few steps of one direction to 1/8 of
the stroke): beyond it a sinusoid draws a smooth warp of the axis, the shape term's job."""

import numpy as np
import pytest

from flann.diagnose import diagnose
from flann.diagnose.model import Data, PhysicsFamily
from flann.diagnose.select import BIC_MARGIN, Fit
from flann.physics.sensor import default_sensor
from flann.recordings import Recordings

NAMES = ["baseline.gain_ratio", "leadscrew_periodic.amplitude_mm", "leadscrew_periodic.period_mm",
         "leadscrew_periodic.phase_rad"]


def test_a_period_outside_its_range_is_vetoed_and_one_inside_is_not():
    x = np.linspace(-6.0, 6.0, 61)
    data = Data(x=np.r_[x, x[::-1]], y=np.tanh(np.r_[x, x[::-1]] / 4),
                direction=np.repeat([1.0, -1.0], x.size), temperature_c=None, time_s=None)
    fam = PhysicsFamily(default_sensor(), data, origin_known=True, shape=None, gain0=2.0, origin0=0.0)
    idx = np.arange(data.x.size)
    spec = fam.specs_by_name(["leadscrew_periodic"])["leadscrew_periodic.period_mm"]
    assert 0 < spec.lower < spec.upper

    def fit(period):
        return Fit(("leadscrew_periodic",), NAMES, np.array([2.0, 0.01, period, 0.3]), np.zeros(4),
                   np.zeros(idx.size), idx)

    assert fam.implausible("leadscrew_periodic", fit(0.5 * (spec.lower + spec.upper)), idx) == ""
    for period in (1.5 * spec.upper, 0.5 * spec.lower):
        assert fam.implausible("leadscrew_periodic", fit(period), idx)


@pytest.fixture(scope="module")
def asymmetric_s_curve():
    """An S-curve whose gain differs by 0.9 % on the two sides of the null (no lead screw):
    2,000 readings out and back on a 14-bit converter, diagnosed on 250 bin means as the line
    does (bench/bench_line_rate.py's third sensor).  Its lead-screw fit ran to a 5 mm period
    on a 20 mm stroke, 240 BIC better than without."""
    x = np.linspace(-10.0, 10.0, 1000)
    xs = np.r_[x, x[::-1]]
    u = xs / 7.0
    asym = -0.004600413061645461
    v = 2.993549435603146 * np.where(u >= 0, 1 + asym, 1 - asym) * u / (1 + np.abs(u) ** 2.5) ** 0.4
    lsb = 7.2 / 2 ** 14
    v = np.round((v + np.random.default_rng(2).normal(0, 0.5e-3, xs.size)) / lsb) * lsb
    rec = Recordings(displacement_mm=xs, voltage_v=v, direction=np.repeat([1.0, -1.0], x.size))
    return diagnose(rec, max_points=250)


def test_a_warp_of_the_axis_is_not_named_a_lead_screw(asymmetric_s_curve):
    dg = asymmetric_s_curve
    assert "leadscrew_periodic" not in dg.named
    assert all("leadscrew_periodic" not in alt for alt in dg.alternatives)
    # every lead-screw fit that BIC would have taken is set aside with the reason
    strong = [t for step in dg.trials for t in step
              if t.name == "leadscrew_periodic" and t.delta_bic < -BIC_MARGIN]
    assert all(t.vetoed for t in strong)
