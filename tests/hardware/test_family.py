"""Family design: sizing, memory image, twin = fixed twin, generated VHDL analyses."""

from __future__ import annotations

import json
import shutil
import subprocess
from dataclasses import replace

import numpy as np
import pytest

from flann.cli import main
from flann.golden.model import load_model
from flann.hardware.family.render import load_design, write
from flann.hardware.family.spec import FitError, derive_family, member_spec
from flann.hardware.family.twin import FlannFamilyMem, FlannFamilyTop
from flann.hardware.fixed.twin import FlannTop


def _models(default_model_json):
    """Two different sensors: the paper's model and one with a steeper, shifted response."""
    a = load_model(default_model_json)
    b = replace(a, weights=tuple(w * (1.1 if i % 3 else 0.9) for i, w in enumerate(a.weights)), bias=a.bias + 0.4,
                input_offset_v=a.input_offset_v + 0.05, voltage_range_v=tuple(v * 0.9 for v in a.voltage_range_v))
    return a, b


@pytest.fixture(scope="module")
def fam(default_model_json):
    return derive_family(list(_models(default_model_json)), names=["a", "b"], input_bits=9)


def test_every_member_fits_and_images_differ(fam, default_model_json):
    a, b = _models(default_model_json)
    wa = FlannFamilyMem.encode(fam, member_spec(fam, a))
    wb = FlannFamilyMem.encode(fam, member_spec(fam, b))
    assert len(wa) == fam.mem_depth and wa != wb
    assert all(0 <= w < 2 ** 32 for w in wa + wb)


def test_twin_from_memory_equals_fixed_twin_and_float(fam, default_model_json):
    for m in _models(default_model_json):
        ms = member_spec(fam, m)
        codes = np.arange(fam.spec.code_min, fam.spec.code_max + 1)
        got, sat = FlannFamilyTop(fam, FlannFamilyMem.encode(fam, ms)).process(codes)
        want, wsat = FlannTop(ms).process(codes)
        assert np.array_equal(got, want) and np.array_equal(sat, wsat)
        inside = (codes >= ms.clamp_lo) & (codes <= ms.clamp_hi)
        ref = m.predict(codes * fam.spec.input_lsb_v) / fam.spec.output_lsb_mm
        assert np.max(np.abs(got - ref)[inside]) < 1.0


def test_write_changes_one_value(fam, default_model_json):
    a, b = _models(default_model_json)
    t = FlannFamilyTop(fam, FlannFamilyMem.encode(fam, member_spec(fam, a)))
    before = t.mem.decode()
    wb = FlannFamilyMem.encode(fam, member_spec(fam, b))
    k1 = next(f for f in fam.fields if f.name == "k1")
    for i in range(k1.words):
        t.write(k1.addr + i, wb[k1.addr + i])
    after = t.mem.decode()
    assert after["k1"] == member_spec(fam, b).k1 and after["ka"] == before["ka"]


def test_sensor_outside_the_family_is_refused(fam, default_model_json):
    a, _ = _models(default_model_json)
    huge = replace(a, weights=tuple(w * 40 for w in a.weights))
    with pytest.raises(FitError, match="design holds|output_bits"):
        member_spec(fam, huge)
    wide = replace(a, voltage_range_v=(-100.0, 100.0))
    with pytest.raises(FitError, match="exceeds the design's input"):
        member_spec(fam, wide)


def test_design_round_trips_and_analyses(fam, tmp_path):
    write(fam, tmp_path, fam.spec.model, "a")
    assert load_design(tmp_path).spec == fam.spec
    man = json.loads((tmp_path / "manifest.json").read_text())
    names = [f["name"] for f in man["family"]["memory"]["fields"]]
    assert names == ["weights", "clamp_lo", "clamp_hi", "k1", "k0", "ka", "kb"]  # normaliser order
    assert set(man["cfg_port"]["ports"]) == {"cfg_we", "cfg_addr", "cfg_data"}
    if shutil.which("ghdl") is None:
        pytest.skip("ghdl not installed")
    for f in man["files"]:
        r = subprocess.run(["ghdl", "-a", "--std=93c", f"--workdir={tmp_path}", str(tmp_path / f)],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr


def test_gen_family_cli_errors(tmp_path, default_model_json, capsys):
    assert main(["gen", "-o", str(tmp_path / "x")]) == 2
    assert main(["gen", str(default_model_json), "--family", str(default_model_json), "-o", str(tmp_path / "y")]) == 2
    assert main(["gen", "--family", str(default_model_json), "--lanes", "2", "-o", str(tmp_path / "z")]) == 2
    err = capsys.readouterr().err
    assert err.count("error: ") == 3 and "Traceback" not in err
    assert not any((tmp_path / n).exists() for n in "xyz")


def test_gen_family_names_every_bad_member_in_one_line(tmp_path, default_model_json, capsys):
    bad_text = tmp_path / "words.csv"
    bad_text.write_text("displacement_mm,voltage_v\n0,abc\n")
    missing = tmp_path / "gone.csv"
    argv = ["gen", "--family", str(default_model_json), str(bad_text), str(missing), "-o", str(tmp_path / "d")]
    assert main(argv) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: 2 of 3 family members")
    assert "words.csv" in lines[0] and "gone.csv" in lines[0]
    assert not (tmp_path / "d").exists()
