"""The production line with temperature, end to end on sensors the project did not make: a
closed-form S-curve family (not the physics simulator) whose gain and null move with
temperature, 3 sensors calibrated at -20, 25 and 80 degC:

    flann gen --family (3 recordings) -> flann sim DIR (0 mismatches) -> flann calibrate
    -> certificates with one error curve per temperature and the drift figure."""

from __future__ import annotations

import csv
import re
import json
import shutil

import numpy as np
import pytest

from flann.cli import main
from flann.golden.thermal_metrics import drift_ppm_fs_per_c
from flann.hardware.family_thermal.twin import FlannFamilyThermalTop
from flann.hardware.family.images import header_fields, parse_hex
from flann.hardware.family.render import design_hash
from flann.recordings import Recordings, write_recordings
from flann.hardware.design import from_directory

SPAN_MM, W_MM, SHARP = 10.0, 7.0, 2.5
ADC_LSB_V = 2 * 3.6 / 2 ** 14
TEMPS = (-20.0, 25.0, 80.0)
# amplitude (V), gain coefficient (/degC), null drift (V/degC): LVDT-like ranges
SENSORS = {"a": (3.0, -2.0e-4, 40e-6), "b": (3.1, -1.2e-4, -25e-6), "c": (2.9, -2.6e-4, 10e-6)}


def volts(x, temp, amp, gain_tc, null_tc):
    u = x / W_MM
    dt = temp - 25.0
    return amp * (1 + gain_tc * dt) * u / (1 + np.abs(u) ** SHARP) ** (1 / SHARP) + null_tc * dt


def recording(params, seed, steps=100):
    x = np.linspace(-SPAN_MM, SPAN_MM, steps)
    xs = np.concatenate([np.concatenate([x, x[::-1]]) for _ in TEMPS])
    ds = np.tile(np.concatenate([np.ones(steps), -np.ones(steps)]), len(TEMPS))
    ts = np.repeat(TEMPS, 2 * steps)
    noise = np.random.default_rng(seed).normal(0, 0.2e-3, xs.size)
    v = np.round((volts(xs, ts, *params) + noise) / ADC_LSB_V) * ADC_LSB_V
    return Recordings(displacement_mm=xs, voltage_v=v, direction=ds, temperature_c=ts)


@pytest.fixture(scope="module")
def line(tmp_path_factory):
    d = tmp_path_factory.mktemp("thermal_line")
    paths = []
    for k, (name, params) in enumerate(SENSORS.items()):
        paths.append(d / f"{name}.csv")
        write_recordings(paths[-1], recording(params, seed=k))
    design = d / "design"
    # a small converter keeps the simulation short (every code at 9 temperature codes)
    assert main(["gen", "--family", *map(str, paths), "-o", str(design), "--input-bits", "8",
                 "--temp-bits", "8", "--temp-lsb-c", "1", "--terms", "15"]) == 0
    return {"dir": d, "paths": paths, "design": design}


def test_design_takes_temperature_and_keeps_images(line):
    man = json.loads((line["design"] / "manifest.json").read_text())
    assert man["datapath"] == "family_thermal" and man["top"] == "flann_family_thermal_top"
    assert "in_temp" in man["cfg_port"]["ports"]
    assert [im["name"] for im in man["images"]] == list(SENSORS)
    spec = from_directory(line["design"]).spec
    assert spec.orders == 3 and spec.temp.lo == -20 and spec.temp.hi == 80
    # the image holds every order's memory: the temperature coefficients are per sensor
    imgs = [parse_hex((line["design"] / f"image_{n}.hex").read_text()) for n in SENSORS]
    assert all(len(w) == spec.image_words for w in imgs)
    d = spec.fam.mem_depth
    assert imgs[0][d:2 * d] != imgs[1][d:2 * d]


def test_twin_follows_the_float_model_at_every_temperature_code(line):
    design = from_directory(line["design"])
    twin = design.twin()
    s = design.spec
    err = twin.error_vs_float(temp_codes=range(s.temp.lo, s.temp.hi + 1))
    assert err["max_err_lsb"] <= 1.0


@pytest.mark.sim
def test_sim_every_voltage_code_at_the_stated_temperatures(line, tmp_path, capsys):
    out = tmp_path / "sim.json"
    assert main(["sim", str(line["design"]), "--summary-json", str(out)]) == 0
    s = json.loads(out.read_text())
    assert s["mismatches"] == 0 and s["all_passed"]
    temps = s["temperature_codes"]
    assert {-128, 127, -20, 80} <= set(temps)  # both ends of the code range and of the calibration
    assert s["codes_tested"] == 256 * len(temps)
    assert s["images"] == ["c"]  # loaded through the cfg port, not the memories' initial sensor


