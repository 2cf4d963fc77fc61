"""Units and ranges that cannot be right are stopped before a design is built; wide ADCs accepted.

The sensor here is a line plus a cubic written in the test: 4.0 V at +-10 mm.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from flann.cli import main
from flann.golden.model import FlannModel


def run(argv, capsys):
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


def sensor_csv(path, scale=1.0, header="displacement_mm,voltage_v", noise_v=0.0, n=81):
    x = np.linspace(-10, 10, n)
    v = (0.45 * x - 0.0005 * x**3 + np.random.default_rng(1).normal(0, noise_v, n)) * scale  # 4 V at 10 mm
    path.write_text(header + "\n" + "\n".join(f"{a:.6g},{b:.9g}" for a, b in zip(x, v)) + "\n")
    return path


@pytest.fixture(scope="module")
def model(tmp_path_factory, in_process):
    """One training for the module's gen and eval checks (none of them writes the model)."""
    d = tmp_path_factory.mktemp("units")
    m = d / "m.json"
    rc, _out, err = in_process(["train", sensor_csv(d / "r.csv"), "-o", m])
    assert rc == 0, err
    return m


def one_error_line(err):
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    return lines[0]


def test_millivolts_under_a_volts_header_are_refused(tmp_path, capsys):
    rec = sensor_csv(tmp_path / "mv.csv", scale=1000.0)
    rc, _, err = run(["train", rec, "-o", tmp_path / "m.json"], capsys)
    assert rc == 2 and "voltage_mv" in one_error_line(err) and "4000 V" in err
    assert not (tmp_path / "m.json").exists()
    # the same numbers under a millivolt header train
    rec = sensor_csv(tmp_path / "mv2.csv", scale=1000.0, header="displacement_mm,Voltage (mV)")
    assert run(["train", rec, "-o", tmp_path / "m.json"], capsys)[0] == 0


def test_trained_range_outside_the_adc_names_both_ranges(tmp_path, capsys, model):
    # 12 bits x 1 mV covers -2.048..2.047 V; the sensor gives -4..4 V
    rc, _, err = run(["gen", model, "-o", tmp_path / "hdl", "--input-bits", 12, "--input-lsb-v", 0.001],
                     capsys)
    line = one_error_line(err)
    assert rc == 2 and "-4..4 V" in line and "-2.048..2.047 V" in line and "--input-lsb-v 0.001" in line
    assert not (tmp_path / "hdl").exists()


def test_small_fraction_of_the_adc_is_said(tmp_path, capsys, model):
    # 16 bits x 10 mV covers +-327 V: the sensor's 8 V uses 1.2 % of it
    rc, _, err = run(["gen", model, "-o", tmp_path / "hdl", "--input-bits", 16, "--input-lsb-v", 0.01],
                     capsys)
    assert rc == 0 and "uses 1.2 % of the ADC" in err


def test_coarse_input_lsb_names_the_option(tmp_path, capsys, model):
    rc, _, err = run(["gen", model, "-o", tmp_path / "hdl", "--input-lsb-v", 10], capsys)
    line = one_error_line(err)
    assert rc == 2 and "--input-lsb-v" in line and "output_bits" not in line


def test_24_bit_adc_drops_low_bits_and_says_what_it_costs(tmp_path, capsys, model):
    lsb24 = 10.0 / 2**24    # +-5 V converter
    rc, out, err = run(["gen", model, "-o", tmp_path / "hdl", "--input-bits", 24, "--input-lsb-v", lsb24,
                        "--json"], capsys)
    assert rc == 0, err
    man = json.loads(out)
    assert man["input_bits"] == 16 and man["input_lsb_v"] == pytest.approx(lsb24 * 256)
    assert "drops 8 low bits" in err and "bits 23..8" in err
    # the stated cost: the dropped bits floor the code, so up to one new LSB over the steepest
    # slope (0.45 - 0.0015 x^2 V/mm at 10 mm)
    steepest_mm_per_v = 1 / (0.45 - 0.0015 * 100)
    said = float(err.split("adding up to ")[1].split(" mm")[0])
    assert said == pytest.approx(lsb24 * 256 * steepest_mm_per_v, rel=0.02)
    # the manifest keeps the converter; eval --design quantises with it and takes its top bits
    assert man["adc_bits"] == 24 and man["adc_lsb_v"] == pytest.approx(lsb24)
    rc, out, err = run(["eval", model, sensor_csv(tmp_path / "held.csv", n=57), "--design", tmp_path / "hdl",
                        "--json"], capsys)
    assert rc == 0, err
    hw = json.loads(out)["hardware"]
    assert (hw["adc_bits"], hw["input_bits"], hw["dropped_low_bits"]) == (24, 16, 8)
    # the physical limit is the 24-bit converter's, not the design's coarser input
    assert hw["physical_limit_mm"]["max"] == pytest.approx(0.5 * lsb24 * steepest_mm_per_v, rel=0.05)


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_dropped_low_bits_are_not_wired():
    from flann.hardware.accuracy import adc_codes
    from flann.hardware.fixed.spec import derive_spec

    m = FlannModel(weights=(2.0, 0.1, 0.0), input_offset_v=0.0, input_scale_v=4.0, voltage_range_v=(-4.0, 4.0),
                   displacement_range_mm=(-10.0, 10.0))
    lsb24 = 10.0 / 2**24
    spec = derive_spec(m, input_bits=16, input_lsb_v=lsb24 * 256)
    # 1.0 V is 1677721.6 LSB24 -> code 1677722; its top 16 bits are 1677722 >> 8 = 6553 (6553.6 rounded
    # to the design's LSB would be 6554); -1.0 V: -1677722 >> 8 = -6554 (a floor, not towards zero)
    assert adc_codes(spec, [1.0, -1.0], (24, lsb24)).tolist() == [6553, -6554]
    assert adc_codes(spec, [1.0, -1.0]).tolist() == [6554, -6554]


