"""Readings rounded by a converter and not dithered by noise: rounding is not physics.

A noise-free simulation through the sensor file's 16-bit converter leaves residuals of up to
half a step whose pattern along the travel looks periodic; the diagnosis must not name it.
A real effect that moves readings by several steps on the same recordings is still named.
"""

import json

import numpy as np

from flann.cli import main
from flann.recordings import converter_step as reading_step

PAPER = "data/sensors/paper_lvdt.toml"


def test_reading_step_found_on_a_grid_and_not_on_noise():
    rng = np.random.default_rng(3)
    q = 20.0 / 2 ** 16
    codes = rng.integers(-30000, 30000, 200)
    codes[:2] = (1000, 1003)  # the smallest gap is three steps, not one
    assert abs(reading_step(codes * q + 7 * q) - q) < 1e-12
    assert reading_step(codes * q + rng.normal(0, 0.2 * q, 200)) == 0.0
    assert reading_step(rng.normal(0, 1, 200)) == 0.0


def _diagnose(tmp_path, capsys, sensor_text=None, step="0.5"):
    args = ["simulate", "-o", str(tmp_path / "r.csv"), "--step-mm", step]
    if sensor_text is not None:
        (tmp_path / "s.toml").write_text(sensor_text)
        args.insert(1, str(tmp_path / "s.toml"))
    assert main(args) == 0
    capsys.readouterr()
    assert main(["diagnose", str(tmp_path / "r.csv"), "--json", "--quiet"]) == 0
    return json.loads(capsys.readouterr().out)


def test_noise_free_quantised_simulation_names_nothing(tmp_path, capsys):
    for step in ("0.5", "1"):
        out = _diagnose(tmp_path, capsys, step=step)
        assert [e["name"] for e in out["effects"]] == [], step


def test_a_lead_screw_of_many_steps_is_still_named(tmp_path, capsys):
    text = open(PAPER).read() + ("\n[effects.leadscrew_periodic]\namplitude_mm = 0.02\n"
                                 "period_mm = 2.54\nphase_rad = 0.4\n")
    out = _diagnose(tmp_path, capsys, text)
    names = [e["name"] for e in out["effects"]]
    assert names == ["leadscrew_periodic"], names
    amp = out["effects"][0]["params"]["amplitude_mm"]["value"]
    assert abs(abs(amp) - 0.02) < 0.004
