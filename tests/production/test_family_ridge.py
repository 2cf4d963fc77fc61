"""gen --family chooses the ridge its members are trained with, and calibrate trains with it.

A fixed ridge of 1e-6 bent the ends of the stroke: three S-curve sensors (not the project's
forms) sized a 41-term design on which the first of them was flagged by calibrate, its
hardware max error 1.53 x what its own design reaches."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flann.cli import main
from flann.golden.family import DEFAULT_RIDGE, FAMILY_RIDGES, ridge_ladder
from flann.hardware.family.render import load_design
from flann.production.calibrate import check_sensor, reach_flag
from flann.recordings import Recordings, read_recordings, write_recordings

BITS, LSB = 14, 2 * 3.6 / 2 ** 14


def _sensor(rng) -> Recordings:
    """An S-curve of sharpness 2.5 over +-10 mm, amplitude, asymmetry and width a few per cent
    apart from sensor to sensor; 0.5 mV noise, 14 bits, 300 positions forward and back."""
    amp, asym, w = rng.uniform(2.9, 3.2), rng.uniform(-0.03, 0.03), 7.0 * rng.uniform(0.95, 1.05)
    x = np.linspace(-10.0, 10.0, 300)
    xs = np.concatenate([x, x[::-1]])
    u = xs / w
    v = amp * np.where(u >= 0, 1 + asym, 1 - asym) * u / (1 + np.abs(u) ** 2.5) ** 0.4
    v = np.round((v + rng.normal(0, 0.5e-3, xs.size)) / LSB) * LSB
    return Recordings(displacement_mm=xs, voltage_v=v, direction=np.sign(np.gradient(xs)))


@pytest.fixture(scope="module")
def design(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("family_ridge")
    rng = np.random.default_rng(7)
    paths = []
    for k in range(3):
        paths.append(tmp / f"s{k:02d}.csv")
        write_recordings(paths[-1], _sensor(rng))
    out = tmp / "design"
    assert main(["gen", "--family", *map(str, paths), "-o", str(out), "--input-bits", str(BITS),
                 "--input-lsb-v", repr(LSB)]) == 0
    return out, paths


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
