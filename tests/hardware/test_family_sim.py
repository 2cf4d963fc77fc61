"""GHDL + cocotb: one family design, two sensors' weight images loaded through cfg_*."""

from __future__ import annotations

import json
import shutil

import pytest

from flann.cli import main
from flann.hardware.family.build import generate_family
from flann.hardware.family.render import load_design
from flann.production.calibrate import check_sensor
from flann.production.demo import write_batch
from flann.hardware.family.images import hex_text
from flann.recordings import read_recordings
from flann.hardware.family.verify import run_family_bench

pytestmark = [pytest.mark.sim,
              pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl not installed")]


def test_two_sensors_through_cfg_port(tmp_path):
    recs = write_batch(tmp_path / "rec", 3, seed=11, points=400)
    hdl = tmp_path / "hdl"
    generate_family(recs[:2], hdl, terms=9, input_bits=8)  # small input: every code stays short
    fam = load_design(hdl)
    images = []
    for p in recs[1:]:  # sensor 2 sized the design, sensor 3 did not
        chk = check_sensor(read_recordings(p), fam)
        h = tmp_path / f"{p.stem}.hex"
        h.write_text(hex_text(chk["words"]))
        images.append({"name": p.stem, "hex": str(h)})
    res = run_family_bench(hdl, images, tmp_path / "build")
    assert res.tests == 4 and res.ok, f"failed: {res.failed_tests} (log {tmp_path / 'build' / 'family' / 'sim.log'})"
    rec = res.records["family_every_code"]
    assert len(rec["codes"]) == 2 ** 8 and rec["mismatches"] == 0


def test_two_identical_sensors_verify(tmp_path):
    """Two sensors whose images are the same word for word (identical sensors) are a valid
    family: every code still agrees with the twin, and the bench does not call it a failed load."""
    recs = write_batch(tmp_path / "rec", 1, seed=11, points=400)
    twin = recs[0].with_name("twin_" + recs[0].name)
    shutil.copy(recs[0], twin)
    hdl = tmp_path / "hdl"
    generate_family([recs[0], twin], hdl, terms=5, input_bits=6)
    fam = load_design(hdl)
    words = hex_text(check_sensor(read_recordings(recs[0]), fam)["words"])
    images = []
    for name in ("a", "b"):
        (tmp_path / f"{name}.hex").write_text(words)
        images.append({"name": name, "hex": str(tmp_path / f"{name}.hex")})
    res = run_family_bench(hdl, images, tmp_path / "build")
    assert res.tests == 4 and res.ok, f"failed: {res.failed_tests}"
    assert res.records["family_every_code"]["mismatches"] == 0


def test_calibrate_then_sim_the_weight_files_it_writes(tmp_path, capsys):
    """The seam a production line walks: gen --family, calibrate two sensors, then sim with the
    two weights.hex files calibrate wrote (same file name, each in its sensor's folder)."""
    recs = write_batch(tmp_path / "rec", 3, seed=11, points=400)
    fam, out = tmp_path / "fam", tmp_path / "cal"
    assert main(["gen", "--family", *map(str, recs[:2]), "--terms", "9", "--input-bits", "8", "-o", str(fam)]) == 0
    assert main(["calibrate", *map(str, recs[1:]), "-o", str(out), "--design", str(fam),
                 "--diagnosis-points", "40", "-j", "1"]) == 0
    hexes = sorted(out.glob("*/weights.hex"))
    assert len(hexes) == 2
    capsys.readouterr()
    assert main(["sim", str(fam), "--image", str(hexes[0]), "--image", str(hexes[1]), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["all_passed"] and s["mismatches"] == 0 and s["codes_tested"] == 2 * 2 ** 8
    assert s["images"] == [f"{h.parent.name}/weights" for h in hexes]
