"""GHDL + cocotb: one family design, two sensors' weight images loaded through cfg_*."""

from __future__ import annotations

import shutil

import pytest

from flann.hardware.family.build import generate_family
from flann.hardware.family.render import load_design
from flann.production.calibrate import check_sensor
from flann.production.demo import write_batch
from flann.production.images import hex_text
from flann.recordings import read_recordings
from flann.verify import runner

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
    res = runner.run_family_bench(hdl, images, tmp_path / "build")
    assert res.tests == 3 and res.ok, f"failed: {res.failed_tests} (log {tmp_path / 'build' / 'family' / 'sim.log'})"
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
    res = runner.run_family_bench(hdl, images, tmp_path / "build")
    assert res.tests == 3 and res.ok, f"failed: {res.failed_tests}"
    assert res.records["family_every_code"]["mismatches"] == 0
