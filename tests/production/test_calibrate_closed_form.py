"""flann calibrate on sensors the project did not make: a closed-form S-curve family (the
shape of /work/shared/checks/e2e_sensors.py, not the physics simulator), held-out points
through the hardware twin loaded from the written image."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from flann.hardware.family.render import load_design
from flann.hardware.family.twin import FlannFamilyTop
from flann.hardware.family.images import parse_hex
from flann.recordings import Recordings, write_recordings

SPAN_MM, W_MM, SHARP = 10.0, 7.0, 2.5
ADC_LSB_V = 2 * 3.6 / 2 ** 14


def s_curve(x, amp_v, asym):
    """Saturating S-curve: slope amp/w at the null, rolling off towards +-amp, asymmetric gain."""
    u = x / W_MM
    shape = u / (1 + np.abs(u) ** SHARP) ** (1 / SHARP)
    return amp_v * np.where(u >= 0, 1 + asym, 1 - asym) * shape


def sweep(amp_v, asym, seed, steps=300):
    x = np.linspace(-SPAN_MM, SPAN_MM, steps)
    xs = np.concatenate([x, x[::-1]])
    d = np.concatenate([np.ones(steps), -np.ones(steps)])
    noise = np.random.default_rng(seed).normal(0, 0.5e-3, xs.size)
    v = np.round((s_curve(xs, amp_v, asym) + noise) / ADC_LSB_V) * ADC_LSB_V
    return Recordings(displacement_mm=xs, voltage_v=v, direction=d)


SENSORS = {"s0": (3.0, 0.02), "s1": (3.15, -0.01), "s2": (2.9, 0.0), "s3": (3.1, 0.03), "big": (9.0, 0.0)}


@pytest.fixture(scope="session")
def run(once, in_process):
    """The family designed from two sensors and every sensor calibrated, once per test run."""
    def make(d):
        paths = {}
        for k, (name, (amp, asym)) in enumerate(SENSORS.items()):
            paths[name] = d / f"{name}.csv"
            write_recordings(paths[name], sweep(amp, asym, seed=k))
        rc, _out, err = in_process(["gen", "--family", paths["s0"], paths["s1"], "-o", d / "design"])
        if rc != 0:
            raise RuntimeError(f"flann gen --family failed: {err}")
        rc = in_process(["calibrate", *paths.values(), "-o", d / "out", "--design", d / "design", "-j", "2"])[0]
        with open(d / "out" / "summary.csv", newline="") as fh:
            rows = {r["sensor"]: r for r in csv.DictReader(fh)}
        return {"dir": d, "rc": rc, "rows": rows}
    return once("calibrate_closed_form", make)


def test_members_and_sensors_like_them_calibrate(run):
    rows = run["rows"]
    assert run["rc"] == 2  # "big" is outside the family
    assert rows["big"]["status"] == "failed" and "exceeds the design's input" in rows["big"]["reason"]
    # rejected: its certificate says why, and there are no weights
    assert sorted(q.name for q in (run["dir"] / "out" / "big").iterdir()) == ["certificate.html"]
    for name in ("s0", "s1", "s2", "s3"):  # s2, s3 did not size the design
        assert rows[name]["status"] == "ok", rows[name]
        assert float(rows[name]["max_error_mm"]) < float(rows[name]["raw_max_error_mm"]) / 10


def test_image_measures_held_out_points(run):
    """Dense noise-free points of each curve, through the twin holding the written image: the
    hardware error off the recorded points stays near the error on them."""
    fam = load_design(run["dir"] / "design")
    s = fam.spec
    x = np.linspace(-SPAN_MM * 0.98, SPAN_MM * 0.98, 1501)
    for name in ("s2", "s3"):
        words = parse_hex((run["dir"] / "out" / name / "weights.hex").read_text())
        codes = np.floor(s_curve(x, *SENSORS[name]) / s.input_lsb_v + 0.5).astype(int)
        out, sat = FlannFamilyTop(fam, words).process(codes)
        held_out = float(np.max(np.abs(out * s.output_lsb_mm - x)))
        on_recording = float(run["rows"][name]["max_error_mm"])
        assert not sat.any()
        assert held_out <= 1.5 * on_recording + 4 * s.output_lsb_mm, (name, held_out, on_recording)
