"""flann gen --family --terms auto: terms chosen like train --terms auto, what sharing costs."""

import json

import numpy as np
import pytest

from flann.cli import main
from flann.golden.family import FAMILY_RIDGES, FAMILY_SHARE, family_terms
from flann.golden.train import fit_auto
from flann.recordings import Recordings, write_recordings


def s_curve_rec(amp, asym, seed, steps=150, lsb=2 * 3.6 / 2 ** 14):
    x = np.linspace(-10.0, 10.0, steps)
    xs = np.concatenate([x, x[::-1]])
    u = xs / 7.0
    v = amp * np.where(u >= 0, 1 + asym, 1 - asym) * u / (1 + np.abs(u) ** 2.5) ** 0.4
    v = np.round((v + np.random.default_rng(seed).normal(0, 5e-4, xs.size)) / lsb) * lsb
    return Recordings(displacement_mm=xs, voltage_v=v, direction=np.sign(np.gradient(xs)))


def test_family_terms_keep_every_member_near_its_own_design():
    recs = [s_curve_rec(3.0, 0.02, 1), s_curve_rec(3.1, -0.01, 2)]
    terms, ridge, choices = family_terms([(str(i), r.voltage_v, r.displacement_mm) for i, r in enumerate(recs)],
                                         norm="half")
    assert 2 <= terms <= max(c.own_terms for c in choices)
    assert ridge in FAMILY_RIDGES
    for c, r in zip(choices, recs):
        # the member's own choice is what train --terms auto takes with the family's normalisation
        _m, own = fit_auto(r.voltage_v, r.displacement_mm, norms=("half",),
                           ridges=(1e-10, 1e-8, 1e-6, 1e-4, 1e-2, 1e-1, 1.0))
        assert c.own_terms == own.terms
        assert c.family_rms_mm <= FAMILY_SHARE * c.own_rms_mm
        assert c.family_max_mm <= FAMILY_SHARE * c.own_max_mm


def test_gen_family_terms_auto_says_what_sharing_costs(tmp_path, capsys):
    paths = []
    for k, (amp, asym) in enumerate([(3.0, 0.02), (3.1, -0.01)]):
        paths.append(tmp_path / f"m{k}.csv")
        write_recordings(paths[-1], s_curve_rec(amp, asym, k))
    rc = main(["gen", "--family", *map(str, paths), "--terms", "auto", "-o", str(tmp_path / "d"),
               "--input-bits", "14"])
    out = capsys.readouterr().out
    assert rc == 0
    man = json.loads((tmp_path / "d" / "manifest.json").read_text())
    terms = man["family"]["terms"]
    lines = [line for line in out.splitlines() if "own design" in line]
    assert len(lines) == 2 and all(f"in the family {terms} terms" in line for line in lines)


@pytest.mark.parametrize("terms", ["auto", "7"])
def test_a_member_the_family_cannot_take_is_named(tmp_path, capsys, terms):
    # a recording of three rows among two good ones: the refusal says which file, whether it
    # fails its own training (auto) or the family's common converter (--terms N)
    paths = []
    for k, (amp, asym) in enumerate([(3.0, 0.02), (3.1, -0.01)]):
        paths.append(tmp_path / f"m{k}.csv")
        write_recordings(paths[-1], s_curve_rec(amp, asym, k))
    short = tmp_path / "short_one.csv"
    short.write_text("displacement_mm,voltage_v\n-10,-2.10\n-9.9,-2.095\n-9.8,-2.09\n")
    rc = main(["gen", "--family", *map(str, paths), str(short), "--terms", terms, "-o", str(tmp_path / "d"),
               "--input-bits", "14", "--input-lsb-v", "0.001"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and err[0].startswith("error: short_one: "), err
    assert not (tmp_path / "d").exists()


def test_members_are_named_as_calibrate_names_the_sensors(tmp_path):
    from flann.hardware.family.build import member_names

    # a file name with a space becomes calibrate's folder name; a model calibrate wrote is
    # named by its sensor's folder, not "1_model", "2_model"
    assert member_names(["line rec/sensor 1.csv", "b/s2.csv"]) == ["sensor_1", "s2"]
    assert member_names(["cal/sensor_1/model.json", "cal/sensor_2/model.json"]) == ["sensor_1", "sensor_2"]
    assert member_names(["a/x.csv", "b/x.csv"]) == ["1_x", "2_x"]
