"""A design directory is checked before anything slow runs: its manifest's files and widths, the
generator flags given with it, the build directory and every weight image, each refused in one
line (exit 2) rather than a traceback, an endless sweep or a failed co-simulation."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest

import flann.implement.ise  # noqa: F401  imported before no_simulation patches synthesize, which it imports by name
from flann.analysis.plugin import Insight
from flann.commands import explore as explore_command
from flann.cli import build_parser
from flann.commands.gen import generator_options
from flann.errors import FlannError
from flann.hardware.family.images import hex_text, read_image
from flann.hardware.family.render import design_hash
from flann.hardware.manifest import read_manifest
from flann.hardware.registry import read_design


def one_line(rc, out, err, *needles):
    assert rc == 2 and out == "", (rc, out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    for needle in needles:
        assert needle in lines[0], err
    return lines[0]


@pytest.fixture
def copy_of(small_designs, tmp_path):
    """A copy of a small design of the datapath named, its manifest edited by ``edit(man)``."""
    def make(name: str, edit=None) -> Path:
        d = tmp_path / name
        shutil.copytree(small_designs["dir"] / name, d)
        if edit is not None:
            man = json.loads((d / "manifest.json").read_text())
            edit(man)
            (d / "manifest.json").write_text(json.dumps(man, indent=2))
        return d
    return make


@pytest.fixture
def no_simulation(monkeypatch):
    """Fail the test if a bench or a synthesis starts (each refusal comes before them)."""
    def started(*_a, **_kw):
        raise AssertionError("a slow step started")
    # the slow step of each datapath's bench: what comes before it (the checks) still runs
    for target in ("flann.hardware.fixed.verify._every_code", "flann.hardware.fixed.verify.run_bench",
                   "flann.hardware.float18.verify.run_design",
                   "flann.hardware.family.verify.run_family_bench", "flann.hardware.thermal.verify.sweep_temperatures",
                   "flann.hardware.family_thermal.verify.sweep_temperatures"):
        monkeypatch.setattr(target, started)
    monkeypatch.setattr("flann.implement.synth.synthesize", started)


# --- sim --build FILE ---------------------------------------------------------------------

def test_sim_build_that_is_a_file_is_refused(small_designs, tmp_path, cli, monkeypatch, no_simulation):
    monkeypatch.chdir(tmp_path)
    Path("afile").write_text("mine\n")
    for target in (small_designs["dir"] / "fixed", small_designs["model"]):
        line = one_line(*cli(["sim", target, "--build", "afile"]))
        assert line == "error: afile: exists and is not a directory"
    assert Path("afile").read_text() == "mine\n"


# --- manifest files -----------------------------------------------------------------------

@pytest.mark.parametrize("entry, why", [
    ("../rec.csv", "not a plain *.vhd"), ("sub/flann_top.vhd", "not a plain *.vhd"),
    ("/etc/passwd", "not a plain *.vhd"), ("notes.txt", "not a plain *.vhd"),
    ("out.vhd", "leads out of"), ("flann_top.vhd", "twice"),
])
def test_manifest_files_are_plain_vhd_names_inside_the_directory(copy_of, tmp_path, cli, no_simulation, entry, why):
    (tmp_path / "rec.csv").write_text("displacement_mm,voltage_v\n0,0\n")
    (tmp_path / "outside.vhd").write_text("-- outside\n")
    d = copy_of("fixed", lambda man: man["files"].append(entry))
    (d / "sub").mkdir()
    shutil.copy(d / "flann_top.vhd", d / "sub" / "flann_top.vhd")
    os.symlink(tmp_path / "outside.vhd", d / "out.vhd")
    with pytest.raises(FlannError, match="listed file|lists"):
        read_manifest(d)
    for argv in (["sim", d], ["synth", d, "--no-lint"], ["ise", d, "-o", tmp_path / "ise", "--no-timing-check"]):
        one_line(*cli(argv), why)
    assert not (tmp_path / "ise").exists()


@pytest.mark.parametrize("edit, why", [
    (lambda man: man.update(model="../model.json"), "kept model '../model.json' is not a plain *.json"),
    (lambda man: man.update(model="/etc/model.json"), "not a plain *.json"),
    (lambda man: man.update(model=7), "field 'model' must be a file name"),
    (lambda man: man["images"][0].update(hex="../image.hex"), "kept weight image '../image.hex' is not a plain"),
    (lambda man: man["images"][0].update(hex="out.hex"), "leads out of"),
    (lambda man: man["images"][0].update(hex="gone.hex"), "does not exist"),
    (lambda man: man.update(images=[{"name": "a"}]), "field 'images' must be a list"),
])
def test_kept_model_and_images_are_confined_like_the_files(copy_of, tmp_path, cli, no_simulation, edit, why):
    (tmp_path / "model.json").write_text("{}\n")
    (tmp_path / "image.hex").write_text("0000\n")
    d = copy_of("family", edit)
    os.symlink(tmp_path / "image.hex", d / "out.hex")
    with pytest.raises(FlannError, match="kept|field"):
        read_manifest(d)
    for argv in (["sim", d], ["synth", d, "--no-lint"]):
        one_line(*cli(argv), why)


def test_a_kept_image_named_after_any_recording_is_read(copy_of):
    d = copy_of("family")
    man = json.loads((d / "manifest.json").read_text())
    (d / man["images"][0]["hex"]).rename(d / "image_sensor 1 (ünï).hex")
    man["images"][0]["hex"] = "image_sensor 1 (ünï).hex"
    (d / "manifest.json").write_text(json.dumps(man))
    assert read_manifest(d)["images"][0]["hex"] == "image_sensor 1 (ünï).hex"


# --- manifest widths ----------------------------------------------------------------------

def test_every_generated_design_passes_the_width_checks(small_designs):
    for name in ("fixed", "float18", "family", "thermal", "family_thermal"):
        read_design(small_designs["dir"] / name)


@pytest.mark.parametrize("field, value, needle", [
    ("input_bits", 64, "flann gen builds 4..24-bit inputs"),
    ("input_bits", 3, "flann gen builds 4..24-bit inputs"),
    ("input_bits", 10, "the spec says 8"),
    ("output_bits", 12, "the spec says 11"),
    ("output_lsb_mm", 0.1, "the spec says 0.05"),
    ("input_lsb_v", 0.1, "the spec says"),
    ("adc_bits", 64, "'adc_bits' must be an integer in 4..32"),
])
def test_top_level_widths_out_of_range_or_not_the_specs_are_refused(copy_of, small_designs, tmp_path, cli,
                                                                   no_simulation, field, value, needle):
    d = copy_of("fixed", lambda man: man.update({field: value}))
    rec = small_designs["rec"]
    for argv in (["sim", d], ["trace", d], ["synth", d, "--no-lint"], ["eval", d / "model.json", rec, "--design", d],
                 ["ise", d, "-o", tmp_path / "ise", "--no-timing-check"]):
        one_line(*cli(argv), needle, "manifest.json")


@pytest.mark.parametrize("name", ["float18", "thermal", "family_thermal"])
def test_other_datapaths_top_level_input_width_must_be_the_specs(copy_of, cli, name):
    """float18 records its input in its spec, the family with temperature only in the rebuilt one."""
    d = copy_of(name, lambda man: man.update({"input_bits": 10}))
    one_line(*cli(["trace", d]), "'input_bits' is 10", "8")


# --- generator flags with a design directory ----------------------------------------------

@pytest.mark.parametrize("command, flags, verb", [
    ("sim", ["--lanes", "2", "--input-bits", "10", "--json"], "simulated"),
    ("sim", ["--input-bits", "8"], "simulated"),          # even the design's own value: given is given
    ("trace", ["--input-bits", "14"], "traced"),
    ("trace", ["--no-clamp"], "traced"),
    ("trace", ["--mult-digit-bits", "2"], "traced"),
])
def test_sim_and_trace_refuse_generator_flags_with_a_directory(small_designs, cli, no_simulation, command, flags,
                                                               verb):
    line = one_line(*cli([command, small_designs["dir"] / "fixed", *flags]))
    assert f"a design directory is {verb} as written" in line and "flann gen" in line and "model.json" in line
    assert flags[0] in line


def test_explore_refuses_another_adc_for_a_directory(small_designs, cli, monkeypatch):
    monkeypatch.setattr(explore_command, "insight", lambda dp: Insight(explore=lambda *a, **kw: []))
    d = small_designs["dir"] / "fixed"
    one_line(*cli(["explore", d, "--input-bits", "10", "--no-seed"]), "explored with the ADC",
             str(d / "model.json"), "--input-bits 10")
    assert cli(["explore", d, "--no-seed", "--json"])[0] == 0   # its own ADC


def test_generator_flags_given_are_told_from_defaults():
    args = build_parser("sim").parse_args(["sim", "m.json"])
    assert generator_options(args)[1] == ()
    args = build_parser("sim").parse_args(["sim", "m.json", "--lanes", "1", "--no-interp", "--device",
                                           "xc2s200-pq208-5"])
    opts, given = generator_options(args)
    assert set(given) == {"lanes", "interp", "device"} and opts.lanes == 1 and opts.interp is False


# --- weight images ------------------------------------------------------------------------

def _calibrated(design: Path, words, out: Path, design_sha=None, count=None) -> Path:
    """A weight image with the header flann calibrate writes."""
    head = ["flann calibrate: sensor s", f"design sha256 {design_sha or design_hash(design)}",
            "model sha256 " + "0" * 64, f"{len(words) if count is None else count} words x 32 bits, address 0 first"]
    out.write_text(hex_text(words, head))
    return out


def test_malformed_weight_images_are_refused_before_the_simulation(small_designs, tmp_path, cli, no_simulation):
    d = small_designs["dir"] / "family"
    words = read_image(d / json.loads((d / "manifest.json").read_text())["images"][0]["hex"])
    n = len(words)
    cut = _calibrated(d, words, tmp_path / "cut.hex")
    cut.write_text("\n".join(cut.read_text().splitlines()[:4 + n // 4]) + "\n")   # `head`: a quarter
    cases = {
        cut: f"{n // 4} words, its header says {n}",
        _calibrated(d, words * 3, tmp_path / "other_depth.hex"): f"{3 * n} words",
        _calibrated(d, words, tmp_path / "other_design.hex", design_sha="ab" * 32): "calibrated for another design",
        _calibrated(d, words, tmp_path / "miscounted.hex", count=n + 1): f"{n} words, its header says {n + 1}",
    }
    (tmp_path / "plain_short.hex").write_text(hex_text(words[:-1]))
    cases[tmp_path / "plain_short.hex"] = f"{n - 1} words"
    (tmp_path / "not_hex.hex").write_text(hex_text(words).replace(format(words[3], "08x"), "xyz", 1))
    cases[tmp_path / "not_hex.hex"] = "is not a hex word"
    for image, needle in cases.items():
        one_line(*cli(["sim", d, "--image", image]), str(image), needle)
        one_line(*cli(["sim", d, "--image", image, "--image", d / "image_lvdt_0001.hex"]), needle)


def test_family_thermal_image_checks_its_header_too(small_designs, tmp_path, cli, no_simulation):
    d = small_designs["dir"] / "family_thermal"
    words = read_image(d / json.loads((d / "manifest.json").read_text())["images"][0]["hex"])
    image = _calibrated(d, words, tmp_path / "ft.hex", design_sha="cd" * 32)
    one_line(*cli(["sim", d, "--image", image]), "calibrated for another design")


def test_one_image_on_a_family_is_loaded_over_one_the_design_keeps(small_designs, tmp_path, cli, monkeypatch):
    d = small_designs["dir"] / "family"
    kept = json.loads((d / "manifest.json").read_text())["images"]
    seen = []

    def bench(directory, images, build_dir, **kw):
        seen.append(images)
        raise FlannError("stopped before the bench")
    monkeypatch.setattr("flann.hardware.family.verify.run_family_bench", bench)
    given = _calibrated(d, read_image(d / kept[0]["hex"]), tmp_path / "weights.hex")
    one_line(*cli(["sim", d, "--image", given]), "stopped before the bench")
    # the given image second, over the kept image that differs from it; calibrate names every
    # image weights.hex, so the folder names the sensor
    assert seen == [[{"name": f"family/{kept[1]['name']}", "hex": str(d.resolve() / kept[1]["hex"]),
                      "model": str(d.resolve() / kept[1]["model"])},
                     {"name": f"{tmp_path.name}/weights", "hex": str(given.resolve())}]]


@pytest.mark.sim
@pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl not installed")
def test_one_image_on_a_family_simulates(small_designs, tmp_path, cli):
    d = small_designs["dir"] / "family"
    kept = json.loads((d / "manifest.json").read_text())["images"]
    given = _calibrated(d, read_image(d / kept[1]["hex"]), tmp_path / "weights.hex")
    rc, out, err = cli(["sim", d, "--image", given, "--json", "--build", tmp_path / "b"])
    s = json.loads(out)
    assert rc == 0 and s["all_passed"] and s["mismatches"] == 0, err
    # calibrate names every image weights.hex: the folder names the sensor
    assert s["images"] == [f"family/{kept[0]['name']}", f"{tmp_path.name}/weights"]
    assert s["codes_tested"] == 2 * 2 ** 8
