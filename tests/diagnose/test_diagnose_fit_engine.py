"""The diagnosis' fitting engine: its cached simulations are the simulator's own numbers (at its
fixed geometry, through the magnetics table), and a
lead-screw phase the fit winds past the catalogue's range is the same phase, not a failure."""

import math

import numpy as np
import pytest

from flann.diagnose.model import Data, PhysicsFamily
from flann.physics.lvdt import tabulated
from flann.physics.sensor import default_sensor
from flann.physics.simulate import simulate_output_v


def _family(sensor):
    x = np.linspace(-6.0, 6.0, 41)
    x = np.concatenate([x, x[::-1]])
    direction = np.repeat([1.0, -1.0], 41)
    data = Data(x=x, y=np.tanh(x / 4), direction=direction, temperature_c=None, time_s=None)
    return PhysicsFamily(sensor, data, origin_known=True, shape=None, gain0=2.0, origin0=0.0)


IMBALANCE = {"secondary_imbalance": {"imbalance_fraction": 0.03}}
SHIFTED = {"zero_shift": {"shift_mm": 0.4}, "backlash": {"deadband_mm": 0.05}}
QUADRATURE = {"quadrature_null": {"quadrature_v": 0.02}}


@pytest.mark.parametrize("kind, inner", [("phase_sensitive", IMBALANCE), ("amplitude", SHIFTED),
                                         ("amplitude", QUADRATURE)])
def test_a_cached_simulation_is_the_simulators_own_at_every_gain(kind, inner):
    sensor = default_sensor().replace(demodulator_kind=kind)
    fam = _family(sensor)
    idx = np.arange(fam.data.x.size)
    core = fam.data.x[idx].copy()
    for gain in (2.0, -3.5, 2.0, 7.25):    # a repeated gain is answered from the cache
        with tabulated():
            want = simulate_output_v(sensor.replace(demodulator_gain_ratio=gain, effects=inner), core,
                                     direction=fam.data.direction)
        got = fam._simulate(gain, inner, idx, core)
        assert np.array_equal(got, want), (kind, gain, float(np.max(np.abs(got - want))))


def test_a_phase_wound_past_the_catalogues_range_is_the_same_phase():
    fam = _family(default_sensor())
    idx = np.arange(fam.data.x.size)
    names = ["baseline.gain_ratio", "leadscrew_periodic.amplitude_mm",
             "leadscrew_periodic.period_mm", "leadscrew_periodic.phase_rad"]
    wound = np.array([2.0, 0.05, 1.7, -1338.45])
    turns = round(wound[3] / (2 * math.pi))
    unwound = wound.copy()
    unwound[3] -= 2 * math.pi * turns
    assert abs(unwound[3]) <= math.pi
    y_wound = fam.evaluate(wound, names, idx)
    y_unwound = fam.evaluate(unwound, names, idx)
    np.testing.assert_allclose(y_wound, y_unwound, rtol=0, atol=1e-9)
    # within the range the phase is left as the fit has it
    inside = np.array([2.0, 0.05, 1.7, 5.0])
    assert fam._physical(inside, names)[3] == 5.0
