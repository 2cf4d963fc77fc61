"""flann calibrate's files as documented (docs/production.md): the certificate's noise on
repeated sweeps, the summary's judged range, weights.hex read by its documented rule, two
recordings of one name, and the summary path printed."""

from __future__ import annotations

import csv
import hashlib
import json
import re
import shutil

import numpy as np
import pytest

from flann.cli import main
from flann.golden.model import load_model
from flann.hardware.family.render import load_design
from flann.hardware.family.twin import FlannFamilyTop
from flann.recordings import read_recordings

NOISE_V = 0.002


@pytest.fixture(scope="session")
def line(once, in_process, data_dir):
    """Two-sweep recordings of the paper's LVDT (2 mV noise), a one-sweep one, and the
    family design sized from the two-sweep ones, made once per test run."""
    def make(d):
        lvdt = data_dir / "sensors" / "paper_lvdt.toml"
        rec = {}
        for name, sweeps, seed in (("s1", 2, 1), ("s2", 2, 2), ("one", 1, 3)):
            rec[name] = d / f"{name}.csv"
            if in_process(["simulate", lvdt, "--sweeps", sweeps, "--step-mm", 0.5, "--noise-v", NOISE_V,
                           "--seed", seed, "-o", rec[name]])[0]:
                raise RuntimeError(f"flann simulate of {name} failed")
        design = d / "fam12"
        if in_process(["gen", "--family", rec["s1"], rec["s2"], "-o", design])[0]:
            raise RuntimeError("flann gen --family failed")
        return {"dir": d, "rec": rec, "design": design}
    return once("calibrate_outputs_line", make)


