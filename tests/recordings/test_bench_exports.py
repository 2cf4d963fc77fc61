"""Bench exports as a new user has them (tests/recordings/data, written by make_data.py):
every command reads them, and train, eval, predict, diagnose and calibrate leave out the same readings
and keep the same usable stroke, each saying so in one line."""

import json
import re
from pathlib import Path

import numpy as np
import pytest

from flann.golden.screen import ready_for_fit
from flann.recordings import read_recordings

DATA = Path(__file__).parent / "data"
# file -> (the file lines the shared reading must leave out, at least; the usable stroke)
CASES = {
    "clipped.csv": ({36, 37, 38, 39, 40, 41, 42}, (-20.0, 13.0)),
    "cubic.csv": ({2, 3, 21, 22}, (-16.0, 16.0)),
    "rough_s_curve.csv": ({11, 25}, (0.0, 44.0)),
    "title_export.csv": (set(), (-20.0, 20.0)),
    "german_export.csv": (set(), (-20.0, 20.0)),
    "ab_export.csv": (set(), (-20.0, 20.0)),
}
LEFT_OUT = re.compile(r"^warning: .*(left out|turns back).*$", re.MULTILINE)


def _lines_named(text: str) -> set[int]:
    """The file lines named by the 'left out' lines of a command's stderr."""
    named = set()
    for line in (m.group(0) for m in LEFT_OUT.finditer(text)):
        named |= {int(n) for n in re.findall(r"line (\d+)", line)}
    return named


@pytest.fixture(scope="session")
def trained(once, in_process):
    """Each export trained once per run (every worker shares it): {name: (model, (rc, out, err))}.
    Nine terms, not the default search: the reading and its screens come before the fit and
    do not depend on it (tests/golden covers `--terms auto`)."""
    def make(d):
        return {name: (d / (name + ".json"),
                       in_process(["train", DATA / name, "-o", d / (name + ".json"), "--terms", "9"]))
                for name in CASES}
    return once("bench-exports-trained", make)


@pytest.mark.parametrize("command", ["train", "eval", "predict", "diagnose", "calibrate"])
@pytest.mark.parametrize("name", sorted(CASES))
def test_commands_share_one_reading(trained, name, command, in_process, tmp_path):
    must, stroke = CASES[name]
    model, (rc, _out, err) = trained[name]
    assert rc == 0, err
    train_named = _lines_named(err)
    if command == "train":
        named, text = train_named, err
        lo, hi = (float(v) for v in re.search(r"usable stroke (\S+)\.\.(\S+) mm", err).groups())
        assert (lo, hi) == stroke
        assert len(re.findall(r"^verdict: ", err, re.MULTILINE)) == 1
    elif command == "eval":
        rc, out, text = in_process(["eval", model, DATA / name])
        assert rc == 0, text
        named = _lines_named(text)
        assert len(re.findall(r"^verdict: GOOD", out, re.MULTILINE)) == 1
    elif command == "predict":   # the usable stroke's rows written, the rest counted
        rc, _out, text = in_process(["predict", model, DATA / name, "-o", tmp_path / "p.csv"])
        assert rc == 0, text
        named = _lines_named(text)
        x = np.loadtxt(tmp_path / "p.csv", delimiter=",", skiprows=1, usecols=1)
        assert (x.min(), x.max()) == stroke
        rows = len(read_recordings(DATA / name, announce=False))
        assert x.size == json.loads(model.read_text())["training"]["readings_used"], text
        assert (f"predicted {x.size} of {rows} readings" in text) == (x.size < rows)
    elif command == "diagnose":
        rc, _out, text = in_process(["diagnose", DATA / name, "--max-points", "0"])
        assert rc == 0, text
        named = _lines_named(text)
    else:   # calibrate's members are made ready by this one function
        rec, said = ready_for_fit(read_recordings(DATA / name, announce=False))
        named = {int(n) for n in re.findall(r"line (\d+)", said)} if said else set()
        kept = {int(n) for n in rec.lines}
        assert not kept & must
        assert (rec.displacement_mm.min(), rec.displacement_mm.max()) == stroke
        text = said
    assert must <= named | _all_listed(text, must), (command, text)
    # each command says what it left out in one line per kind, never more
    assert len(LEFT_OUT.findall(text)) <= 2


def _all_listed(text: str, must: set[int]) -> set[int]:
    """A line lists the first readings and 'N more': those are the rest of a run."""
    return must if re.search(r"and \d+ more", text) else set()


def test_four_sensors_select_by_id(tmp_path, in_process):
    rc, _o, err = in_process(["train", DATA / "four_sensors.csv", "-o", tmp_path / "m.json"])
    assert rc == 2 and "4 sensors" in err and "--sensor" in err and len(err.strip().splitlines()) == 1
    rc, _o, err = in_process(["train", DATA / "four_sensors.csv", "--sensor", "LV-103", "-o", tmp_path / "m.json"])
    assert rc == 0, err
    assert "sensor LV-103 of 4" in err


def test_ab_is_the_ratiometric_output():
    rec = read_recordings(DATA / "ab_export.csv", announce=False)
    a_b = np.loadtxt(DATA / "ab_export.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(rec.voltage_v, (a_b[:, 1] - a_b[:, 2]) / (a_b[:, 1] + a_b[:, 2]))
    assert "(A - B)/(A + B)" in rec.recognised


def test_eval_warns_when_compensation_is_worse_than_the_line(tmp_path, in_process):
    """A model of another sensor (LV-101) on the A/B export's ratio: compensated worse than the
    straight line through the same readings, said, and exit 1 under --strict."""
    m = tmp_path / "m.json"
    assert in_process(["train", DATA / "four_sensors.csv", "--sensor", "LV-101", "-o", m])[0] == 0
    rc, out, err = in_process(["eval", m, DATA / "ab_export.csv", "--json"])
    res = json.loads(out)
    assert res["compensated"]["max_error_mm"] > res["raw"]["max_error_mm"]
    assert res["verdict"]["status"] == "bad" and rc == 0
    rc, out, _err = in_process(["eval", m, DATA / "ab_export.csv", "--strict"])
    assert rc == 1 and "compensated worse than the straight line" in out


def test_paper_exact_fit_verdict_is_bad(tmp_path, in_process):
    root = Path(__file__).parents[2]
    rc, _o, err = in_process(["train", root / "data" / "paper_table1.csv", "--terms", "51", "-o", tmp_path / "m.json",
                           "--strict"])
    assert rc == 1 and "verdict: BAD" in err


def test_sound_end_readings_of_an_s_curve_are_kept():
    """The two glitches of the rough S-curve, and only they: its end readings, where a
    high-degree fit held out swings, are the curve's."""
    from flann.golden.reading import read_usable

    reading = read_usable(read_recordings(DATA / "rough_s_curve.csv", announce=False))
    assert {int(line.split()[1]) for line in reading.lines_left_out} == CASES["rough_s_curve.csv"][0]
