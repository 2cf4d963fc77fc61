"""The family design's default (--terms auto) and its headroom for sensors not in the gen set."""

import contextlib
import io
import json
import warnings

import numpy as np
import pytest

from flann.cli import main
from flann.hardware.family.datapath import rebuild
from flann.production.calibrate import check_sensor, train_for_design
from flann.recordings import Recordings, read_recordings, write_recordings

LSB = 2 * 3.6 / 2 ** 14


def s_curve_rec(amp, asym, w_mm, rng, steps=300):
    """A closed-form S-curve sensor (not the physics simulator's model), 14-bit, 0.5 mV noise."""
    x = np.linspace(-10.0, 10.0, steps)
    xs = np.concatenate([x, x[::-1]])
    u = xs / w_mm
    v = amp * np.where(u >= 0, 1 + asym, 1 - asym) * u / (1 + np.abs(u) ** 2.5) ** 0.4
    v = np.round((v + rng.normal(0, 5e-4, xs.size)) / LSB) * LSB
    return Recordings(displacement_mm=xs, voltage_v=v, direction=np.sign(np.gradient(xs)))


@pytest.fixture(scope="module")
def family(tmp_path_factory):
    """Three members drawn with +-3 % asymmetry, the design sized by flann gen's defaults."""
    d = tmp_path_factory.mktemp("headroom")
    rng = np.random.default_rng(2)
    paths = []
    for k in range(3):
        paths.append(d / f"m{k}.csv")
        write_recordings(paths[-1], s_curve_rec(rng.uniform(2.9, 3.2), rng.uniform(-0.03, 0.03),
                                                7.0 * rng.uniform(0.95, 1.05), rng))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = main(["gen", "--family", *map(str, paths), "-o", str(d / "design"), "--input-bits", "14",
                   "--input-lsb-v", repr(LSB)])
    assert rc == 0
    man = json.loads((d / "design" / "manifest.json").read_text())
    fam, _ = rebuild(d / "design" / "init_model.json", man)
    return d, man, fam, out.getvalue()


def test_default_terms_are_chosen_like_train_auto(family):
    _d, man, fam, out = family
    # no --terms given: the terms were chosen per member (auto), not a fixed count
    lines = [line for line in out.splitlines() if "own design" in line]
    assert [line.split(":")[0].strip() for line in lines] == ["m0", "m1", "m2"]
    assert all(f"in the family {fam.terms} terms" in line for line in lines)
    assert man["family"]["terms"] == fam.terms != 15


def test_sensors_near_the_family_are_calibrated_not_refused(family, tmp_path):
    """Sensors drawn twice as asymmetric as the members (+-6 %), +-10 % wider: every one fits
    the design and its hardware output stays within the design's error bound of its model.
    Sized from the members' largest values alone (x 1.5), the design refused some of these
    (their offset constant k0 reached past it)."""
    _d, _man, fam, _out = family
    rng = np.random.default_rng(12)
    worst = 0.0
    for k in range(30):
        p = tmp_path / f"n{k}.csv"
        write_recordings(p, s_curve_rec(rng.uniform(2.8, 3.3), rng.uniform(-0.06, 0.06),
                                        7.0 * rng.uniform(0.9, 1.1), rng))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if k < 2:   # the whole hardware check on a few, fitting alone on the rest (time)
                r = check_sensor(read_recordings(p), fam)
                assert r["twin_err_lsb"] <= r["bound_lsb"]
                worst = max(worst, float(np.max(np.abs(r["hw_err_mm"]))))
            else:
                train_for_design(read_recordings(p), fam)
    assert worst < 0.05   # mm over a 20 mm stroke: a calibration, not a clamp


def test_a_sensor_far_outside_the_family_is_still_refused(family, tmp_path, capsys):
    d, _man, _fam, _out = family
    p = tmp_path / "far.csv"
    write_recordings(p, s_curve_rec(6.5, 0.0, 7.0, np.random.default_rng(3)))
    rc = main(["calibrate", str(p), "-o", str(tmp_path / "cal"), "--design", str(d / "design")])
    assert rc != 0
    assert "exceeds the design's input" in capsys.readouterr().err
