"""The two-input model x(v, T): its file, its training, the drift metric and the commands."""

import json

import numpy as np
import pytest

from flann.cli import main
from flann.errors import ModelFileError
from flann.golden.model import load_model
from flann.golden.thermal import FORMAT, ThermalModel, corrected_voltage, load_any_model
from flann.golden.thermal_metrics import by_temperature, drift_ppm_fs_per_c
from flann.golden.thermal_train import fit_thermal, fit_thermal_auto


def run(argv, capsys):
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


def sensor_v(x, temp):
    """A tanh sensor (stroke +-10 mm) whose gain falls 0.02 %/degC and null moves 3 ppm/degC."""
    dt = np.asarray(temp, dtype=float) - 25.0
    return 2.0 * (1 - 2e-4 * dt) * np.tanh(x / 12.0) / np.tanh(10 / 12.0) + 2.0 * 3e-6 * dt


def calibration(temps=(-20.0, 25.0, 80.0), n=41):
    x = np.linspace(-10, 10, n)
    xs = np.tile(x, len(temps))
    ts = np.repeat(temps, n)
    return xs, np.round(sensor_v(xs, ts) / 1e-5) * 1e-5, ts


def write_csv(path, x, v, t=None):
    head = "displacement_mm,voltage_v" + (",temperature_c" if t is not None else "")
    rows = [f"{float(a)!r},{float(b)!r}" + (f",{float(c)!r}" if t is not None else "")
            for a, b, c in zip(x, v, t if t is not None else x)]
    path.write_text(head + "\n" + "\n".join(rows) + "\n")
    return path


def small_model():
    return ThermalModel(weights=((1.0, 0.2, -0.1), (0.05,), ()), bias=(0.3, -0.02, 0.004),
                        input_offset_v=0.1, input_scale_v=2.0, temperature_offset_c=30.0,
                        temperature_scale_c=50.0, input_gain_t=(0.01, -0.001),
                        input_offset_t_v=(0.002, 0.0001), voltage_range_v=(-2.0, 2.0),
                        temperature_range_c=(-20.0, 80.0), displacement_range_mm=(-10.0, 10.0))


# -- model -----------------------------------------------------------------------------
def test_predict_is_the_term_by_term_sum_written_out():
    m = small_model()
    v = np.linspace(-2, 2, 7)
    temp = np.linspace(-20, 80, 7)
    t = (temp - 30.0) / 50.0
    vc = v * (1 + 0.01 * t - 0.001 * t ** 2) + 0.002 * t + 0.0001 * t ** 2
    vn = (vc - 0.1) / 2.0
    f0 = 0.3 + 1.0 * vn + 0.2 * np.sin(np.pi * vn) - 0.1 * np.cos(np.pi * vn)
    f1 = -0.02 + 0.05 * vn
    f2 = 0.004
    np.testing.assert_allclose(m.predict(v, temp), f0 + t * f1 + t ** 2 * f2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m.predict_direct(v, temp), m.predict(v, temp), atol=1e-12)
    np.testing.assert_allclose(corrected_voltage(v, t, (), ()), v)


def test_file_round_trip_and_both_kinds_load(tmp_path, default_model_json):
    m = small_model()
    p = tmp_path / "m.json"
    m.save(p)
    d = json.loads(p.read_text())
    assert d["format"] == FORMAT and d["inputs"] == ["voltage_v", "temperature_c"]
    assert d["terms"] == [3, 1, 0]
    back = load_any_model(p)
    assert back == m
    one = load_any_model(default_model_json)
    assert one == load_model(default_model_json) and one.inputs == ("voltage_v",)
    assert back.inputs == ("voltage_v", "temperature_c")
    assert "inputs" not in json.loads(default_model_json.read_text())
    with pytest.raises(ModelFileError):   # the one-input loader refuses it in one line
        load_model(p)
    d["inputs"] = ["voltage_v"]
    p.write_text(json.dumps(d))
    with pytest.raises(ModelFileError, match="inputs"):
        load_any_model(p)
    d["inputs"] = ["voltage_v", "temperature_c"]
    d["terms"] = [3, 1, 1]
    p.write_text(json.dumps(d))
    with pytest.raises(ModelFileError, match="terms"):
        load_any_model(p)


# -- metrics ---------------------------------------------------------------------------
def test_drift_is_the_largest_change_of_error_per_degc_in_ppm_of_full_scale():
    x = np.tile(np.linspace(-10, 10, 21), 3)
    temp = np.repeat([0.0, 20.0, 50.0], 21)
    # error grows 1 um per degC at +10 mm, none at -10 mm; plus a constant that must not count
    err = 1e-3 * (temp / 1.0) * (x + 10) / 20 + 0.05
    # largest change: 1 um per degC at x = +10 mm; full scale 10 mm -> 100 ppm FS/degC
    assert drift_ppm_fs_per_c(err, x, temp, 10.0) == pytest.approx(100.0)
    rows = by_temperature(err, temp)
    assert [r["temperature_c"] for r in rows] == [0.0, 20.0, 50.0]
    assert rows[2]["max_error_mm"] == pytest.approx(0.05 + 0.05)
    assert drift_ppm_fs_per_c(err[:21], x[:21], temp[:21], 10.0) is None


