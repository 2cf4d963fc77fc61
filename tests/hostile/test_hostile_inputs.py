"""Hostile input on every subcommand: exit code, exactly one ``error:`` line, no traceback,
and nothing created, changed or removed outside the expected place (the whole temporary
tree is snapshotted before and after each case).

The table :data:`CASES` is the suite; ``FLANN_HOSTILE_TABLE=docs/hostile_inputs.md`` makes
a run of this file write it as a Markdown table with what was observed (see
docs/hostile_inputs.md for the command).
"""

from __future__ import annotations

import fnmatch
import hashlib
import json
import math
import os
import re
import shutil
import stat
from dataclasses import dataclass
from pathlib import Path

import pytest

from flann.cli import main
from flann.recordings import csvio


@dataclass(frozen=True)
class Case:
    id: str
    klass: str          # the hostile-input defect class (1..17, docs/hostile_inputs.md) or "own"
    argv: tuple         # {w} is the world directory
    rc: int
    expect: str = ""    # a substring of the error line (rc != 0) or of stdout+stderr (rc 0)
    changes: tuple = ()  # glob patterns (relative to the world) that may be created/changed
    prep: str = ""      # name of a function below that makes the hostile file(s)
    absent: tuple = ()  # paths that must not exist afterwards (a stale result: weights of an earlier run)


# ---------------------------------------------------------------------------- hostile files
def _table(w: Path) -> list[str]:
    return (w / "rec.csv").read_text().splitlines()


def _write(path: Path, text: str) -> None:
    path.write_text(text)


def p_fifo(w):
    os.mkfifo(w / "pipe")


def p_fifo_png(w):
    os.mkfifo(w / "pipe.png")


