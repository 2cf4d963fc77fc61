"""The family design's default (--terms auto: terms and ridge) and its headroom for sensors not in
the gen set."""

import contextlib
import io
import json
import warnings

import numpy as np
import pytest

from flann.cli import main
from flann.hardware.family.datapath import rebuild
from flann.golden.family import DEFAULT_RIDGE, FAMILY_RIDGES, ridge_ladder
from flann.hardware.family.render import load_design
from flann.production.calibrate import check_sensor, reach_flag, train_for_design
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


def sized(d, seed: int, stem: str) -> tuple[list, str]:
    """Three members drawn with +-3 % asymmetry (``stem``0.csv ...), a design sized from them
    by flann gen's defaults in d/design: (their paths, what gen printed)."""
    rng = np.random.default_rng(seed)
    paths = []
    for k in range(3):
        paths.append(d / f"{stem}{k}.csv")
        write_recordings(paths[-1], s_curve_rec(rng.uniform(2.9, 3.2), rng.uniform(-0.03, 0.03),
                                                7.0 * rng.uniform(0.95, 1.05), rng))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = main(["gen", "--family", *map(str, paths), "-o", str(d / "design"), "--input-bits", "14",
                   "--input-lsb-v", repr(LSB)])
    assert rc == 0
    return paths, out.getvalue()


@pytest.fixture(scope="module")
def family(tmp_path_factory):
    d = tmp_path_factory.mktemp("headroom")
    _paths, said = sized(d, 2, "m")
    man = json.loads((d / "design" / "manifest.json").read_text())
    fam, _ = rebuild(d / "design" / "init_model.json", man)
    return d, man, fam, said


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


@pytest.fixture(scope="module")
def design(tmp_path_factory):
    """Three members whose design, at a fixed ridge of 1e-6, took 41 terms and left the first
    flagged by calibrate at 1.53 x what its own design reaches: the ends of the stroke bent."""
    tmp = tmp_path_factory.mktemp("family_ridge")
    paths, _said = sized(tmp, 7, "s")
    return tmp / "design", paths


def test_the_design_names_its_ridge_and_its_members_are_not_flagged(design):
    out, paths = design
    man = json.loads((out / "manifest.json").read_text())
    ridge = man["family"]["ridge"]
    assert ridge in FAMILY_RIDGES
    fam = load_design(out)
    assert fam.ridge == ridge
    for p in paths:
        rec = read_recordings(p)
        chk = check_sensor(rec, fam)
        assert chk["model"].training["ridge"] == ridge      # calibrate trains at the design's ridge
        hw = float(np.max(np.abs(chk["hw_err_mm"])))
        own, flag = reach_flag(rec, fam, hw)
        assert flag is None, (p.name, hw / own)


def test_a_design_without_a_ridge_is_read_at_the_one_it_was_trained_with(design):
    out, _paths = design
    written = (out / "manifest.json").read_text()
    man = json.loads(written)
    del man["family"]["ridge"]
    (out / "manifest.json").write_text(json.dumps(man))
    try:
        assert load_design(out).ridge == DEFAULT_RIDGE
    finally:
        (out / "manifest.json").write_text(written)


def test_calibrate_tries_the_design_ridge_then_larger_ones():
    assert ridge_ladder(1e-10) == (1e-10, 1e-8, 1e-6, 1e-5, 1e-4, 1e-3)
    assert ridge_ladder(DEFAULT_RIDGE) == (1e-6, 1e-5, 1e-4, 1e-3)