def test_pathological_model_one_line_with_cause(tmp_path, capsys):
    # half-period normalisation, 61 terms, no ridge: nearly collinear terms whose huge weights
    # cancel (what auto used to write); asked for explicitly, train refuses to write what gen
    # would refuse, and says why in one line
    rec, m = sensor_csv(tmp_path / "r.csv", noise_v=0.001, n=401), tmp_path / "half.json"
    rc, _, err = run(["train", rec, "-o", m, "--terms", 61, "--normalise", "half"], capsys)
    line = one_error_line(err)
    assert rc == 2 and "weights sum to" in line and "--ridge" in line
    assert not m.exists()


def test_what_train_writes_gen_builds(tmp_path, capsys):
    # over-fitted (as many terms as points, no ridge) and a plain line: each is either refused
    # by train or built by gen -- never written and then refused
    rec = sensor_csv(tmp_path / "r.csv", noise_v=0.001, n=61)
    for terms in (1, 60):
        m = tmp_path / f"m{terms}.json"
        rc, _, _ = run(["train", rec, "-o", m, "--terms", terms], capsys)
        if rc == 0:
            rc, _, err = run(["gen", m, "-o", tmp_path / f"hdl{terms}"], capsys)
            assert rc == 0, err
        else:
            assert rc == 2 and not m.exists()


def test_model_whose_output_leaves_its_range_is_refused(tmp_path, capsys):
    w = [20.0] + [3e9, -3e9 + 1.0] + [0.0] * 8
    m = FlannModel(weights=tuple(w), voltage_range_v=(-4.0, 4.0), displacement_range_mm=(-10.0, 10.0),
                   input_scale_v=8.0)
    p = tmp_path / "ext.json"
    m.save(p)
    rc, _, err = run(["gen", p, "-o", tmp_path / "hdl"], capsys)
    assert rc == 2 and "not a usable model" in one_error_line(err)


def _steep_ended_model(ridge):
    """A sensor written here (saturating S-curve, 16-bit noise), 41 terms, half normalisation."""
    from flann.golden.train import fit_lstsq

    x = np.linspace(-2, 2, 261)
    xs = np.concatenate([x, x[::-1]])
    u = xs / 1.16
    v = 5.7 * u / (1 + np.abs(u) ** 3.75) ** (1 / 3.75) + np.random.default_rng(3).normal(0, 3e-4, xs.size)
    return fit_lstsq(v, xs, 41, norm="half", ridge=ridge, training={"cv_heldout_rms_error_mm": 4e-4})


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_a_model_whose_datapath_misses_the_float_model_is_not_buildable_for_auto():
    from flann.hardware.accuracy import fixed_point_cost
    from flann.hardware.fixed.spec import derive_spec
    from flann.hardware.fixed.twin import FlannTop

    loose, tight = _steep_ended_model(1e-14), _steep_ended_model(1e-8)
    # the loose model builds, but its capped widths let the hardware leave the float model
    spec = derive_spec(loose, input_bits=16)
    codes = np.arange(spec.clamp_lo, spec.clamp_hi + 1)
    out, _ = FlannTop(spec).process(codes)
    miss = np.max(np.abs(out * spec.output_lsb_mm - spec.float_reference(codes))) / spec.output_lsb_mm
    assert miss > 1.5, miss
    cost = fixed_point_cost(loose)
    assert not cost["buildable"] and "output LSB (> 1)" in cost["why"]
    assert fixed_point_cost(tight)["buildable"]


def test_unipolar_converter_gets_the_way_to_use_it(tmp_path, capsys):
    # a 0..5 V ADC around a 2.5 V mid-scale: the recorded voltages are all positive
    rec = sensor_csv(tmp_path / "r.csv", scale=0.15)
    text = rec.read_text().splitlines()
    rows = [f"{a},{float(b) + 2.5:.9g}" for a, b in (ln.split(",") for ln in text[1:])]
    rec.write_text("\n".join([text[0], *rows]) + "\n")
    m = tmp_path / "m.json"
    assert run(["train", rec, "-o", m], capsys)[0] == 0
    rc, _, err = run(["gen", m, "-o", tmp_path / "hdl", "--input-bits", 12, "--input-lsb-v", 5 / 4096], capsys)
    line = one_error_line(err)
    assert rc == 2 and "unipolar 0..5 V" in line and "minus 2.5 V" in line and "top bit inverted" in line