def p_chardev(w):
    """A character device (the null device) inside the world, never the system's /dev/null:
    a regression would replace only this copy."""
    try:
        os.mknod(w / "dev", stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("a device node needs root")


def p_link(w):
    (w / "target.json").write_text("old\n")
    os.symlink("target.json", w / "link.json")


def p_outdir_holds_model(w):
    (w / "design" / "m.json").write_text((w / "m.json").read_text())


def p_bigfield(w):
    _write(w / "bad.csv", "\n".join(_table(w)) + '\n1,"' + "9" * 140_000 + '"\n')


def p_bigfield_sim(w):
    _write(w / "bad.csv", (w / "s0.csv").read_text() + '1,"' + "9" * 140_000 + '"\n')


def p_overflow(w):
    rows = "".join(f"{(i + 1) * 3e306!r},{i * 0.1}\n" for i in range(20))
    _write(w / "bad.csv", "displacement_m,voltage_v\n" + rows)


def p_huge_voltage(w):
    _write(w / "bad.csv", "voltage_v\n" + "".join(f"{(i + 1) * 1e300!r}\n" for i in range(20)))


def p_subnormal(w):
    _write(w / "bad.csv", "displacement_mm,voltage_v\n" + "".join(f"{i * 5e-324!r},{i * 0.1}\n" for i in range(20)))


def p_zero(w):
    """/dev/zero's kind inside the world: a device that never ends and holds no line end."""
    try:
        os.mknod(w / "zero", stat.S_IFCHR | 0o666, os.makedev(1, 5))
    except PermissionError:
        pytest.skip("a device node needs root")


def p_endless_line(w):
    """A file with no line end beyond a line's bound (what /dev/urandom gives the reader)."""
    (w / "bad.csv").write_bytes(b"displacement_mm,voltage_v\n" + b"7" * (5 << 20))


def p_cr_rows(w):
    """More rows than flann reads, ended by a lone CR (the early bound counted LF only)."""
    (w / "bad.csv").write_bytes(b"displacement_mm,voltage_v\r" + b"1,2\r" * 1_100_000)


def p_nel_comment(w):
    """A Latin-1 comment holding byte 0x85 (NEL, which str.splitlines() takes for a line end)."""
    (w / "rec.csv").write_bytes(b"# caf\x85 x,y\ndisplacement_mm,voltage_v\n" +
                                b"".join(f"{i},{0.1 * i}\n".encode() for i in range(10)))


def p_underflow(w):
    _write(w / "bad.csv", "displacement_mm,voltage_v\n0,1e-400\n" + "".join(f"{i},{0.1 * i}\n" for i in range(1, 10)))


def p_flat(w):
    _write(w / "flat.csv", "displacement_mm,voltage_v\n" + "".join(f"{i},1.5\n" for i in range(10)))


def p_newline_sensor(w):
    from flann.physics.sensor import default_sensor, format_sensor

    text = format_sensor(default_sensor()).replace('name = "paper_lvdt"', 'name = "a\\nb"')
    _write(w / "s.toml", text)


def p_temperature_every_row(w):
    _write(w / "bad.csv", "displacement_mm,voltage_v,temperature_c\n" +
           "".join(f"{i % 24},{0.1 * (i % 24)},{20 + 0.37 * i}\n" for i in range(723)))


def p_degenerate(w):
    """Voltages that differ only in the last digits of a double (the diagnosis crashed)."""
    _write(w / "bad.csv", "displacement_mm,voltage_v\n" + "".join(f"{i},{1 + i * 1e-15!r}\n" for i in range(20)))


def _model(w, **changes):
    d = json.loads((w / "m.json").read_text())
    d.update(changes)
    return d


def p_terms_1e999(w):
    _write(w / "bad.json", re.sub(r'"terms": \d+', '"terms": 1e999', json.dumps(_model(w))))


def p_bias_400(w):
    _write(w / "bad.json", json.dumps(_model(w)).replace('"bias": ', '"bias": ' + "9" * 400 + ".0, \"x\": "))


def p_int_5000(w):
    _write(w / "bad.json", re.sub(r'"terms": \d+', '"terms": ' + "1" * 5000, json.dumps(_model(w))))


def p_nested(w):
    _write(w / "bad.json", "[" * 100_000 + "]" * 100_000)


def p_nested_manifest(w):
    (w / "design" / "manifest.json").write_text("[" * 100_000 + "]" * 100_000)


def p_nested_spec(w):
    _write(w / "bad.toml", "x = " + "[" * 100_000 + "]" * 100_000 + "\n")


def p_bad_image(w):
    """A sensor's image whose last word does not fit the memory's width."""
    words = (w / "fam" / "image_s0.hex").read_text().splitlines()
    _write(w / "a.hex", "\n".join(words[:-1] + ["1" + "0" * 40]) + "\n")


def p_design_notes(w):
    (w / "design" / "notes.txt").write_text("my notes\n")


def p_fold(w):
    """A sensor read past its turning points at +-23.56 mm (sin of x / 15 on -30..30 mm)."""
    _write(w / "fold.csv", "displacement_mm,voltage_v\n"
           + "".join(f"{i * 0.5},{math.sin(i * 0.5 / 15)!r}\n" for i in range(-60, 61)))


def p_afile(w):
    (w / "afile").write_text("a file\n")


def p_range_point(w):
    _write(w / "bad.json", json.dumps(_model(w, voltage_range_v=[1.0, 1.0])))


def p_terms_true(w):
    _write(w / "bad.json", json.dumps(_model(w, terms=True)))


def p_terms_frac(w):
    _write(w / "bad.json", json.dumps(_model(w, terms=61.7)))


def p_weights_str(w):
    _write(w / "bad.json", json.dumps(_model(w, weights="123456789")))


def p_scale_subnormal(w):
    _write(w / "bad.json", json.dumps(_model(w, input_scale_v=1e-320)))


def p_toml_int(w):
    _write(w / "bad.toml", (w / "sensor.toml").read_text().replace("stroke_mm = 30.0", "stroke_mm = " + "7" * 5000))


def p_toml_deep(w):
    _write(w / "bad.toml", (w / "sensor.toml").read_text() + "\nx = " + "[" * 3000 + "]" * 3000 + "\n")


def p_workfile(w):
    (w / "work").write_text("mine\n")


def p_nul_cell(w):
    _write(w / "bad.csv", "\n".join(_table(w)) + "\n1,\x002\n")


def p_summary_name(w):
    (w / "summary.csv.csv").write_text((w / "s1.csv").read_text())


def p_traversal(w):
    (w / "...csv").write_text((w / "s1.csv").read_text())


def p_dotname(w):
    (w / "..csv").write_text((w / "s1.csv").read_text())


def p_newline_name(w):
    (w / "a\nb.csv").write_text((w / "s1.csv").read_text())


def p_cut(w):
    lines = (w / "s0.csv").read_text().splitlines()
    _write(w / "bad.csv", "\n".join(lines[:-1]) + "\n" + lines[-1][: len(lines[-1]) - 5])


def p_cut_table(w):
    lines = _table(w)
    _write(w / "bad.csv", "\n".join(lines[:-1]) + "\n" + lines[-1][:-2])


def p_dup_units(w):
    rows = [r.split(",") for r in _table(w) if r and not r.startswith("#")][1:]
    _write(w / "dup.csv", "displacement_in,displacement_mm,voltage_v\n"
           + "".join(f"{float(x) / 25.4:.5f},{x},{v}\n" for x, v in rows))


def p_dup_disagree(w):
    rows = [r.split(",") for r in _table(w) if r and not r.startswith("#")][1:]
    _write(w / "bad.csv", "displacement_mm,displacement_in,voltage_v\n"
           + "".join(f"{x},{float(x) / 20:.5f},{v}\n" for x, v in rows))


def p_binary(w):
    (w / "bad.csv").write_bytes(b"\x00\x01\xff\xfe" * 100)


def p_empty(w):
    (w / "bad.csv").write_text("")


def p_many_rows(w):
    csvio.MAX_ROWS = 100
    _write(w / "bad.csv", "displacement_mm,voltage_v\n" + "".join(f"{i * 0.01},{i * 0.001}\n" for i in range(200)))


def p_outdir_file(w):
    (w / "out").write_text("a file\n")


def p_userdir(w):
    (w / "mine").mkdir()
    (w / "mine" / "notes.txt").write_text("my notes\n")


def p_stale(w):
    """An earlier passing calibration of sensor 'bad' that must not outlive its failure."""
    (w / "out" / "bad").mkdir(parents=True)
    (w / "out" / "bad" / "certificate.html").write_text("<p>passed</p>\n")
    (w / "out" / "bad" / "weights.hex").write_text("00\n")
    _write(w / "bad.csv", "displacement_mm,temperature_c\n1,2\n3,4\n")


def p_step(w):
    """A hard step: every reading on one of two flat levels, no curve to diagnose."""
    _write(w / "bad.csv", "displacement_mm,voltage_v\n" + "".join(f"{i},{0.5 if i >= 0 else -0.5}\n"
                                                                    for i in range(-10, 11)))


def p_repeats(w):
    """Table 1 recorded twice (a second sweep): every position repeats."""
    rows = [r for r in _table(w) if r and not r.startswith("#")]
    _write(w / "bad.csv", "\n".join(rows + rows[1:]) + "\n")


def _edited_manifest(w, edit, design="design"):
    """A copy of ``design`` as w/edited with its manifest changed by ``edit``."""
    shutil.copytree(w / design, w / "edited")
    man = json.loads((w / "edited" / "manifest.json").read_text())
    edit(man)
    (w / "edited" / "manifest.json").write_text(json.dumps(man))


def p_manifest_outside(w):
    _edited_manifest(w, lambda m: m["files"].append("../rec.csv"))


def p_manifest_model_outside(w):
    _edited_manifest(w, lambda m: m.update(model="../m.json"))


def p_build_file(w):
    (w / "bb").mkdir()
    _write(w / "bb" / "family", "mine\n")


def p_thermal_toml(w):
    shutil.copy(Path(__file__).resolve().parents[2] / "data" / "sensors" / "paper_lvdt_thermal.toml",
                w / "thermal.toml")


def p_manifest_wide(w):
    _edited_manifest(w, lambda m: m.update(input_bits=64))


def p_thousands(w):
    """A quoted thousands separator beside '.' decimals: 30,000 um, not 30 um."""
    _write(w / "bad.csv", "displacement_um,voltage_v\n" + "".join(
        f'"{x:,}",{v}\n' for x, v in ((-30000, -5.185), (-20000, -4.717), (-10000, -2.896), (0, 0.05),
                                     (10000, 2.9), (20000, 4.7), (30000, 5.27))))


def p_empty_spec(w):
    _write(w / "spec.toml", 'name = "line A"\n')


def p_summary_input(w):
    (w / "out").mkdir()
    shutil.copy(w / "s1.csv", w / "out" / "summary.csv")


def p_sparse(w):
    """Six positions of s1: fewer than the family design's terms."""
    rows = [r for r in (w / "s1.csv").read_text().splitlines() if r and not r.startswith("#")]
    _write(w / "sparse.csv", "\n".join([rows[0]] + rows[1::len(rows) // 6][:6]) + "\n")


def _edited_family(w, edit):
    _edited_manifest(w, edit, "fam")


def p_top_renamed(w):
    """The top entity renamed by hand in its VHDL (sed s/flann_top/flann_topx/), the manifest not."""
    f = w / "design" / "flann_top.vhd"
    f.write_text(f.read_text().replace("flann_top", "flann_topx"))


def p_clamp_codes_short(w):
    _edited_manifest(w, lambda m: m.update(clamp_codes=[1]))


def p_clamp_codes_reversed(w):
    _edited_manifest(w, lambda m: m.update(clamp_codes=[462, -454]))


def p_init_model_outside(w):
    _edited_family(w, lambda m: m.update(init_model="../m.json"))


def p_init_model_absolute(w):
    _edited_family(w, lambda m: m.update(init_model="/etc/passwd"))


def p_image_model_outside(w):
    _edited_family(w, lambda m: m["images"][0].update(model="../m.json"))


def p_family_memory(w):
    _edited_family(w, lambda m: m["family"]["memory"].update(depth=128))


def p_family_formats(w):
    _edited_family(w, lambda m: m["family"]["formats"].update(weight="sfix<40,30,rnd,sat>"))


def p_family_members(w):
    _edited_family(w, lambda m: m["family"].update(members=["a", "b"]))


def p_cfg_port(w):
    _edited_family(w, lambda m: m["cfg_port"]["ports"]["cfg_addr"].update(width=9))


def p_family_clamp(w):
    _edited_family(w, lambda m: m.update(clamp_codes=[-500, 500]))


def p_alias_bomb(w):
    _write(w / "bomb.yaml", 'a: &a ["x", "x"]\nb: &b [*a, *a]\nc: &c [*b, *b]\nd: [*c, *c]\n')


def p_python_tag(w):
    _write(w / "tag.yaml", 'rule: !!python/object/apply:os.system ["echo owned"]\n')


def _image_with_weights(w, word: int):
    """fam's first image with every trig weight word set to ``word`` (fam/manifest.json's map)."""
    man = json.loads((w / "fam" / "manifest.json").read_text())
    field = next(f for f in man["family"]["memory"]["fields"] if f["name"] == "weights")
    lines = [ln for ln in (w / "fam" / "image_s0.hex").read_text().splitlines() if not ln.startswith("#")]
    for k in range(field["addr"], field["addr"] + field["words"]):
        lines[k] = f"{word:08X}"
    _write(w / "big.hex", "\n".join(lines) + "\n")
    return field


def p_image_max_weights(w):
    """Every weight at the largest value its field holds (0x001FFFFF for sint<22>)."""
    field = json.loads((w / "fam" / "manifest.json").read_text())["family"]["memory"]["fields"][0]
    _image_with_weights(w, (1 << (field["bits"] - 1)) - 1)


def p_image_min_weights(w):
    field = json.loads((w / "fam" / "manifest.json").read_text())["family"]["memory"]["fields"][0]
    _image_with_weights(w, (1 << 32) - (1 << (field["bits"] - 1)))


def p_image_wide_word(w):
    _image_with_weights(w, 0x7FFFFFFF)


def p_fifo_member(w):
    os.mkfifo(w / "pipe.csv")


def p_build_in_design(w):
    (w / "design" / "build").mkdir()


# ------------------------------------------------------------------------------------- table
FAM = ("--design", "fam", "--diagnosis-points", "40", "-j", "1")


def sane(name: str) -> tuple:
    """What a calibrate of one sensor named ``name`` may write: its folder and the summary."""
    return ("out", "out/summary.csv", f"out/{name}", f"out/{name}/[!/]*")
CASES = [
    # 1 path traversal and names from files
    Case("calibrate-dots-name", "1", ("calibrate", "...csv", "-o", "out", *FAM), 0, "1 of 1", sane("_"), "p_traversal"),
    Case("calibrate-dotdot-name", "1", ("calibrate", "..csv", "-o", "out", *FAM), 0, "1 of 1", sane("_"), "p_dotname"),
    Case("calibrate-newline-name", "1", ("calibrate", "a\nb.csv", "-o", "out", *FAM), 0, "1 of 1", sane("a_b"), "p_newline_name"),
    # 2 special files and symlinks as outputs
    Case("train-o-fifo", "2", ("train", "rec.csv", "-o", "pipe", "--terms", "5"), 2, "FIFO", (), "p_fifo"),
    Case("predict-o-fifo", "2", ("predict", "m.json", "rec.csv", "-o", "pipe"), 2, "FIFO", (), "p_fifo"),
    Case("gen-o-fifo", "2", ("gen", "m.json", "-o", "pipe"), 2, "not a directory", (), "p_fifo"),
    Case("diagnose-json-fifo", "2", ("diagnose", "rec.csv", "--json", "pipe"), 2, "FIFO", (), "p_fifo"),
    Case("eval-plot-fifo", "2", ("eval", "m.json", "rec.csv", "--design", "design", "--plot", "pipe.png"), 2, "FIFO", (), "p_fifo_png"),
    Case("simulate-o-fifo", "2", ("simulate", "-o", "pipe"), 2, "FIFO", (), "p_fifo"),
    Case("train-o-device", "2", ("train", "rec.csv", "-o", "dev", "--terms", "5"), 2, "character device", (), "p_chardev"),
    Case("predict-o-device", "2", ("predict", "m.json", "rec.csv", "-o", "dev"), 2, "character device", (), "p_chardev"),
    Case("train-o-symlink-followed", "2", ("train", "rec.csv", "-o", "link.json", "--terms", "5"), 0, "lstsq",
         ("target.json",), "p_link"),
    Case("train-o-directory", "2", ("train", "rec.csv", "-o", "design", "--terms", "5"), 2, "is a directory"),
    # 6 an output that is one of the inputs
    Case("predict-o-input", "6", ("predict", "m.json", "rec.csv", "-o", "rec.csv"), 2, "also an input"),
    Case("predict-o-model", "6", ("predict", "m.json", "rec.csv", "-o", "m.json"), 2, "also an input"),
    Case("train-o-input", "6", ("train", "rec.csv", "-o", "rec.csv", "--terms", "5"), 2, "also an input"),
    Case("simulate-fit-json-input", "6", ("simulate", "--fit", "rec.csv", "--json", "rec.csv"), 2, "also an input"),
    Case("diagnose-json-input", "6", ("diagnose", "rec.csv", "--json", "rec.csv"), 2, "also an input"),
    Case("simulate-o-sensor", "6", ("simulate", "sensor.toml", "-o", "sensor.toml"), 2, "also an input"),
    Case("gen-o-dir-holding-model", "6", ("gen", "design/m.json", "-o", "design", "--input-bits", "10"), 2,
         "an input of this command", (), "p_outdir_holds_model"),
    # 8 a CSV field over the csv module's limit
    Case("train-big-field", "8", ("train", "bad.csv", "-o", "o.json", "--terms", "5"), 2, "characters long", (), "p_bigfield"),
    Case("predict-big-field", "8", ("predict", "m.json", "bad.csv", "-o", "p.csv"), 2, "characters long", (), "p_bigfield"),
    Case("eval-big-field", "8", ("eval", "m.json", "bad.csv"), 2, "characters long", (), "p_bigfield"),
    Case("diagnose-big-field", "8", ("diagnose", "bad.csv"), 2, "characters long", (), "p_bigfield"),
    Case("gen-family-big-field", "8", ("gen", "--family", "bad.csv", "-o", "newfam"), 2, "characters long", (), "p_bigfield_sim"),
    Case("calibrate-big-field", "8", ("calibrate", "bad.csv", "s1.csv", "-o", "out", *FAM), 2, "characters long",
         ("out", "out/**"), "p_bigfield_sim"),
    # 9 overflow after unit conversion
    Case("train-overflow-unit", "9", ("train", "bad.csv", "-o", "o.json", "--terms", "5"), 2, "x 1000", (), "p_overflow"),
    Case("simulate-fit-overflow", "9", ("simulate", "--fit", "bad.csv"), 2, "x 1000", (), "p_overflow"),
    Case("eval-overflow-unit", "9", ("eval", "m.json", "bad.csv"), 2, "x 1000", (), "p_overflow"),
    Case("predict-huge-voltage", "9", ("predict", "m.json", "bad.csv", "-o", "p.csv"), 2, "outside what flann computes", (), "p_huge_voltage"),
    # 10 subnormal displacements
    # readers bounded before they allocate; outputs the readers accept; lines that say what is wrong
    Case("train-dev-zero", "own", ("train", "zero", "-o", "o.json"), 2, "without a line end", (), "p_zero"),
    Case("diagnose-endless-line", "own", ("diagnose", "bad.csv"), 2, "without a line end", (), "p_endless_line"),
    Case("train-cr-only-rows", "own", ("train", "bad.csv", "-o", "o.json"), 2, "more than 1,000,000", (), "p_cr_rows"),
    Case("train-nel-comment", "own", ("train", "rec.csv", "-o", "o.json", "--terms", "1"), 0, "verdict:", ("o.json",),
         "p_nel_comment"),
    Case("train-underflow", "own", ("train", "bad.csv", "-o", "o.json"), 2, "outside what flann computes", (), "p_underflow"),
    Case("simulate-fit-flat", "own", ("simulate", "--fit", "flat.csv", "--json"), 2, "same on every row", (), "p_flat"),
    Case("simulate-step-rows", "own", ("simulate", "-o", "o.csv", "--step-mm", "1e-4"), 2, "more than flann reads"),
    Case("simulate-seed-alone", "own", ("simulate", "-o", "o.csv", "--seed", "3"), 2, "every seed writes the same"),
    Case("simulate-newline-name", "own", ("simulate", "s.toml", "-o", "o.csv"), 0, "", ("o.csv",), "p_newline_sensor"),
    Case("train-temperature-every-row", "own", ("train", "bad.csv", "--temperature", "-o", "o.json"), 2, "temperatures",
         (), "p_temperature_every_row"),
    Case("train-subnormal", "10", ("train", "bad.csv", "-o", "o.json", "--terms", "5"), 2, "outside what flann computes", (), "p_subnormal"),
    Case("diagnose-subnormal", "10", ("diagnose", "bad.csv"), 2, "outside what flann computes", (), "p_subnormal"),
    Case("gen-family-subnormal", "10", ("gen", "--family", "bad.csv", "-o", "newfam"), 2, "outside what flann computes", (), "p_subnormal"),
    Case("diagnose-degenerate-span", "10", ("diagnose", "bad.csv"), 2, "no usable signal", (), "p_degenerate"),
    Case("simulate-fit-degenerate-span", "10", ("simulate", "--fit", "bad.csv"), 2, "no usable signal", (), "p_degenerate"),
    # 11 model.json numbers
    Case("predict-terms-1e999", "11", ("predict", "bad.json", "rec.csv", "-o", "p.csv"), 2, "not finite", (), "p_terms_1e999"),
    Case("predict-bias-400-digits", "11", ("predict", "bad.json", "rec.csv", "-o", "p.csv"), 2, "not finite", (), "p_bias_400"),
    Case("trace-int-5000-digits", "11", ("trace", "bad.json"), 2, "digits", (), "p_int_5000"),
    Case("sim-nested-json", "11", ("sim", "bad.json"), 2, "nested deeper", (), "p_nested"),
    Case("predict-nested-json", "11", ("predict", "bad.json", "rec.csv", "-o", "p.csv"), 2, "nested deeper", (), "p_nested"),
    Case("gen-nested-json", "11", ("gen", "bad.json", "-o", "new"), 2, "nested deeper", (), "p_nested"),
    Case("sim-nested-manifest", "11", ("sim", "design"), 2, "nested deeper", (), "p_nested_manifest"),
    Case("synth-nested-manifest", "11", ("synth", "design", "--no-lint"), 2, "nested deeper", (), "p_nested_manifest"),
    Case("ise-nested-manifest", "11", ("ise", "design", "-o", "ise"), 2, "nested deeper", (), "p_nested_manifest"),
    Case("sim-image-too-wide", "11", ("sim", "fam", "--image", "a.hex", "--image", "fam/image_s1.hex"), 2,
         "does not fit", (), "p_bad_image"),
    Case("sim-image-missing", "own", ("sim", "fam", "--image", "nosuch.hex"), 2, "nosuch.hex: no such file"),
    Case("sim-image-on-a-fixed-design", "own", ("sim", "design", "--image", "fam/image_s0.hex"), 2,
         "weights are built in"),
    Case("sim-image-twice", "own", ("sim", "fam", "--image", "fam/image_s0.hex", "--image", "fam/image_s0.hex"), 2,
         "given twice"),
    Case("calibrate-o-is-the-design", "own", ("calibrate", "s1.csv", "-o", "fam", *FAM), 2, "inside the design"),
    Case("calibrate-o-inside-the-design", "own", ("calibrate", "s1.csv", "-o", "fam/cal", *FAM), 2, "inside the design"),
    Case("gen-over-a-design-holding-user-files", "own", ("gen", "m.json", "-o", "design", "--input-bits", "10"), 2,
         "notes.txt", (), "p_design_notes"),
    Case("calibrate-unknown-flag", "17", ("calibrate", "s1.csv", "-o", "out", "--trim", *FAM), 2,
         "flann calibrate: unrecognized arguments: --trim (see flann calibrate --help)"),
    # a member read past its turning points is kept to its monotonic span, said in one line
    Case("gen-family-foldback-names-the-span", "own", ("gen", "--family", "fold.csv", "s1.csv", "-o", "newfam"), 0,
         "output turns back at +23.5 mm and -23.5 mm: trained on -23.5..23.5 mm", ("newfam", "newfam/**"),
         "p_fold"),
    Case("synth-ice40-o-is-a-file", "2", ("synth", "design", "--device", "ice40-hx8k-ct256", "-o", "afile", "--no-lint",
                                          "--work", "wdir"),
         2, "exists and is not a directory", (), "p_afile"),
    Case("gen-model-range-one-point", "11", ("gen", "bad.json", "-o", "new"), 2, "is a single point", (),
         "p_range_point"),
    Case("gen-lanes-0-names-the-flag", "17", ("gen", "m.json", "-o", "new", "--lanes", "0"), 2, "(--lanes)"),
    Case("eval-terms-true", "11", ("eval", "bad.json", "rec.csv"), 2, "must be a number", (), "p_terms_true"),
    Case("predict-terms-61.7", "11", ("predict", "bad.json", "rec.csv", "-o", "p.csv"), 2, "must be an integer", (), "p_terms_frac"),
    Case("gen-weights-string", "11", ("gen", "bad.json", "-o", "new"), 2, "'weights' must be a list", (), "p_weights_str"),
    # 12 TOML sensor files
    Case("simulate-toml-5000-digits", "12", ("simulate", "bad.toml", "-o", "o.csv"), 2, "too large", (), "p_toml_int"),
    Case("simulate-describe-toml-deep", "12", ("simulate", "bad.toml", "--describe"), 2, "nested deeper", (), "p_toml_deep"),
    Case("diagnose-sensor-toml-deep", "12", ("diagnose", "rec.csv", "--sensor", "bad.toml"), 2, "nested deeper", (), "p_toml_deep"),
    Case("calibrate-sensor-toml-int", "12", ("calibrate", "s1.csv", "-o", "out", "--sensor", "bad.toml", *FAM), 2,
         "too large", (), "p_toml_int"),
    Case("calibrate-spec-toml-deep", "12", ("calibrate", "s1.csv", "-o", "out", "--spec", "bad.toml", *FAM), 2,
         "nested deeper", (), "p_nested_spec"),
    # 14 flags that crashed
    Case("simulate-from-nan", "14", ("simulate", "-o", "o.csv", "--from-mm", "nan"), 2, "finite"),
    Case("simulate-seed-negative", "14", ("simulate", "-o", "o.csv", "--seed", "-1"), 2, "--seed"),
    Case("train-ridge-1e308", "14", ("train", "rec.csv", "-o", "o.json", "--terms", "11", "--ridge", "1e308"), 2, "--ridge"),
    Case("train-offset-nan", "14", ("train", "rec.csv", "-o", "o.json", "--terms", "11", "--input-offset-v", "nan",
                                    "--input-scale-v", "1"), 2, "finite"),
    Case("synth-work-is-file", "14", ("synth", "design", "--work", "work", "--no-lint"), 2, "not a directory", (), "p_workfile"),
    Case("ise-clock-inf", "14", ("ise", "design", "-o", "ise", "--clock-mhz", "inf"), 2, "finite"),
    Case("eval-tol-nan", "14", ("eval", "m.json", "rec.csv", "--tol", "nan"), 2, "finite"),
    Case("paper-eta-nan", "14", ("paper", "--eta", "nan"), 2, "finite"),
    # 16 resource bounds
    Case("train-terms-million", "16", ("train", "rec.csv", "-o", "o.json", "--terms", "1000000"), 2, "1..61"),
    Case("train-epochs-1e11", "16", ("train", "rec.csv", "-o", "o.json", "--terms", "5", "--method", "lms",
                                     "--epochs", "100000000000"), 2, "--epochs"),
    Case("paper-epochs-1e11", "16", ("paper", "--epochs", "100000000000"), 2, "--epochs"),
    Case("gen-family-terms-100", "16", ("gen", "--family", "s0.csv", "s1.csv", "-o", "newfam", "--terms", "100"), 2,
         "--terms"),
    Case("train-too-many-rows", "16", ("train", "bad.csv", "-o", "o.json", "--terms", "5"), 2, "more than flann reads",
         (), "p_many_rows"),
    # 17 exit codes and lines
    Case("explore-input-bits-0", "17", ("explore", "m.json", "--input-bits", "0"), 2, "--input-bits"),
    Case("explore-lsb-negative", "17", ("explore", "m.json", "--input-lsb-v", "-1"), 2, "--input-lsb-v"),
    Case("calibrate-max-error-nan", "17", ("calibrate", "s1.csv", "-o", "out", "--max-error-mm", "nan", *FAM), 2, "finite"),
    Case("predict-scale-subnormal", "17", ("predict", "bad.json", "rec.csv", "-o", "p.csv"), 2, "too small", (), "p_scale_subnormal"),
    Case("train-nul-in-cell", "17", ("train", "bad.csv", "-o", "o.json", "--terms", "5"), 2, "\\x00", (), "p_nul_cell"),
    Case("train-newline-in-name", "17", ("train", "no\nsuch.csv", "-o", "o.json"), 2, "no\\nsuch.csv"),
    Case("calibrate-summary-name", "17", ("calibrate", "summary.csv.csv", "s1.csv", "-o", "out", *FAM), 2,
         "batch summary", ("out", "out/**"), "p_summary_name"),
    # own: a cut-off last line, named as such in every command
    Case("train-cut-line", "own", ("train", "bad.csv", "-o", "o.json", "--terms", "5"), 2, "looks cut off", (), "p_cut_table"),
    Case("predict-cut-line", "own", ("predict", "m.json", "bad.csv", "-o", "p.csv"), 2, "looks cut off", (), "p_cut_table"),
    Case("eval-cut-line", "own", ("eval", "m.json", "bad.csv"), 2, "looks cut off", (), "p_cut_table"),
    Case("diagnose-cut-line", "own", ("diagnose", "bad.csv"), 2, "looks cut off", (), "p_cut"),
    Case("simulate-fit-cut-line", "own", ("simulate", "--fit", "bad.csv"), 2, "looks cut off", (), "p_cut_table"),
    Case("gen-family-cut-line", "own", ("gen", "--family", "bad.csv", "-o", "newfam"), 2, "looks cut off", (), "p_cut"),
    Case("calibrate-cut-line", "own", ("calibrate", "bad.csv", "s1.csv", "-o", "out", *FAM), 2, "looks cut off",
         ("out", "out/**"), "p_cut"),
    # own: one quantity in two units
    Case("train-mm-and-in", "own", ("train", "dup.csv", "-o", "o.json", "--terms", "5"), 0, "agrees with", ("o.json",), "p_dup_units"),
    Case("train-mm-and-in-disagree", "own", ("train", "bad.csv", "-o", "o.json", "--terms", "5"), 2, "disagree", (), "p_dup_disagree"),
    # own: other hostile inputs and outputs
    Case("train-binary", "own", ("train", "bad.csv", "-o", "o.json"), 2, "binary", (), "p_binary"),
    Case("predict-empty", "own", ("predict", "m.json", "bad.csv", "-o", "p.csv"), 2, "no header", (), "p_empty"),
    Case("eval-directory-as-csv", "own", ("eval", "m.json", "design"), 2, "is a directory"),
    Case("trace-directory-as-model", "own", ("predict", "fam", "rec.csv", "-o", "p.csv"), 2, "is a directory"),
    Case("gen-o-user-directory", "own", ("gen", "m.json", "-o", "mine"), 2, "not empty", (), "p_userdir"),
    Case("calibrate-o-is-file", "own", ("calibrate", "s1.csv", "-o", "out", *FAM), 2, "not a directory", (), "p_outdir_file"),
    Case("calibrate-stale-removed", "5", ("calibrate", "bad.csv", "-o", "out", *FAM), 2, "missing column",
         ("out/**",), "p_stale", absent=("out/bad/model.json", "out/bad/weights.hex", "out/bad/weights.mem")),
    Case("simulate-sensor-missing", "own", ("simulate", "nosuch.toml", "-o", "o.csv"), 2, "no such file"),
    Case("diagnose-a-step", "own", ("diagnose", "bad.csv", "--json", "d.json"), 2, "flat levels", (), "p_step"),
    Case("paper-data-repeated-positions", "own", ("paper", "--data", "bad.csv"), 0, "repeated readings averaged",
         (), "p_repeats"),
    Case("sim-build-is-a-file", "2", ("sim", "design", "--build", "afile"), 2, "exists and is not a directory",
         (), "p_afile"),
    Case("sim-manifest-file-outside-dir", "1", ("sim", "edited"), 2, "../rec.csv", (), "p_manifest_outside"),
    Case("synth-manifest-input-bits-64", "own", ("synth", "edited", "--no-lint"), 2, "input_bits", (),
         "p_manifest_wide"),
    Case("train-thousands-separator", "own", ("train", "bad.csv", "-o", "t.json", "--terms", "3"), 0,
         "thousands separator", ("t.json",), "p_thousands"),
    Case("calibrate-spec-without-tolerance", "own", ("calibrate", "s1.csv", "-o", "out", "--spec", "spec.toml", *FAM),
         2, "states no tolerance", (), "p_empty_spec"),
    Case("calibrate-recording-is-the-summary", "6", ("calibrate", "out/summary.csv", "-o", "out", *FAM), 2,
         "is the batch summary", (), "p_summary_input"),
    Case("calibrate-fewer-positions-than-terms", "own", ("calibrate", "sparse.csv", "-o", "out", *FAM), 2,
         "could not be judged", ("out", "out/**"), "p_sparse", absent=("out/sparse/weights.hex",)),
    Case("ise-o-fifo", "2", ("ise", "design", "-o", "pipe"), 2, "FIFO", (), "p_fifo"),
    Case("simulate-temperatures-1e9", "14", ("simulate", "-o", "o.csv", "--temperatures", "25,1e9"), 2,
         "within -273.15..1000 degC"),
    Case("simulate-sine-beyond-range", "14", ("simulate", "-o", "o.csv", "--temperature-profile", "sine:25:2000:60"),
         2, "within -273.15..1000 degC"),
    Case("simulate-thermal-below-its-model", "own", ("simulate", "thermal.toml", "-o", "o.csv", "--temperatures",
                                                     "-260,25"), 2, "not positive", (), "p_thermal_toml"),
    Case("sim-seed-negative", "14", ("sim", "design", "--seed", "-1"), 2, "--seed"),
    Case("synth-seed-negative", "14", ("synth", "design", "--seed", "-1", "--no-lint"), 2, "--seed"),
    Case("sim-build-holds-a-file-where-a-bench-builds", "own", ("sim", "fam", "--build", "bb"), 2,
         "bb/family: Not a directory", ("bb/**",), "p_build_file"),
    Case("sim-kept-model-outside-dir", "1", ("sim", "edited"), 2, "kept model '../m.json'", (),
         "p_manifest_model_outside"),
    # issue 48: a renamed top entity (the sweep waited for it for ever)
    Case("sim-top-entity-renamed", "own", ("sim", "design"), 2, "declared in none of the files", (), "p_top_renamed"),
    # manifest confinement and fields checked against the design
    Case("sim-init-model-outside-dir", "1", ("sim", "edited"), 2, "initial model '../m.json'", (),
         "p_init_model_outside"),
    Case("sim-init-model-absolute", "1", ("sim", "edited"), 2, "initial model '/etc/passwd'", (),
         "p_init_model_absolute"),
    Case("sim-image-model-outside-dir", "1", ("sim", "edited"), 2, "model of image 's0' '../m.json'", (),
         "p_image_model_outside"),
    Case("sim-verilator-clamp-codes-one", "own", ("sim", "edited", "--engine", "verilator"), 2,
         "'clamp_codes' must be [lowest, highest]", (), "p_clamp_codes_short"),
    Case("sim-clamp-codes-reversed", "own", ("sim", "edited"), 2, "'clamp_codes' must be [lowest, highest]", (),
         "p_clamp_codes_reversed"),
    Case("sim-family-clamp-codes-edited", "own", ("sim", "edited"), 2, "'clamp_codes' [-500, 500]", (),
         "p_family_clamp"),
    Case("sim-family-memory-edited", "own", ("sim", "edited"), 2, "'family.memory.depth'", (), "p_family_memory"),
    Case("sim-family-formats-edited", "own", ("sim", "edited"), 2, "'family.formats.weight'", (), "p_family_formats"),
    Case("sim-family-members-edited", "own", ("sim", "edited"), 2, "'family.members'", (), "p_family_members"),
    Case("sim-cfg-port-edited", "own", ("sim", "edited"), 2, "'cfg_port.ports.cfg_addr'", (), "p_cfg_port"),
    # the family hardware never wraps: an image it would wrap with is refused
    Case("sim-image-every-weight-max", "11", ("sim", "fam", "--image", "big.hex"), 2, "could overflow the hardware",
         (), "p_image_max_weights"),
    Case("sim-image-every-weight-most-negative", "11", ("sim", "fam", "--image", "big.hex"), 2,
         "could overflow the hardware", (), "p_image_min_weights"),
    Case("sim-image-word-wider-than-its-field", "11", ("sim", "fam", "--image", "big.hex"), 2,
         "does not fit the field's sint<", (), "p_image_wide_word"),
    # tracebacks
    Case("synth-vsg-config-alias-bomb", "12", ("synth", "design", "--vsg-config", "bomb.yaml"), 2, "YAML alias",
         (), "p_alias_bomb"),
    Case("synth-vsg-config-python-tag", "12", ("synth", "design", "--vsg-config", "tag.yaml"), 2,
         "not a VSG configuration", (), "p_python_tag"),
    # lost or polluted outputs
    Case("sim-build-is-a-design", "own", ("sim", "design", "--build", "fam"), 2, "is a flann design directory"),
    Case("sim-build-inside-a-design", "own", ("sim", "design", "--build", "design/build"), 2,
         "lies inside", (), "p_build_in_design"),
    Case("synth-work-is-a-design", "own", ("synth", "design", "--work", "design", "--no-lint"), 2,
         "is a flann design directory"),
    Case("gen-family-over-its-own-design", "own", ("gen", "--family", "s0.csv", "s1.csv", "-o", "fam",
                                                   "--input-bits", "10"), 0, "replaced the flann design in fam",
         ("fam", "fam/*")),
    # hangs: a FIFO member nobody writes
    Case("calibrate-fifo-member", "2", ("calibrate", "s1.csv", "pipe.csv", "-o", "out", *FAM), 2,
         "is a FIFO (named pipe)", ("out", "out/**"), "p_fifo_member"),
    # misleading lines
    Case("flann-no-command", "17", (), 2, "no command given"),
    # certificates: nothing judged without a specification
    Case("calibrate-without-a-spec-is-not-judged", "own", ("calibrate", "s1.csv", "-o", "out", *FAM), 0,
         "1 of 1 sensor(s) calibrated and NOT JUDGED", sane("s1")),
    Case("calibrate-reference-standard-expired", "own", ("calibrate", "s1.csv", "-o", "out", "--reference-due",
                                                         "2001-01-01", *FAM), 2, "calibration expired"),
]
OBSERVED: dict[str, tuple[int, str]] = {}


def snapshot(root: Path) -> dict[str, tuple]:
    """Every entry under root: kind, mode and content hash (or link target)."""
    out = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for name in dirnames + filenames:
            p = Path(dirpath) / name
            st = os.lstat(p)
            rel = str(p.relative_to(root))
            if stat.S_ISLNK(st.st_mode):
                out[rel] = ("link", os.readlink(p))
            elif stat.S_ISREG(st.st_mode):
                out[rel] = ("file", stat.S_IMODE(st.st_mode), hashlib.sha256(p.read_bytes()).hexdigest())
            else:
                out[rel] = (stat.S_IFMT(st.st_mode),)
    return out


def run_case(case: Case, capsys) -> tuple[int, str, str]:
    capsys.readouterr()
    try:
        rc = main(list(case.argv))
    except SystemExit as exc:   # argparse refusals
        rc = exc.code
    out = capsys.readouterr()
    return rc, out.out, out.err


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_hostile(case, world, capsys, monkeypatch):
    monkeypatch.setattr(csvio, "MAX_ROWS", getattr(csvio, "MAX_ROWS", None), raising=False)   # p_many_rows lowers it
    root = world.parent
    before = snapshot(root)
    if case.prep:
        globals()[case.prep](world)
        before = snapshot(root)
    rc, out, err = run_case(case, capsys)
    after = snapshot(root)
    errors = [ln for ln in err.splitlines() if ln.startswith("error:")]
    said = [ln for ln in (out + err).splitlines() if case.expect and case.expect in ln] or (out + err).splitlines()
    # the table shows the world as w/, not this run's temporary path
    OBSERVED[case.id] = (rc, (errors[0] if errors else (said or [""])[0]).replace(str(world), "w"))
    assert "Traceback" not in err, err
    assert rc == case.rc, err
    assert len(errors) == (1 if case.rc else 0), err
    if case.rc:
        assert case.expect in errors[0], errors[0]
    else:
        assert case.expect in out + err
    allowed = ["w/" + pat for pat in case.changes]
    changed = {k for k in before.keys() | after.keys() if before.get(k) != after.get(k)}
    stray = sorted(k for k in changed if not any(fnmatch.fnmatch(k, pat) for pat in allowed))
    assert not stray, f"changed outside the expected place: {stray}"
    assert not [p for p in case.absent if (world / p).exists()], "a stale result survived"


def test_the_table_covers_every_subcommand_and_class():
    from flann.cli import COMMANDS

    used = {c.argv[0] for c in CASES if c.argv}
    assert used == set(COMMANDS), set(COMMANDS) - used
    assert len(CASES) >= 60
    assert {str(k) for k in range(1, 18)} - {"3", "4", "7", "13", "15"} <= {c.klass for c in CASES}


def pytest_sessionfinish_table(path: Path) -> None:
    passed = sum(1 for c in CASES if c.id in OBSERVED and OBSERVED[c.id][0] == c.rc)
    lines = ["# Hostile inputs: the suite's table", "",
             "Generated by `FLANN_HOSTILE_TABLE=docs/hostile_inputs.md .venv/bin/python -m pytest "
             "tests/hostile/test_hostile_inputs.py` from the table `CASES` in that file and what each "
             "case observed; do not edit by hand.", "",
             f"**{len(CASES)} cases** over all {len({c.argv[0] for c in CASES if c.argv})} subcommands, {passed} with the "
             "expected exit code.  Each case also asserts: exactly one `error:` line when the exit code is "
             "not 0 (none when it is), no traceback, and no file created, changed or removed outside the "
             "paths it may write (the whole temporary tree is hashed before and after).  Class = the hostile-input "
             "defect class (1-17) or `own`.  Faults (a 200 kB tmpfs, a write error inside a design and "
             "inside one sensor of a batch, Ctrl-C during start-up and in a calibrate pool, SIGTERM) are in "
             "`tests/hostile/test_faults.py`.", "",
             "| # | case | class | command | expected | observed |", "|---|---|---|---|---|---|"]
    for n, c in enumerate(CASES, 1):
        cmd = "flann" + "".join(" " + (json.dumps(a)[1:-1] if (" " in a or "\\" in json.dumps(a)) else a) for a in c.argv)
        exp = f"exit {c.rc}" + (f", error line with `{c.expect}`" if c.rc else f", `{c.expect}`")
        rc, line = OBSERVED.get(c.id, (None, "not run"))
        obs = f"exit {rc}: {line}".replace("|", "\\|")
        lines.append(f"| {n} | {c.id} | {c.klass} | `{cmd}` | {exp} | {obs} |")
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module", autouse=True)
def _write_table():
    yield
    target = os.environ.get("FLANN_HOSTILE_TABLE")
    if target:
        pytest_sessionfinish_table(Path(target))
