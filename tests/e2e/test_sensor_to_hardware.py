"""From a sensor's recordings to hardware: train -> gen -> eval --design, on three kinds of sensor.

* a closed-form family written here (not the project's physics): an asymmetric arctan
  roll-off and a cubic-saturation curve, with noise, several ADC widths and origins;
* the physics simulator (`flann simulate`) with two geometries (the paper's LVDT and a
  miniature reversed-polarity one);
* Table 1 of the paper (13 points).

Every model `flann train` writes must build with `flann gen` at the user's ADC; the design's
bit-true twin on held-out voltages (as ADC codes) must stay within 1.5x the float model's
max error plus one output LSB.  One design also goes through the HDL simulation.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from flann.cli import main
from flann.hardware.design import from_directory
from flann.verify.runner import sweep


def run(argv, capsys):
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


def write_csv(path, cols: dict):
    names = list(cols)
    lines = [",".join(names)] + [",".join(f"{c:.9g}" for c in row) for row in zip(*cols.values())]
    path.write_text("\n".join(lines) + "\n")
    return path


# -- a closed-form family, independent of flann.physics -------------------------------------
def arctan_sensor(x, span, amp, asym):
    u = x / span
    return amp * np.arctan(2.2 * u) / np.arctan(2.2) * np.where(u >= 0, 1 + asym, 1 - asym)


def cubic_sensor(x, span, amp, asym):
    u = x / span
    return amp * (u - 0.28 * u**3 + asym * u**2) / (1 - 0.28)


FAMILY = [  # (shape, span mm, amplitude V, asymmetry, ADC bits, origin at 0?, noise V)
    (arctan_sensor, 10.0, 4.0, 0.03, 12, False, 0.0008),
    (cubic_sensor, 50.0, 1.5, -0.05, 14, True, 0.0003),
    (arctan_sensor, 2.0, -7.0, 0.0, 16, False, 0.002),
]


def family_recordings(tmp_path, shape, span, amp, asym, bits, from_zero, noise, seed):
    rng = np.random.default_rng(seed)
    lo, hi = (0.0, 2 * span) if from_zero else (-span, span)
    null = span if from_zero else 0.0
    x = np.linspace(lo, hi, 161)
    xs = np.concatenate([x, x[::-1]])
    d = np.concatenate([np.ones_like(x), -np.ones_like(x)])
    vmax = float(np.max(np.abs(shape(np.array([lo, hi]) - null, span, amp, asym)))) * 1.08
    lsb = float(f"{2 * vmax / 2**bits:.6g}")
    v = np.round((shape(xs - null, span, amp, asym) + rng.normal(0, noise, xs.size)) / lsb) * lsb
    xt = np.sort(rng.uniform(lo + 0.01 * span, hi - 0.01 * span, 600))
    vt = np.round(shape(xt - null, span, amp, asym) / lsb) * lsb
    rec = write_csv(tmp_path / "rec.csv", {"displacement_mm": xs, "voltage_v": v, "direction": d})
    held = write_csv(tmp_path / "held.csv", {"displacement_mm": xt, "voltage_v": vt})
    return rec, held, lsb


def train_gen_eval(tmp_path, capsys, rec, held, gen_opts=(), train_opts=()):
    model, design = tmp_path / "model.json", tmp_path / "hdl"
    rc, _, err = run(["train", rec, "-o", model, *train_opts], capsys)
    assert rc == 0, err
    rc, _, err = run(["gen", model, "-o", design, *gen_opts], capsys)
    assert rc == 0, err
    rc, out, err = run(["eval", model, held, "--design", design, "--json"], capsys)
    assert rc == 0, err
    return model, design, json.loads(out)


def check_hardware(res, unquantised=False):
    """Hardware within 1.5x the float model's error + 1 output LSB.  ``unquantised``: the
    held-out voltages are exact (not ADC readings), so the hardware alone pays the ADC's
    quantisation, up to the physical limit, on top."""
    fl, hw = res["compensated"], res["hardware"]
    extra = hw["physical_limit_mm"]["max"] if unquantised else 0.0
    assert hw["max_error_mm"] <= 1.5 * fl["max_error_mm"] + hw["output_lsb_mm"] + extra
    assert hw["rms_error_mm"] <= 1.5 * fl["rms_error_mm"] + hw["output_lsb_mm"] + extra
    # the datapath itself: within one output LSB of the float model at the same ADC codes
    assert hw["max_abs_hardware_minus_float_at_codes_mm"] <= hw["output_lsb_mm"]
    # the ratio is computed from the figures it reports
    assert hw["ratio_to_limit"] == pytest.approx(hw["max_error_mm"] / hw["physical_limit_mm"]["max"])


@pytest.mark.parametrize("case", range(len(FAMILY)))
def test_closed_form_sensors_train_gen_eval(tmp_path, capsys, case):
    shape, span, amp, asym, bits, from_zero, noise = FAMILY[case]
    rec, held, lsb = family_recordings(tmp_path, shape, span, amp, asym, bits, from_zero, noise, case)
    _, design, res = train_gen_eval(tmp_path, capsys, rec, held,
                                    gen_opts=["--input-bits", bits, "--input-lsb-v", f"{lsb:.9g}"])
    man = json.loads((design / "manifest.json").read_text())
    assert man["input_bits"] == bits and man["input_lsb_v"] == pytest.approx(lsb)
    check_hardware(res)
    # compensation is worth having: far better than the raw sensor's straight line
    assert res["hardware"]["max_error_mm"] < 0.1 * res["raw"]["max_error_mm"]


@pytest.mark.parametrize("sensor, step", [("paper_lvdt", "0.5"), ("miniature_reversed", None)])
def test_physics_sensors_train_gen_eval(tmp_path, capsys, data_dir, sensor, step):
    toml = data_dir / "sensors" / f"{sensor}.toml"
    rec, held = tmp_path / "rec.csv", tmp_path / "held.csv"
    step_opt = ["--step-mm", step] if step else []
    rc, _, err = run(["simulate", toml, "--sweeps", 2, *step_opt, "--noise-v", 0.002, "-o", rec], capsys)
    assert rc == 0, err
    rc, _, err = run(["simulate", toml, "--sweeps", 1, *step_opt, "--noise-v", 0, "-o", held],
                     capsys)
    assert rc == 0, err
    model, design, res = train_gen_eval(tmp_path, capsys, rec, held)
    check_hardware(res, unquantised=True)
    # the dense noisy recording itself, as in the README walk-through
    rc, out, _ = run(["eval", model, rec, "--design", design, "--json"], capsys)
    check_hardware(json.loads(out))


def test_table1_train_gen_eval(tmp_path, capsys, table1_csv):
    # auto on 13 points: builds, and the hardware stays near the float model
    _, _, res = train_gen_eval(tmp_path, capsys, table1_csv, table1_csv)
    check_hardware(res, unquantised=True)   # Table 1's voltages are not this ADC's codes


def test_table1_paper_interpolant_builds(tmp_path, capsys, table1_csv):
    # the paper's 51-term interpolant swings between the points: one ADC LSB of quantisation
    # moves it by more than the limit at the point, so only the datapath's error is bounded
    _, _, res = train_gen_eval(tmp_path, capsys, table1_csv, table1_csv,
                               train_opts=["--terms", "51", "--method", "lstsq"])
    hw = res["hardware"]
    assert hw["max_abs_hardware_minus_float_at_codes_mm"] <= hw["output_lsb_mm"]
    assert res["compensated"]["max_error_mm"] < 1e-9 < hw["max_error_mm"]


@pytest.mark.sim
def test_closed_form_sensor_through_the_hdl_simulation(tmp_path, capsys):
    shape, span, amp, asym, _, from_zero, noise = FAMILY[0]
    rec, held, lsb = family_recordings(tmp_path, shape, span, amp, asym, 8, from_zero, noise, 11)
    # the design at the recordings' converter: the 1.5x bound has no room for a second quantisation
    _, design_dir, res = train_gen_eval(tmp_path, capsys, rec, held,
                                        gen_opts=["--input-bits", 8, "--input-lsb-v", f"{lsb:.9g}"])
    check_hardware(res)
    # the directory flann gen wrote, every code through the VHDL, judged against its twin
    design = from_directory(design_dir, tmp_path / "model.json")
    r = sweep(design, tmp_path / "build")
    assert r["bench"].ok, f"failed: {r['bench'].failed_tests} (see {tmp_path}/build/sweep)"
    assert r["codes"].tolist() == list(range(-128, 128))
