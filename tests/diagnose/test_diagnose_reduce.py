"""`flann diagnose` on long recordings: beyond --max-points it diagnoses means of neighbouring
readings (and says so); shorter recordings are diagnosed exactly as before."""

import json

import numpy as np

from flann.cli import main
from flann.diagnose.data import MAX_POINTS, find_passes, reduce_points
from flann.golden.paper import s_curve
from flann.recordings import Recordings


def _sweeps(n_sweeps, positions, temperature=None):
    """Out-and-back sweeps over ``positions`` (row order only, no direction column)."""
    x = np.concatenate([positions if k % 2 == 0 else positions[::-1] for k in range(n_sweeps)])
    t = None if temperature is None else np.repeat(temperature, positions.size)
    return Recordings(displacement_mm=x, voltage_v=s_curve(x, 1e-3), temperature_c=t)


def test_short_recording_is_untouched():
    rec = _sweeps(2, np.arange(-30.0, 30.5, 0.5))
    assert reduce_points(rec, MAX_POINTS) == (rec, "")
    assert reduce_points(rec, 0) == (rec, "")


def test_few_long_passes_are_means_inside_each_pass():
    # three temperatures, out and back at each: a mean never mixes two passes
    rec = _sweeps(6, np.arange(-30.0, 30.001, 0.01), temperature=[-20, -20, 25, 25, 80, 80])
    small, how = reduce_points(rec, 600)
    assert 500 <= len(small) <= 650
    assert "means of the 36006 readings" in how and "passes" not in how
    assert set(np.unique(small.temperature_c)) == {-20.0, 25.0, 80.0}
    passes = find_passes(small.displacement_mm, None)
    assert len(passes.runs) == 6
    assert small.displacement_mm.min() < -29.5 and small.displacement_mm.max() > 29.5


def test_many_short_sweeps_keep_every_position():
    # the tester's 900,000-row file in small: 1 mm steps from -30 to 29, then back to -30
    n = 60_000
    x = (np.arange(n) % 60 - 30).astype(float)
    rec = Recordings(displacement_mm=x, voltage_v=0.17 * x)
    small, how = reduce_points(rec, 1_000)
    assert len(small) <= 1_100
    assert "each position of a pass" in how and "consecutive passes" in how
    # every position is kept, each a mean of the same readings (the ramp stays exact)
    assert np.unique(small.displacement_mm).size == 60
    np.testing.assert_allclose(small.voltage_v, 0.17 * small.displacement_mm, atol=1e-12)


def test_rows_in_no_order_are_sampled(tmp_path):
    rng = np.random.default_rng(1)
    x = rng.uniform(-30, 30, 3_000)
    rec = Recordings(displacement_mm=x, voltage_v=s_curve(x))
    small, how = reduce_points(rec, 500)
    assert len(small) == 500 and "evenly sampled" in how
    assert np.all(np.isin(small.displacement_mm, x))


def test_cli_says_it_diagnosed_means(tmp_path, capsys):
    rec = _sweeps(4, np.arange(-30.0, 30.01, 0.1))
    path = tmp_path / "long.csv"
    path.write_text("displacement_mm,voltage_v\n" + "".join(
        f"{a:.2f},{b:.6f}\n" for a, b in zip(rec.displacement_mm, rec.voltage_v)))
    out = tmp_path / "d.json"
    assert main(["diagnose", str(path), "--max-points", "600", "--quiet", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    notes = [line for line in text.splitlines() if "means of the 2404 readings" in line]
    assert len(notes) == 1 and notes[0].startswith("note: ")
    d = json.loads(out.read_text())
    assert d["reduced"]["readings"] == 2404 and d["reduced"]["points"] <= 650
    # the same file with every row: no note, no "reduced"
    assert main(["diagnose", str(path), "--max-points", "0", "--quiet", "--json", str(out)]) == 0
    assert "means of the" not in capsys.readouterr().out
    assert "reduced" not in json.loads(out.read_text())
