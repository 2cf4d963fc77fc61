"""`flann paper --data` on a recording that repeats positions (more sweeps, out and back):
repeated readings are data, averaged per position where an interpolant x(v) needs a
strictly increasing voltage."""

from __future__ import annotations

import numpy as np

from flann.cli import main
from flann.golden.paper import (TABLE1_DISPLACEMENT_MM, TABLE1_VOLTAGE_V, between_points,
                                paper_model, table1)
from flann.recordings import Recordings


def _out_and_back(noise_v=0.0):
    x = np.r_[TABLE1_DISPLACEMENT_MM, TABLE1_DISPLACEMENT_MM[::-1]]
    v = np.r_[TABLE1_VOLTAGE_V, TABLE1_VOLTAGE_V[::-1]]
    if noise_v:
        v = v + np.r_[np.zeros(13), np.random.default_rng(3).normal(0.0, noise_v, 13)]
    return x, v


def test_repeated_positions_give_the_same_sweep_as_one_pass():
    model = paper_model(table1(), 11, epochs=50)
    x, v = _out_and_back()
    twice = between_points(model, Recordings(displacement_mm=x, voltage_v=v))
    once = between_points(model, table1())
    np.testing.assert_array_equal(twice["ref"], once["ref"])
    assert twice["max_dev_from_pchip_mm"] == once["max_dev_from_pchip_mm"]


def test_repeats_that_differ_are_averaged_per_position():
    model = paper_model(table1(), 11, epochs=50)
    x, v = _out_and_back(noise_v=0.01)
    sweep = between_points(model, Recordings(displacement_mm=x, voltage_v=v))
    means = (v[:13] + v[13:][::-1]) / 2
    at = np.searchsorted(sweep["v"], means[1:-1])
    # the interpolant passes through each position's mean reading (to the sweep's grid)
    assert np.max(np.abs(sweep["ref"][at] - TABLE1_DISPLACEMENT_MM[1:-1])) < 0.5


def test_paper_data_with_two_sweeps(tmp_path, capsys):
    x, v = _out_and_back()
    path = tmp_path / "two.csv"
    rows = "".join(f"{a:g},{float(b)!r}\n" for a, b in zip(x, v))
    path.write_text("displacement_mm,voltage_v\n" + rows)
    assert main(["paper", "--data", str(path), "--epochs", "50"]) == 0
    cap = capsys.readouterr()
    assert cap.err == ""
    assert "Between the 26 points (13 positions: repeated readings averaged" in cap.out
    assert cap.out.count("max deviation") == 3
