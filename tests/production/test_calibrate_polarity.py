"""A sensor whose output falls with displacement where the family's rises (secondaries
swapped) calibrates, since its weights invert either slope, but its row, certificate and a
warning line say the output is reversed; a sensor of the family's polarity says nothing."""

from __future__ import annotations

import csv

from flann.cli import main
from flann.recordings import write_recordings

from test_calibrate_closed_form import sweep


def test_a_reversed_output_is_named(tmp_path, capsys):
    for name, (amp, asym, seed) in {"a": (3.0, 0.02, 0), "b": (3.1, -0.01, 1), "flipped": (-3.05, 0.0, 2),
                                    "same": (3.05, 0.0, 3)}.items():
        write_recordings(tmp_path / f"{name}.csv", sweep(amp, asym, seed))
    assert main(["gen", "--family", str(tmp_path / "a.csv"), str(tmp_path / "b.csv"), "-o",
                 str(tmp_path / "d"), "--terms", "15"]) == 0
    capsys.readouterr()
    assert main(["calibrate", str(tmp_path / "flipped.csv"), str(tmp_path / "same.csv"), "-o",
                 str(tmp_path / "out"), "--design", str(tmp_path / "d"), "-j", "1"]) == 0
    err = capsys.readouterr().err.splitlines()
    with open(tmp_path / "out" / "summary.csv", newline="") as fh:
        rows = {r["sensor"]: r for r in csv.DictReader(fh)}
    assert rows["flipped"]["status"] == "ok" and "reversed output" in rows["flipped"]["warnings"]
    assert "reversed output" not in rows["same"]["warnings"]
    assert [ln for ln in err if "reversed output" in ln and "flipped" in ln], err
    assert "reversed output" in (tmp_path / "out" / "flipped" / "certificate.html").read_text()