def test_calibrate_certificates_per_temperature(line):
    out = line["dir"] / "out"
    rc = main(["calibrate", *map(str, line["paths"]), "--design", str(line["design"]), "-o", str(out),
               "-j", "1", "--diagnosis-points", "60"])
    assert rc == 0
    with open(out / "summary.csv", newline="") as fh:
        rows = {r["sensor"]: r for r in csv.DictReader(fh)}
    spec = from_directory(line["design"]).spec
    for name, params in SENSORS.items():
        r = rows[name]
        assert r["verdict"] == "NOT JUDGED" and r["status"] == "ok", r   # no specification given
        # the drift column is the hardware's: recompute it from the written image and the twin
        rec = recording(params, seed=list(SENSORS).index(name))
        words = parse_hex((out / name / "weights.hex").read_text())
        assert header_fields((out / name / "weights.hex").read_text()) == (design_hash(line["design"]), len(words))
        codes = np.clip(np.floor(rec.voltage_v / spec.input_lsb_v + 0.5).astype(int), spec.code_min, spec.code_max)
        tcodes = np.floor(rec.temperature_c / spec.temp.lsb_c + 0.5).astype(int)
        hw = FlannFamilyThermalTop(spec, words).process(codes, tcodes).out_data * spec.output_lsb_mm
        want = drift_ppm_fs_per_c(hw - rec.displacement_mm, rec.displacement_mm, rec.temperature_c,
                                  float(np.ptp(rec.displacement_mm)) / 2)  # full scale: half the span
        assert float(r["drift_ppm_fs_per_c"]) == pytest.approx(want, rel=1e-3)
        # compensated far better than the raw sensor
        assert float(r["max_error_mm"]) < float(r["raw_max_error_mm"]) / 5
        html = (out / name / "certificate.html").read_text()
        assert "drift_ppm_fs_per_c (hardware)" in html
        # the summary's figures are on the certificate, as on a one-temperature sensor's
        cells = dict(re.findall(r"<t[hd][^>]*>([^<]+)</t[hd]><td[^>]*>([^<]+)</td>", html))
        assert cells["ratio to the limit"] == f"{float(r['ratio_to_limit']):.3g}"
        assert cells["compensated max error, whole recording"].startswith(f"{float(r['max_error_mm']):.4g} ")
        assert "box method" in html and "{" not in html.split("<body")[1].split("<svg")[0]
        assert "Verdict at each calibration temperature" in html
        for t in ("-20 degC", "25 degC", "80 degC"):  # the legend: one curve per temperature
            assert f">{t}</text>" in html
        assert html.count("<polyline") >= 2 * len(TEMPS)


def test_single_temperature_recording_is_refused_by_a_temperature_design(line, tmp_path):
    rec = recording(SENSORS["a"], seed=9)
    one = rec.subset(rec.temperature_c == 25.0)
    p = tmp_path / "one.csv"
    write_recordings(p, one)
    rc = main(["calibrate", str(p), "--design", str(line["design"]), "-o", str(tmp_path / "o"), "-j", "1"])
    assert rc == 2
    with open(tmp_path / "o" / "summary.csv", newline="") as fh:
        row = next(csv.DictReader(fh))
    assert row["verdict"] == "FAIL" and "temperature" in row["reason"]


@pytest.mark.sim
def test_sim_finds_a_wrong_rounding_in_the_vhdl(line, tmp_path):
    """The bench can fail: the Horner step's rounding constant zeroed in a copy of the VHDL."""
    bad = tmp_path / "bad"
    shutil.copytree(line["design"], bad)
    top = bad / "flann_family_thermal_top.vhd"
    text = top.read_text()
    head, sep, rest = text.partition("constant half_t_c   : signed(")
    width, _, tail = rest.partition(" downto 0) := \"")
    literal, _, after = tail.partition('"')
    assert sep and "1" in literal
    top.write_text(head + sep + width + " downto 0) := \"" + "0" * len(literal) + '"' + after)
    out = tmp_path / "sim.json"
    assert main(["sim", str(bad), "--summary-json", str(out)]) == 1
    assert json.loads(out.read_text())["mismatches"] > 0


def test_calibrated_models_make_the_same_images(line):
    """The two-input model.json calibrate writes is a family member as it is: a design generated
    from them holds the images calibrate wrote (one fit, one encoding)."""
    out = line["dir"] / "out"
    if not (out / "summary.csv").is_file():
        assert main(["calibrate", *map(str, line["paths"]), "--design", str(line["design"]), "-o", str(out),
                     "-j", "1", "--diagnosis-points", "60"]) == 0
    models = [out / n / "model.json" for n in SENSORS]
    again = line["dir"] / "from_models"
    assert main(["gen", "--family", *map(str, models), "-o", str(again), "--input-bits", "8",
                 "--temp-bits", "8", "--temp-lsb-c", "1"]) == 0
    man = json.loads((again / "manifest.json").read_text())
    assert man["datapath"] == "family_thermal"
    # every file is model.json: the members are named by their sensors' folders
    for n in SENSORS:
        assert parse_hex((again / f"image_{n}.hex").read_text()) == \
            parse_hex((out / n / "weights.hex").read_text())
