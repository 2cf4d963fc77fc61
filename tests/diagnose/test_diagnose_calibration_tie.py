"""Two geometries that draw the same curve: the calibration keeps the one nearest the sensor
description's, whichever the noise made cheaper, and never one that fits clearly worse."""

import numpy as np

from flann.diagnose.calibrate import GEOMETRY_FIELDS, _reproducible
from flann.physics.lvdt import ideal_output_v
from flann.physics.sensor import default_sensor

G0 = np.array([getattr(default_sensor(), f) for f in GEOMETRY_FIELDS])


def _solutions(noise_seed: int):
    s = default_sensor()
    x = np.linspace(-8, 8, 200)
    y = ideal_output_v(s, x) + np.random.default_rng(noise_seed).normal(0, 0.004, x.size)
    near, far = G0 * 1.1, G0 * 2.0
    # the same curve under two geometry labels (the sensor is what the residuals come from),
    # the far one the cheaper; and the description's own geometry at a clearly worse gain
    same = (s, near, s.demodulator_gain_ratio, 0.0, 1, 1.0)
    cheaper = (s, far, s.demodulator_gain_ratio, 0.0, 1, 0.9)
    worse = (s, G0, 1.05 * s.demodulator_gain_ratio, 0.0, 1, 2.0)
    return [(1.0, worse), (1.0, cheaper), (1.0, same)], x, y


def test_alike_geometries_resolve_to_the_description_s_neighbour():
    for seed in (1, 2):
        solutions, x, y = _solutions(seed)
        k, out = _reproducible(solutions, x, y, G0)
        assert np.allclose(out[1], G0 * 1.1), out[1]


def test_a_clearly_worse_fit_is_not_kept_for_its_geometry():
    solutions, x, y = _solutions(3)
    _, out = _reproducible(solutions, x, y, G0)
    assert not np.allclose(out[1], G0)