def test_drift_is_the_box_method_over_the_whole_temperature_range():
    # a position read 0.01 mm high at 10 degC only (a converter step, say): the change across
    # the recorded temperatures (0..50 degC) is 0.01 mm, per degC of that range -- not per the
    # closest pair's 10 degC, which would make it 5x larger
    x = np.tile(np.linspace(-10, 10, 21), 3)
    temp = np.repeat([0.0, 10.0, 50.0], 21)
    err = np.where((temp == 10.0) & (x == 0.0), 0.01, 0.0)
    assert drift_ppm_fs_per_c(err, x, temp, 10.0) == pytest.approx(0.01 / 50 / 10 * 1e6)


def test_drift_interpolates_positions_one_temperature_lacks():
    xa, xb = np.linspace(-10, 10, 21), np.linspace(-10, 10, 8)
    x = np.concatenate([xa, xb])
    temp = np.concatenate([np.zeros(21), np.full(8, 10.0)])
    err = np.concatenate([0 * xa, 0.002 * xb])   # linear: interpolation is exact
    assert drift_ppm_fs_per_c(err, x, temp, 10.0) == pytest.approx(0.02 / 10 / 10 * 1e6)


# -- training --------------------------------------------------------------------------
def test_auto_compensates_between_the_calibration_temperatures():
    x, v, t = calibration()
    model, choice = fit_thermal_auto(v, t, x)
    assert model.orders <= 3 and choice.coefficients == model.coefficients
    xh = np.linspace(-10, 10, 401)
    worst_raw, worst = 0.0, 0.0
    base = model.predict(sensor_v(xh, 25.0), 25.0) - xh
    for temp in (-10.0, 10.0, 40.0, 65.0):
        e = model.predict(sensor_v(xh, temp), temp) - xh
        assert np.max(np.abs(e)) < 0.002              # 200 ppm of the 10 mm full scale
        worst = max(worst, np.max(np.abs(e - base)) / abs(temp - 25) / 10 * 1e6)
        # the sensor read at 25 degC's calibration: how much temperature moves it uncompensated
        e_raw = (np.interp(sensor_v(xh, temp), sensor_v(xh, 25.0), xh) - xh)
        worst_raw = max(worst_raw, np.max(np.abs(e_raw)) / abs(temp - 25) / 10 * 1e6)
    assert worst_raw > 100 and worst < 5


def test_fit_without_input_correction_is_the_plain_product_expansion():
    x, v, t = calibration()
    m = fit_thermal(v, t, x, (7, 3), correct_input=False)
    assert m.input_gain_t == () and m.input_offset_t_v == () and m.terms == (7, 3)


# -- commands --------------------------------------------------------------------------
def test_train_eval_predict_with_temperature(tmp_path, capsys):
    x, v, t = calibration()
    cal = write_csv(tmp_path / "cal.csv", x, v, t)
    model = tmp_path / "m.json"
    rc, _, err = run(["train", cal, "--temperature", "-o", model], capsys)
    assert rc == 0 and "held-out" in err and "temperatures" in err
    assert json.loads(model.read_text())["inputs"] == ["voltage_v", "temperature_c"]
    xh = np.tile(np.linspace(-10, 10, 101), 2)
    th = np.repeat([10.0, 40.0], 101)
    held = write_csv(tmp_path / "held.csv", xh, sensor_v(xh, th), th)
    rc, out, _ = run(["eval", model, held, "--json"], capsys)
    res = json.loads(out)
    assert rc == 0
    assert set(res["drift_ppm_fs_per_c"]) == {"raw", "float", "hardware"}
    assert res["drift_ppm_fs_per_c"]["hardware"] is None
    assert res["drift_ppm_fs_per_c"]["raw"] > 10 * res["drift_ppm_fs_per_c"]["float"]
    # by_temperature: in each figure's own section (compensated = the float model), not repeated
    assert "by_temperature" not in res and "hardware" not in res
    assert [r["temperature_c"] for r in res["compensated"]["by_temperature"]] == [10.0, 40.0]
    assert set(res["raw"]["by_temperature"][0]) >= {"temperature_c", "max_error_mm", "rms_error_mm"}
    m = load_any_model(model)
    e = np.abs(m.predict(*m.clamp(sensor_v(xh, th), th)[:2]) - xh)
    assert res["compensated"]["by_temperature"][1]["max_error_mm"] == pytest.approx(e[101:].max(), rel=1e-4)
    rc, out, _ = run(["eval", model, held], capsys)
    assert rc == 0 and "drift (ppm FS/degC)" in out
    pred = tmp_path / "p.csv"
    assert run(["predict", model, held, "-o", pred], capsys)[0] == 0
    lines = pred.read_text().splitlines()
    assert lines[0].split(",")[:3] == ["voltage_v", "temperature_c", "displacement_mm"]
    no_temp = write_csv(tmp_path / "nt.csv", xh, sensor_v(xh, th))
    rc, _, err = run(["eval", model, no_temp], capsys)
    assert rc == 2 and "temperature_c" in err and "Traceback" not in err
    rc, _, err = run(["predict", model, no_temp, "-o", tmp_path / "q.csv"], capsys)
    assert rc == 2 and not (tmp_path / "q.csv").exists()


