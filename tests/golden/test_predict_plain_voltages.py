"""flann predict of plain voltages (no displacements) with a model whose training left out a
rail or a fold-back: what can still be judged against the trained stroke is said, one line each."""

from pathlib import Path

import numpy as np
import pytest

DATA = Path(__file__).parents[1] / "recordings" / "data"


@pytest.fixture(scope="module")
def models(tmp_path_factory, in_process):
    d = tmp_path_factory.mktemp("plain")
    out = {}
    for name in ("clipped", "cubic"):
        rc, _o, err = in_process(["train", DATA / f"{name}.csv", "-o", d / f"{name}.json", "--terms", 9])
        assert rc == 0, err
        volts = d / f"{name}_v.csv"   # the recording's voltage column alone
        volts.write_text("voltage_v\n" + "".join(ln.split(",")[1] + "\n" for ln in
                                                 (DATA / f"{name}.csv").read_text().splitlines()[1:]))
        out[name] = (d / f"{name}.json", volts)
    return out


def test_readings_at_the_rail_are_counted_and_flagged(models, in_process, tmp_path):
    model, volts = models["clipped"]
    rc, _o, err = in_process(["predict", model, volts, "-o", tmp_path / "p.csv"])
    assert rc == 0, err
    # make_data.py holds the last 7 readings at 4.2 V
    assert "7 of 41 voltages at or past the high rail 4.2 V" in err
    rows = np.loadtxt(tmp_path / "p.csv", delimiter=",", skiprows=1)
    assert rows.shape == (41, 3) and np.all(rows[-7:, 2] == 1)
    assert len([ln for ln in err.splitlines() if "rail" in ln]) == 1


def test_a_fold_back_is_said_once(models, in_process, tmp_path):
    model, volts = models["cubic"]
    rc, _o, err = in_process(["predict", model, volts, "-o", tmp_path / "p.csv"])
    assert rc == 0, err
    assert len([ln for ln in err.splitlines() if "turning point" in ln]) == 1
    assert "-16..16 mm" in err
