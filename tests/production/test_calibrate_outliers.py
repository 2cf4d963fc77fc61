"""A gross outlier in a production recording (a glitch of the reading, not the sensor): the
family's sizing and flann calibrate leave it out with one warning naming its line, as flann
train does, so one reading cannot bend a sensor's weights or fail a good sensor; a failed
sensor's row and certificate name no model (none is written)."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from flann.cli import main
from flann.golden.model import load_model
from flann.recordings import write_recordings

from test_calibrate_closed_form import sweep

GLITCH_ROW = 100        # an interior reading on the way up, 1 V off (about 2000 noise units)


def _rows(path):
    with open(path, newline="") as fh:
        return {r["sensor"]: r for r in csv.DictReader(fh)}


@pytest.fixture(scope="module")
def line(tmp_path_factory):
    d = tmp_path_factory.mktemp("glitch")
    clean, other = sweep(3.0, 0.02, seed=0), sweep(3.1, -0.01, seed=1)
    v = clean.voltage_v.copy()
    v[GLITCH_ROW] += 1.0
    glitched = type(clean)(displacement_mm=clean.displacement_mm, voltage_v=v, direction=clean.direction)
    for name, rec in (("clean", clean), ("glitched", glitched), ("other", other)):
        write_recordings(d / f"{name}.csv", rec)
    rows = [ln.split(",") for ln in (d / "glitched.csv").read_text().splitlines()]
    file_line = next(k + 1 for k, cols in enumerate(rows)
                     if len(cols) > 1 and cols[1][:1] in "-.0123456789" and abs(float(cols[1]) - v[GLITCH_ROW]) < 1e-6)
    return {"dir": d, "line": file_line}


def test_the_family_sizing_leaves_the_outlier_out_with_one_warning(line, capsys):
    d = line["dir"]
    assert main(["gen", "--family", str(d / "glitched.csv"), str(d / "other.csv"), "-o", str(d / "design"),
                 "--json"]) == 0
    out, err = capsys.readouterr()
    err = err.splitlines()
    said = [ln for ln in err if "gross outlier" in ln]
    assert len(said) == 1 and f"line {line['line']}" in said[0] and "glitched.csv" in said[0], err
    man = json.loads(out)
    own = {c["name"]: c["own_rms_mm"] for c in man["terms_chosen"]}
    assert own["glitched"] < 1.5 * own["other"], own     # the glitch would dominate the held-out RMS


def test_calibrate_fits_and_judges_without_the_outlier(line, capsys):
    d = line["dir"]
    if not (d / "design").is_dir():
        assert main(["gen", "--family", str(d / "clean.csv"), str(d / "other.csv"), "-o", str(d / "design")]) == 0
    rc = main(["calibrate", str(d / "clean.csv"), str(d / "glitched.csv"), "-o", str(d / "out"),
               "--design", str(d / "design"), "-j", "1"])
    rows = _rows(d / "out" / "summary.csv")
    assert rc == 0, rows
    said = [ln for ln in capsys.readouterr().err.splitlines() if "gross outlier" in ln]
    assert len(said) == 1 and said[0].startswith("warning: glitched: ") and f"line {line['line']}" in said[0]
    clean, glitched = rows["clean"], rows["glitched"]
    assert glitched["status"] == "ok" and f"line {line['line']}" in glitched["warnings"]
    assert "gross outlier" not in clean["warnings"]
    # one reading left out of ~600: the same model within a small part of the error it reaches
    m0, m1 = (load_model(d / "out" / s / "model.json") for s in ("clean", "glitched"))
    v = np.linspace(-2.5, 2.5, 2001)      # inside both sensors' calibrated range
    moved = float(np.max(np.abs(m0.predict(v) - m1.predict(v))))
    assert moved < 0.1 * float(clean["max_error_mm"]), (moved, clean["max_error_mm"])
    assert float(glitched["max_error_mm"]) < 1.2 * float(clean["max_error_mm"])
    html = (d / "out" / "glitched" / "certificate.html").read_text()
    assert "gross outlier" in html and f"line {line['line']}" in html


def test_a_failed_sensor_names_no_model(line):
    d = line["dir"]
    if not (d / "design").is_dir():
        assert main(["gen", "--family", str(d / "clean.csv"), str(d / "other.csv"), "-o", str(d / "design")]) == 0
    rc = main(["calibrate", str(d / "clean.csv"), "-o", str(d / "tight"), "--design", str(d / "design"),
               "--max-error-mm", "1e-6"])
    row = _rows(d / "tight" / "summary.csv")["clean"]
    assert rc == 1 and row["verdict"] == "FAIL" and row["model_sha256"] == ""
    assert not (d / "tight" / "clean" / "model.json").exists()
    assert "no model: not calibrated" in (d / "tight" / "clean" / "certificate.html").read_text()
