"""The smooth shape term must not take what the calibrated simulation's gain and geometry
draw: on a sensor the simulation fits to the noise, every noise draw gives the same gain,
and a small backlash is read at its size, whether or not shape terms were chosen.

The recordings are an ideal tanh curve (not the project's LVDT model): 4.2 V tanh(0.045 x),
-20..20 mm every 0.25 mm, two sweeps each way, 1.5 mV noise, a 12-bit +-5 V converter.  The
noise draws are ones on which cross-validation chose shape terms (with them, the gain's
standard error was 2.2 on a value of 1.2-2.6 and a 30 um backlash was read as 60-100 um)."""

import json

import numpy as np
import pytest

from flann.cli import main

LSB = 10 / 4096


def _recording(path, seed, deadband_mm=0.0):
    rng = np.random.default_rng(seed)
    xs = np.arange(-20, 20 + 1e-9, 0.25)
    rows = ["displacement_mm,voltage_v,direction"]
    for _ in range(2):
        for d, sweep in ((1, xs), (-1, xs[::-1])):
            for x in sweep:
                core = x - d * deadband_mm / 2
                v = 4.2 * np.tanh(0.045 * core) + rng.normal(0, 0.0015)
                v = np.clip(np.round(v / LSB) * LSB, -5, 5 - LSB)
                rows.append(f"{x:.3f},{v:.6f},{d:+d}")
    path.write_text("\n".join(rows) + "\n")
    return str(path)


def _diagnose(tmp_path, seed, deadband_mm=0.0):
    rec = _recording(tmp_path / f"r{seed}_{deadband_mm}.csv", seed, deadband_mm)
    out = tmp_path / f"d{seed}_{deadband_mm}.json"
    assert main(["diagnose", rec, "--quiet", "--json", str(out)]) == 0
    return json.loads(out.read_text())


def test_gain_is_the_same_on_every_noise_draw(tmp_path):
    reports = [_diagnose(tmp_path, seed) for seed in (2, 5, 8)]
    # seed 8's curve needs no shape terms; 2 and 5 took two
    assert [r["baseline"]["shape_term"]["terms"] > 0 for r in reports] == [True, True, False]
    gains = np.array([r["baseline"]["params"]["gain_ratio"]["value"] for r in reports])
    errs = np.array([r["baseline"]["params"]["gain_ratio"]["stderr"] for r in reports])
    assert np.all(errs < 1e-3 * np.abs(gains)), (gains, errs)
    assert np.ptp(gains) < 2e-3 * np.mean(np.abs(gains)), gains
    for r in reports:
        # the simulation alone, at that gain, meets the readings to the noise
        assert r["baseline"]["ideal_rms_v"] < 1.5 * r["noise_v"], r["baseline"]["ideal_rms_v"]
        assert r["effects"] == []


@pytest.mark.parametrize("seed", [5, 6])
def test_backlash_is_read_at_its_size_beside_shape_terms(tmp_path, seed):
    r = _diagnose(tmp_path, seed, deadband_mm=0.03)
    assert r["baseline"]["shape_term"]["terms"] > 0
    assert [e["name"] for e in r["effects"]] == ["backlash"]
    db = r["effects"][0]["params"]["deadband_mm"]
    assert abs(db["value"] - 0.03) < 0.004 and db["stderr"] < 0.004, db


def test_halves_of_unequal_gain_are_not_read_as_large_cancelling_effects(tmp_path):
    # 5.18 V tanh(x / 13.84 mm), the + half 1.14 % stronger than the - half, 0.5 mV offset,
    # 0.5 mV noise, 14 bits over +-8.192 V, -20..20 mm every 0.05 mm out and back.  With the
    # shape modes moved by a zero shift the selection named a 24 % imbalance, a -0.61 V
    # offset and a -0.94 mm shift that cancel (the reading at 0 mm is 0.5 mV)
    rng = np.random.default_rng(1001)
    lsb = 16.384 / 2 ** 14
    xf = np.round(np.arange(-20, 20.0001, 0.05), 4)
    x = np.r_[xf, xf[::-1]]
    v = 5.177 * np.tanh(x / 13.84) * (1 + 0.0114 * np.sign(x)) + 0.00055 + rng.normal(0, 5e-4, x.size)
    v = np.clip(np.round(v / lsb), -2 ** 13, 2 ** 13 - 1) * lsb
    d = np.r_[np.ones(xf.size), -np.ones(xf.size)]
    rec = tmp_path / "halves.csv"
    rec.write_text("displacement_mm,voltage_v,direction\n"
                   + "".join(f"{a:.4f},{b:.6f},{int(c)}\n" for a, b, c in zip(x, v, d)))
    out = tmp_path / "d.json"
    assert main(["diagnose", str(rec), "--quiet", "--json", str(out)]) == 0
    r = json.loads(out.read_text())
    sizes = {e["name"]: {k: p["value"] for k, p in e["params"].items()} for e in r["effects"]}
    assert abs(sizes.get("null_offset", {}).get("offset_v", 0.0)) < 0.01, sizes
    assert abs(sizes.get("zero_shift", {}).get("shift_mm", 0.0)) < 0.1, sizes
    assert abs(sizes.get("secondary_imbalance", {}).get("imbalance_fraction", 0.0)) < 0.05, sizes
