"""--terms auto: the readings near the flat ends of the stroke settled onto a forward fit."""

import numpy as np

from flann.cli import main
from flann.golden.forward import END_BLEND, END_WINDOWS, settle_ends
from flann.golden.model import load_model


def arctan_sensor(x):
    # our own flat-ended curve (slope at +-20 mm is 1/7 of the null's)
    return 3.0 * np.arctan(x / 8.0)


def sweeps(positions, noise_v, seed):
    x = np.linspace(-20.0, 20.0, positions)
    xs = np.concatenate([x, x[::-1]])
    rng = np.random.default_rng(seed)
    return xs, arctan_sensor(xs) + rng.normal(0.0, noise_v, xs.size)


def test_readings_on_a_low_order_curve_stay_where_they_are():
    x = np.linspace(0.0, 10.0, 60)
    v = 0.2 + 0.5 * x - 0.01 * x ** 2 + 3e-4 * x ** 3
    got = settle_ends(x, v)
    assert np.max(np.abs(got.voltage_v - v)) < 1e-9
    assert min(got.degrees) >= 1


def test_noisy_flat_ends_come_closer_to_the_curve_and_the_middle_is_untouched():
    x, v = sweeps(200, 0.002, seed=5)
    got = settle_ends(x, v)
    xu = np.unique(x)
    raw = np.array([v[x == a].mean() for a in xu])
    settled = np.array([got.voltage_v[x == a].mean() for a in xu])
    truth = arctan_sensor(xu)
    outer = (xu < -19.0) | (xu > 19.0)
    assert np.mean(np.abs(settled - truth)[outer]) < 0.8 * np.mean(np.abs(raw - truth)[outer])
    middle = np.abs(xu) < 20.0 - 40.0 * max(END_WINDOWS)
    assert np.array_equal(settled[middle], raw[middle])
    # the readings of one position move together: their scatter is kept
    first, second = got.voltage_v[:200], got.voltage_v[200:][::-1]
    assert np.allclose(first - second, v[:200] - v[200:][::-1], atol=1e-12)


def test_too_few_positions_are_left_as_read():
    x, v = sweeps(13, 0.002, seed=1)
    got = settle_ends(x, v)
    assert got.degrees == (0, 0) and np.array_equal(got.voltage_v, v)


def test_the_training_record_says_how_the_ends_were_settled(tmp_path, capsys):
    x, v = sweeps(80, 0.001, seed=3)
    rec = tmp_path / "rec.csv"
    rec.write_text("displacement_mm,voltage_v\n" + "".join(f"{a:.6g},{b:.9g}\n" for a, b in zip(x, v)))
    assert main(["train", str(rec), "-o", str(tmp_path / "m.json")]) == 0
    capsys.readouterr()
    ends = load_model(tmp_path / "m.json").training["ends_settled"]
    assert all(w in END_WINDOWS for w in ends["windows"]) and all(d >= 1 for d in ends["degrees"])
