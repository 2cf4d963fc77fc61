"""flann calibrate of a file holding several sensors (a sensor column, as a rig exports four
LVDTs): that many sensors, each named by its ID; a bad one is reported and the batch goes on."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import pytest

DATA = Path(__file__).parents[1] / "recordings" / "data"
IDS = ("LV-101", "LV-102", "LV-103", "LV-104")


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory, in_process):
    d = tmp_path_factory.mktemp("sensor_column")
    lines = (DATA / "four_sensors.csv").read_text().splitlines()
    members = []
    for sid in ("LV-101", "LV-104"):   # the family design from two of the rig's sensors
        members.append(d / f"{sid}.csv")
        members[-1].write_text("displacement_mm,voltage_v\n" + "".join(
            ln.split(",", 1)[1] + "\n" for ln in lines[1:] if ln.startswith(sid + ",")))
    design = d / "design"
    rc, _out, err = in_process(["gen", "--family", *members, "-o", design, "--input-bits", 8, "--terms", 5])
    assert rc == 0, err
    # the four sensors and a fifth whose output lies beyond the design's converter
    rig = d / "rig.csv"
    rig.write_text("\n".join(lines) + "\n" + "".join(f"LV-999,{x},{9.0 + 0.01 * x}\n" for x in range(-20, 21)))
    out = d / "cal"
    rc, stdout, err = in_process(["calibrate", rig, "-o", out, "--design", design, "-j", 1,
                                  "--diagnosis-points", 40])
    with open(out / "summary.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    return {"rc": rc, "out": out, "stdout": stdout, "err": err, "rows": rows}


def test_each_id_is_a_sensor_of_its_own(calibrated):
    rows = calibrated["rows"]
    assert [r["sensor"] for r in rows] == [f"rig_{i}" for i in (*IDS, "LV-999")]
    for r in rows[:4]:
        assert r["status"] == "ok" and r["verdict"] == "NOT JUDGED", r
        folder = calibrated["out"] / r["sensor"]
        assert (folder / "weights.hex").is_file()
        html = (folder / "certificate.html").read_text()
        sid = r["sensor"].removeprefix("rig_")
        assert re.search(rf"{sid} \(from the sensor column\)", html), sid
    numbers = {re.search(r"FLANN-\d{8}-\d{6}-[0-9a-f]{8}", (calibrated["out"] / r["sensor"] / "certificate.html")
                         .read_text()).group(0) for r in rows}
    assert len(numbers) == 5   # one file, five certificate numbers


def test_a_bad_sensor_is_reported_and_the_batch_goes_on(calibrated):
    bad = calibrated["rows"][4]
    assert bad["status"] == "failed" and bad["verdict"] == "FAIL"
    assert "exceeds the design's input" in bad["reason"]
    assert calibrated["rc"] == 2
    assert re.search(r"^error: rig_LV-999: ", calibrated["err"], re.MULTILINE)
    assert "4 of 5 sensor(s) calibrated" in calibrated["stdout"]