def _calibrate(line, out, *args):
    rc = main(["calibrate", *map(str, args), "-o", str(out), "--design", str(line["design"]), "-j", "1"])
    with open(out / "summary.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    return rc, rows


def test_certificate_noise_of_a_two_sweep_recording(line, tmp_path):
    """The certificate gave 60.2 mV for this recording's 2 mV noise, and U marked a sensor far
    inside its tolerance marginal."""
    out = tmp_path / "cal"
    rc, rows = _calibrate(line, out, line["rec"]["s1"], "--tolerance-mm", "0.5")
    assert rc == 0
    html = (out / "s1" / "certificate.html").read_text()
    mv = float(re.search(r"noise of one reading</td><td[^>]*>([0-9.]+) mV", html).group(1))
    assert mv == pytest.approx(1e3 * NOISE_V, rel=0.2)
    assert rows[0]["verdict"] == "PASS" and float(rows[0]["max_error_mm"]) < 0.25
    assert rows[0]["reasons"] == ""     # not "marginal: ... within U of the tolerance"


def test_summary_says_what_the_verdict_judged(line, tmp_path):
    """With a working range, max_error_mm is the whole recording's; judged_max_error_mm and
    max_error_pct_fs are over the range the verdict judged, named in judged_over."""
    out = tmp_path / "cal"
    rc, rows = _calibrate(line, out, line["rec"]["one"], "--working-range=-10:10", "--tolerance-pct-fs", "2")
    assert rc == 0
    (r,) = rows
    assert r["verdict"] == "PASS" and r["judged_over"] == "-10..10 mm"
    # the hardware error, recomputed from the written image through the design's twin
    fam = load_design(line["design"])
    s = fam.spec
    words = [int(w, 16) for w in (out / "one" / "weights.hex").read_text().splitlines()
             if not w.startswith("#")]
    rec = read_recordings(line["rec"]["one"])
    x = np.asarray(rec.displacement_mm, dtype=float)
    codes = np.clip(np.floor(np.asarray(rec.voltage_v) / s.input_lsb_v + 0.5).astype(int), s.code_min, s.code_max)
    err = np.abs(FlannFamilyTop(fam, words).process(codes)[0] * s.output_lsb_mm - x)
    whole, judged = float(err.max()), float(err[np.abs(x) <= 10].max())
    assert whole > 1.5 * judged     # the S-curve's ends are worse: the two figures differ here
    assert float(r["max_error_mm"]) == pytest.approx(whole, rel=1e-4)
    assert float(r["judged_max_error_mm"]) == pytest.approx(judged, rel=1e-4)
    # full scale: half the working range's span, 10 mm
    assert float(r["max_error_pct_fs"]) == pytest.approx(100 * judged / 10, rel=1e-3)
    # without a working range the verdict judges the whole recorded stroke
    rc, (r,) = _calibrate(line, tmp_path / "whole", line["rec"]["one"])
    assert r["judged_over"] == "the recorded stroke -30..30 mm"
    assert r["judged_max_error_mm"] == r["max_error_mm"]


def test_weights_hex_read_by_the_documented_rule(line, tmp_path):
    """'#' lines first, then one 32-bit word per line, address 0 first, the memory's depth."""
    out = tmp_path / "cal"
    rc, (row,) = _calibrate(line, out, line["rec"]["s1"])
    assert rc == 0
    lines = (out / "s1" / "weights.hex").read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    body = [ln for ln in lines if not ln.startswith("#")]
    assert head and lines[:len(head)] == head           # the comments come first
    assert f"# design sha256 {row['design_sha256']}" in head
    model_json = (out / "s1" / "model.json").read_bytes()
    assert f"# model sha256 {hashlib.sha256(model_json).hexdigest()}" in head
    assert all(re.fullmatch(r"[0-9a-fA-F]{8}", ln) for ln in body)
    words = [int(ln, 16) for ln in body]
    memory = json.loads((line["design"] / "manifest.json").read_text())["family"]["memory"]
    assert len(words) == memory["depth"]
    # address order: the clamp words sit at their manifest addresses and hold the input codes
    # of the recording's voltage range
    fam = load_design(line["design"])
    lsb = fam.spec.input_lsb_v
    at = {f["name"]: f["addr"] for f in memory["fields"]}
    signed = [w - (1 << 32) if w >> 31 else w for w in words]
    v = np.asarray(read_recordings(line["rec"]["s1"]).voltage_v, dtype=float)
    assert abs(signed[at["clamp_lo"]] - v.min() / lsb) <= 2
    assert abs(signed[at["clamp_hi"]] - v.max() / lsb) <= 2
    # and the twin holding them is the model written beside it, within one output LSB
    codes = np.arange(signed[at["clamp_lo"]], signed[at["clamp_hi"]] + 1)
    hw = FlannFamilyTop(fam, words).process(codes)[0] * fam.spec.output_lsb_mm
    ref = load_model(out / "s1" / "model.json").predict(codes * lsb)
    assert np.max(np.abs(hw - ref)) <= fam.spec.output_lsb_mm


def test_two_recordings_of_one_name(line, tmp_path, capsys):
    """The first is calibrated; a later one of the same name (letter case ignored) cannot
    have that folder: a rejected row with the reason and an error line, and the batch goes on."""
    src = line["rec"]
    for rel, f in (("a/s1.csv", "s1"), ("b/s1.csv", "s2"), ("c/S1.csv", "s2"), ("one.csv", "one")):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(src[f], tmp_path / rel)
    out = tmp_path / "cal"
    capsys.readouterr()
    rc, rows = _calibrate(line, out, *(tmp_path / p for p in ("a/s1.csv", "b/s1.csv", "c/S1.csv", "one.csv")),
                          "--tolerance-mm", "0.5")
    assert rc == 2
    assert [(r["sensor"], r["status"], r["verdict"]) for r in rows] == \
        [("s1", "ok", "PASS"), ("s1", "failed", "FAIL"), ("S1", "failed", "FAIL"), ("one", "ok", "PASS")]
    for r in rows[1:3]:
        assert r["reasons"].startswith("rejected: ") and f"already used by {tmp_path / 'a/s1.csv'}" in r["reason"]
        assert r["tolerance"] == rows[0]["tolerance"] != ""
        assert r["max_error_mm"] == r["judged_max_error_mm"] == ""
    err = capsys.readouterr().err
    assert err.count("error: ") == 2 and "Traceback" not in err
    # one folder per name, holding the first recording's certificate
    assert sorted(p.name for p in out.iterdir()) == ["one", "s1", "summary.csv"]
    html = (out / "s1" / "certificate.html").read_text()
    assert hashlib.sha256((tmp_path / "a/s1.csv").read_bytes()).hexdigest() in html


def test_summary_path_printed_once_joined(line, tmp_path, capsys):
    out = tmp_path / "calibrated"
    capsys.readouterr()
    rc = main(["calibrate", str(line["rec"]["one"]), "-o", f"{out}/", "--design", str(line["design"]), "-j", "1"])
    assert rc == 0
    printed = capsys.readouterr().out
    assert f"summary {out / 'summary.csv'}" in printed and "//" not in printed


def test_too_few_positions_for_the_terms_are_rejected(line, tmp_path, capsys):
    """Six positions for the design's terms calibrated to PASS at 0 mm (its error between the
    positions was 21 mm): the error at the positions cannot be judged, so the sensor is
    rejected, and its row carries no figures measured before the rejection."""
    rows = read_recordings(line["rec"]["s1"])
    x = rows.displacement_mm
    keep = np.isin(x, np.unique(x)[::20])
    sparse = tmp_path / "sparse.csv"
    np.savetxt(sparse, np.column_stack([x[keep], rows.voltage_v[keep]]), delimiter=",",
               header="displacement_mm,voltage_v", comments="")
    out = tmp_path / "cal"
    rc, got = _calibrate(line, out, sparse, line["rec"]["s2"], "--tolerance-mm", "0.5")
    err = capsys.readouterr().err
    terms = json.loads((line["design"] / "manifest.json").read_text())["spec"]["terms"]
    row = {r["sensor"]: r for r in got}
    assert rc != 0 and row["s2"]["verdict"] == "PASS"
    assert row["sparse"]["verdict"] == "FAIL" and row["sparse"]["status"] == "failed"
    assert f"{np.unique(x[keep]).size} positions for the design's {terms} terms" in row["sparse"]["reason"]
    assert all(row["sparse"][k] == "" for k in ("max_error_mm", "ratio_to_limit", "limit_mm",
                                                 "raw_max_error_mm", "twin_vs_float_lsb", "max_error_pct_fs"))
    assert not (out / "sparse" / "weights.hex").exists() and (out / "sparse" / "certificate.html").is_file()
    assert "sparse" in err and "Traceback" not in err


def test_a_recording_at_the_summarys_path_is_refused_before_any_work(line, tmp_path, capsys):
    """OUTDIR/summary.csv given as a recording was calibrated into OUTDIR/summary/ before the
    summary's write refused it."""
    out = tmp_path / "oc"
    out.mkdir()
    shutil.copy(line["rec"]["s1"], out / "summary.csv")
    rc = main(["calibrate", str(out / "summary.csv"), "-o", str(out), "--design", str(line["design"]), "-j", "1"])
    err = capsys.readouterr().err
    assert rc == 2 and "is the batch summary this run writes" in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in out.iterdir()) == ["summary.csv"]


