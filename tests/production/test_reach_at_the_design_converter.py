"""calibrate's reach flag compares the hardware with the sensor's own design at the design's
converter: a 10-bit family design of 12-bit recordings (an erf S-curve with a cubic, not the
project's forms) had every sensor flagged at about 2x, the own design asked at the recording's
12-bit voltages and the hardware at its 10-bit codes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import erf

from flann.cli import main
from flann.golden.family import REACH_FACTOR, own_reach_mm
from flann.hardware.family.render import load_design
from flann.production.calibrate import check_sensor, first_own_design, reach_flag
from flann.recordings import Recordings, read_recordings, write_recordings


def _sensor(seed: int, gain: float) -> Recordings:
    rng, lsb = np.random.default_rng(seed), 5.0 / 4096
    xs = np.arange(-25, 25.0001, 0.5)
    x = np.concatenate([xs, xs[::-1]])
    u = x - 1.3
    v = 1.9 * gain * erf(u / 11) + 0.012 * (u / 10) ** 3 - 0.0004 * u ** 2 + 0.045 + rng.normal(0, 8e-4, x.size)
    return Recordings(displacement_mm=x, voltage_v=np.round(v / lsb) * lsb, direction=np.sign(np.gradient(x)))


@pytest.fixture(scope="module")
def family(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("reach")
    paths = []
    for seed, gain in ((11, 1.02), (12, 1.0), (13, 1.01)):
        paths.append(tmp / f"f{seed}.csv")
        write_recordings(paths[-1], _sensor(seed, gain))
    assert main(["gen", "--family", *map(str, paths), "-o", str(tmp / "fam"), "--input-bits", "10"]) == 0
    return load_design(tmp / "fam"), paths


def test_a_member_is_not_flagged_for_the_design_converter(family):
    fam, paths = family
    rec = read_recordings(paths[0])
    hw = float(np.max(np.abs(check_sensor(rec, fam)["hw_err_mm"])))
    reach, flag = reach_flag(rec, fam, hw)
    assert flag is None, flag
    # at the recording's own 12-bit voltages the own design reaches more than any 10-bit
    # design can: that yardstick flags the member
    finer, _terms = own_reach_mm(rec.voltage_v, rec.displacement_mm)
    assert hw > REACH_FACTOR * finer, (hw, finer, reach)


def test_the_flag_still_names_a_sensor_the_design_serves_badly(family):
    fam, paths = family
    rec = read_recordings(paths[0])
    reach, flag = reach_flag(rec, fam, 10.0)
    assert flag is not None and "at the design's 10-bit input" in flag and f"{10.0 / reach:.2f} x" in flag


def test_the_batch_chooses_the_own_design_once_and_each_sensor_fits_it(family, tmp_path):
    """calibrate chooses the own design's structure once (``--terms auto`` on the first
    recording that reads, skipping a FIFO), then each sensor is one fit with it: its reach
    within 10 % of its own choice's, and a member still unflagged."""
    fam, paths = family
    import os

    os.mkfifo(tmp_path / "pipe.csv")
    own = first_own_design([tmp_path / "pipe.csv", tmp_path / "missing.csv", *paths], fam)
    assert own is not None and own.chosen_on == paths[0].stem
    for p in paths[1:]:
        rec = read_recordings(p)
        hw = float(np.max(np.abs(check_sensor(rec, fam)["hw_err_mm"])))
        reach, flag = reach_flag(rec, fam, hw, own)
        its_own, _flag = reach_flag(rec, fam, hw)
        assert reach == pytest.approx(its_own, rel=0.1)
        assert flag is None, flag
        _r, named = reach_flag(rec, fam, 10.0, own)
        assert f"as chosen on {own.chosen_on}" in named