def test_train_temperature_refusals(tmp_path, capsys):
    x, v, t = calibration(temps=(25.0,))
    one = write_csv(tmp_path / "one.csv", x, v, t)
    rc, _, err = run(["train", one, "--temperature", "-o", tmp_path / "m.json"], capsys)
    assert rc == 2 and "2 or more temperatures" in err and not (tmp_path / "m.json").exists()
    x, v, t = calibration()
    cal = write_csv(tmp_path / "cal.csv", x, v, t)
    rc, _, err = run(["train", cal, "--temperature", "--method", "lms", "-o", tmp_path / "m.json"], capsys)
    assert rc == 2 and "--method" in err and not (tmp_path / "m.json").exists()
    # --terms N sets the expansion per temperature order (a hardware that must fit a part)
    rc, _, err = run(["train", cal, "--temperature", "--terms", "5", "-o", tmp_path / "m.json"], capsys)
    assert rc == 0, err
    assert set(json.loads((tmp_path / "m.json").read_text())["terms"]) == {5}


def test_one_line_says_a_multi_temperature_recording_could_be_compensated(tmp_path, capsys):
    # the note is said as the recording is read, before any fit and whatever --terms is: a
    # 5-term fit follows it here (--terms auto fitted the forward curve for 15 s to no purpose)
    x, v, t = calibration()
    cal = write_csv(tmp_path / "cal.csv", x, v, t)
    _, _, err = run(["train", cal, "--terms", "5", "-o", tmp_path / "m.json"], capsys)
    hint = [ln for ln in err.splitlines() if "could be compensated" in ln]
    assert len(hint) == 1 and "-20, 25, 80 degC" in hint[0] and "--temperature" in hint[0]
    x, v, t = calibration(temps=(25.0, 30.0))
    two = write_csv(tmp_path / "two.csv", x, v, t)
    _, _, err = run(["train", two, "--terms", "5", "-o", tmp_path / "m2.json"], capsys)
    assert "could be compensated" not in err


def test_one_input_eval_json_without_temperature_is_unchanged(tmp_path, capsys, default_model_json):
    x = np.linspace(-10, 10, 21)
    rec = write_csv(tmp_path / "r.csv", x, sensor_v(x, 25.0))
    rc, out, _ = run(["eval", default_model_json, rec, "--json"], capsys)
    assert rc == 0
    assert "by_temperature" not in json.loads(out) and "drift_ppm_fs_per_c" not in json.loads(out)


def test_random_tanh_family_compensated_between_and_beside_the_calibration():
    """Sensors the project did not make: v = A g(T) tanh(k(T) x / w) / tanh(k0) + null(T),
    span -0.01..-0.03 %/degC, null +-5 ppm FS/degC, roll-off +-0.01 %/degC; calibrated at
    -20/25/80 degC (18-bit ADC), judged on dense noise-free sweeps at -10, 10, 40, 65 degC."""
    rng = np.random.default_rng(20)
    for _ in range(3):
        fs = float(rng.choice([2.0, 10.0, 40.0]))
        w, k0, amp = fs, rng.uniform(0.8, 1.6), rng.uniform(0.5, 4.0)
        a, n, r = rng.uniform(-3e-4, -1e-4), rng.uniform(-5e-6, 5e-6), rng.uniform(-1e-4, 1e-4)

        def volts(x, temp):
            dt = np.asarray(temp, dtype=float) - 25.0
            k = k0 * (1 + r * dt)
            return amp * ((1 + a * dt) * np.tanh(k * x / w) / np.tanh(k0) + n * dt)

        lsb = 2.2 * amp / 2 ** 18
        x = np.linspace(-fs, fs, 61)
        xs, ts = np.tile(x, 3), np.repeat([-20.0, 25.0, 80.0], x.size)
        model, _ = fit_thermal_auto(np.round(volts(xs, ts) / lsb) * lsb, ts, xs)
        xh = np.linspace(-fs, fs, 801)

        def errors(temps):
            xa, ta = np.tile(xh, len(temps)), np.repeat(temps, xh.size)
            return xa, ta, model.predict(volts(xa, ta), ta) - xa

        _, _, e_cal = errors([-20.0, 25.0, 80.0])
        xa, ta, e_held = errors([-10.0, 10.0, 40.0, 65.0])
        raw = np.interp(volts(xa, ta), volts(xh, 25.0), xh) - xa      # read with 25 degC's curve
        assert drift_ppm_fs_per_c(raw, xa, ta, fs) > 50
        assert drift_ppm_fs_per_c(e_held, xa, ta, fs) <= 10
        for temp in (-10.0, 10.0, 40.0, 65.0):
            assert np.max(np.abs(e_held[ta == temp])) <= 1.5 * np.max(np.abs(e_cal))