def test_the_family_costs_accuracy_flag_reaches_the_summary_and_the_console(line, tmp_path, capsys,
                                                                          monkeypatch):
    """The flag of a sensor whose hardware error exceeds its own design's reach by more than
    REACH_FACTOR was on the certificate only: it is now a summary column (with the reach beside
    it) and a warning line.  The factor is moved so that the same sensor is flagged, then not."""
    from flann.production import calibrate as production
    for factor, flagged in ((1e-3, True), (1e6, False)):
        monkeypatch.setattr(production, "REACH_FACTOR", factor)
        out = tmp_path / f"cal{factor:g}"
        capsys.readouterr()
        rc, rows = _calibrate(line, out, line["rec"]["s1"], "--tolerance-mm", "0.5")
        err = capsys.readouterr().err
        (row,) = rows
        assert rc == 0 and float(row["own_design_max_error_mm"]) > 0
        assert ("the family design costs it accuracy" in row["warnings"]) is flagged, row["warnings"]
        assert ("warning: s1: hardware max error" in err) is flagged, err
        html = (out / "s1" / "certificate.html").read_text()
        assert ("the family design costs it accuracy" in html) is flagged


def test_a_certificate_without_a_spec_is_not_judged_and_names_its_reference(line, tmp_path, capsys):
    """No specification: NOT JUDGED on the certificate, in the summary and in the last line
    (never PASS); the certificate number, the reference standard and its due date, page numbers."""
    out = tmp_path / "cal"
    capsys.readouterr()
    rc, rows = _calibrate(line, out, line["rec"]["one"], "--reference-standard", "gauge block set GB-7",
                          "--reference-due", "2099-12-31", "--certificate-prefix", "QA")
    printed = capsys.readouterr().out
    assert rc == 0
    assert rows[0]["verdict"] == "NOT JUDGED" and rows[0]["status"] == "ok"
    assert "1 of 1 sensor(s) calibrated and NOT JUDGED" in printed and "PASS" not in printed
    html = (out / "one" / "certificate.html").read_text()
    assert "NOT JUDGED: no specification given" in html and "PASS:" not in html
    number = re.search(r"Certificate no\. (QA-\d{8}-\d{6}-[0-9a-f]{8})", html).group(1)
    assert number[-8:] == hashlib.sha256((line["rec"]["one"]).read_bytes()).hexdigest()[:8]
    assert "gauge block set GB-7" in html and "2099-12-31" in html
    assert 'counter(page) " of " counter(pages)' in html
    assert (out / "one" / "weights.hex").is_file()   # calibrated: its weights are written
