"""CI guard: the default 51-term design still fits the device it is documented for.

The design is the checked-in hdl/ when present, else it is generated from
data/default_model.json exactly as `make gen` does.  The documented device is the one
the design was generated for (manifest spec.device) and docs/synthesis.md names it.
"""

import json
import shutil
from pathlib import Path

import pytest

from flann.cli import main

ROOT = Path(__file__).resolve().parents[2]


def _default_design(tmp_path) -> Path:
    hdl = ROOT / "hdl"
    if (hdl / "manifest.json").is_file():
        return hdl
    from flann.hardware.fixed import render as hdlgen

    hdlgen.generate(ROOT / "data" / "default_model.json", tmp_path / "hdl")
    return tmp_path / "hdl"


def test_docs_name_the_generated_device(tmp_path):
    d = _default_design(tmp_path)
    device = json.loads((d / "manifest.json").read_text())["spec"]["device"]
    assert f"`{device}`" in (ROOT / "docs" / "synthesis.md").read_text()


def test_default_design_passes_vsg(tmp_path):
    from flann.hardware.manifest import read_manifest
    from flann.implement.synth import lint_vhdl

    man = read_manifest(_default_design(tmp_path))
    assert lint_vhdl(man.files, ROOT / "vsg.yaml") == []


@pytest.mark.synth
@pytest.mark.skipif(not (shutil.which("ghdl") and shutil.which("yosys")), reason="ghdl and yosys are required")
def test_default_design_fits_its_documented_device_and_xc2s30_as_the_readme_says(tmp_path, capsys):
    # the headline of docs/results.md: the default design fits the smallest Spartan-II in PQ208
    assert "| **ours, default fixed point** |" in (ROOT / "docs" / "results.md").read_text()
    d = _default_design(tmp_path)
    device = json.loads((d / "manifest.json").read_text())["spec"]["device"]
    rc = main(["synth", str(d), "--device", device, "--json", "--no-lint"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    rep = json.loads(out)
    assert rep["device"] == device and rep["fits"] is True
    assert rep["cycles_per_sample"] == json.loads((d / "manifest.json").read_text())["cycles_per_sample"]
    # one synthesis, two devices: capacities of the XC2S30 from DS001 (12 x 18 CLBs x 4 LUT4, 6
    # block RAMs), not from the tool under test, and the tool's own pick of the smallest part
    assert rep["luts"] <= 12 * 18 * 4 and rep["brams"] <= 6
    assert rep["smallest_device"] == "xc2s30-pq208-5"
    # the ISE handoff, which has only the estimate, does not refuse the part synth measured
    assert main(["ise", str(d), "-o", str(tmp_path / "ise"), "--device", rep["smallest_device"]]) == 0, \
        capsys.readouterr().err
