"""`flann diagnose` command: JSON schema, bad input (one line, exit 2), fold-back, Table 1."""

import json
import os

import numpy as np
import pytest

from flann.cli import main
from flann.physics.sensor import default_sensor
from flann.physics.simulate import simulate_recordings
from flann.recordings import Recordings, write_recordings


def _write(path, x, y, direction=None):
    rec = Recordings(np.asarray(x, float), np.asarray(y, float),
                     None if direction is None else np.asarray(direction, float))
    write_recordings(path, rec)
    return str(path)


def _bad(argv, capsys, words):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: "), err
    assert words in err[0]


def test_table1_json_plot(tmp_path, capsys):
    out, png = tmp_path / "d.json", tmp_path / "d.png"
    assert main(["diagnose", "data/paper_table1.csv", "--json", str(out), "--plot", str(png),
                 "--quiet"]) == 0
    text = capsys.readouterr().out
    d = json.loads(out.read_text())
    assert list(d) == ["baseline", "noise_v", "regions", "outliers", "effects", "alternatives",
                       "separate_by", "final", "improvement"]
    assert {"rms_v", "params", "shape_term"} <= set(d["baseline"])
    assert "odd" in d["baseline"]["shape_term"]["description"] or \
        d["baseline"]["shape_term"]["terms"] == 0
    assert "local quadratic" in d["baseline"]["noise_method"]
    assert set(d["final"]) == {"rms_v"}
    # the +10 mm / 1.810 V reading: row 8 (0-based), about 1 V below the curve
    assert [o["row"] for o in d["outliers"]] == [8]
    o = d["outliers"][0]
    assert set(o) == {"row", "displacement_mm", "residual_v"}
    assert o["displacement_mm"] == 10.0 and -1.3 < o["residual_v"] < -0.8
    for r in d["regions"]:
        assert set(r) == {"from_mm", "to_mm", "direction", "peak_residual_v"}
        assert r["direction"] in ("+", "-", "both")
    for e in d["effects"]:
        assert {"name", "explanation", "params", "rms_v_after", "delta_bic", "cv_t"} <= set(e)
    assert d["improvement"] == pytest.approx(d["baseline"]["rms_v"] / d["final"]["rms_v"])
    assert "row 8 at 10 mm" in text
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    mask = os.umask(0)
    os.umask(mask)
    assert png.stat().st_mode & 0o777 == 0o666 & ~mask


def test_json_to_stdout(capsys):
    assert main(["diagnose", "data/paper_table1.csv", "--json", "--quiet"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["effects"] == [] or all("name" in e for e in d["effects"])


@pytest.mark.parametrize("x, y, d, words", [
    ([2.0] * 8, np.linspace(-1, 1, 8), None, "does not vary"),
    ([2.0] * 8, [0.5] * 8, None, "identical"),
    (np.linspace(-5, 5, 8), [0.5] * 8, None, "voltage_v"),
])
def test_bad_recordings_exit_2(tmp_path, capsys, x, y, d, words):
    _bad(["diagnose", _write(tmp_path / "r.csv", x, y, d)], capsys, words)


def test_bad_direction_exit_2(tmp_path, capsys):
    p = tmp_path / "r.csv"
    p.write_text("displacement_mm,voltage_v,direction\n" +
                 "".join(f"{i},{i * 0.1},{1 if i != 3 else 2}\n" for i in range(10)))
    _bad(["diagnose", str(p)], capsys, "direction")


def test_other_bad_input_exit_2(tmp_path, capsys):
    _bad(["diagnose", str(tmp_path / "missing.csv")], capsys, "no such file")
    p = tmp_path / "r.csv"
    p.write_text("displacement_mm,voltage_v\n1,abc\n")
    _bad(["diagnose", str(p)], capsys, "not a number")
    _bad(["diagnose"], capsys, "recordings")
    _bad(["diagnose", "--demo", "data/paper_table1.csv"], capsys, "--demo")
    _bad(["diagnose", "data/paper_table1.csv", "--sensor", str(tmp_path / "no.toml")], capsys,
         "no such file")


def test_foldback_trimmed_with_warning(tmp_path, capsys):
    # the paper LVDT driven to +-42 mm: the core leaves the coils beyond ~30 mm and the
    # output falls back; the diagnosis keeps the monotonic span and claims nothing
    s = default_sensor().replace(adc_bits=None, adc_full_scale_v=None)
    rec = simulate_recordings(s, step_mm=0.2, noise_v=0.005, seed=7, travel_mm=(-42.0, 42.0))
    p = tmp_path / "fold.csv"
    write_recordings(p, rec)
    assert main(["diagnose", str(p), "--json", str(tmp_path / "f.json"), "--quiet"]) == 0
    cap = capsys.readouterr()
    assert "fold" in cap.err and cap.err.startswith("warning: ")
    d = json.loads((tmp_path / "f.json").read_text())
    assert d["effects"] == [] and d["regions"] == []


def test_interior_foldback_refused(tmp_path, capsys):
    x = np.linspace(-30, 30, 200)
    _bad(["diagnose", _write(tmp_path / "r.csv", x, np.sin(x / 4.0))], capsys, "no inverse")


def test_text_report_names_effect(tmp_path, capsys):
    s = default_sensor().replace(adc_bits=None, adc_full_scale_v=None)
    s = s.with_effect("backlash", deadband_mm=0.06)
    rec = simulate_recordings(s, step_mm=0.2, noise_v=0.005, seed=8)
    p = tmp_path / "bl.csv"
    write_recordings(p, rec)
    assert main(["diagnose", str(p), "--plot", str(tmp_path / "bl.png"), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "1. backlash: the residual changes sign with the direction of travel" in out
    assert "deadband_mm = " in out and "RMS " in out and "improvement" in out
    assert "nothing missing" not in out
