"""flann calibrate on a small simulated batch with bad files (the 200-sensor batch is bench/bench_calibrate.py)."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from flann.cli import main
from flann.golden.model import load_model
from flann.hardware.family.render import design_hash, load_design
from flann.hardware.family.twin import FlannFamilyTop
from flann.production.demo import bad_files, write_batch
from flann.hardware.family.images import header_fields, parse_hex
from flann.recordings import read_recordings


@pytest.fixture(scope="session")
def batch(once, in_process):
    """Three good recordings and the bad files, the family designed from two of them and the
    batch calibrated, once per test run."""
    def make(d):
        good = write_batch(d / "rec", 3, seed=7, points=600)
        bad = bad_files(d / "rec")
        design = d / "design"
        rc, _out, err = in_process(["gen", "--family", *good[:2], "-o", design, "--input-bits", 10])
        if rc != 0:
            raise RuntimeError(f"flann gen --family failed: {err}")
        out = d / "out"
        rc = in_process(["calibrate", *good, *bad, "-o", out, "--design", design, "-j", 2])[0]
        with open(out / "summary.csv", newline="") as fh:
            rows = {r["sensor"]: r for r in csv.DictReader(fh)}
        return {"good": good, "bad": bad, "design": design, "out": out, "rc": rc, "rows": rows}
    return once("calibrate_batch", make)


def test_batch_reports_bad_rows_and_goes_on(batch):
    assert batch["rc"] == 2
    rows = batch["rows"]
    assert len(rows) == 6
    for p in batch["bad"]:
        r = rows[p.stem]
        assert r["status"] == "failed" and r["reason"], r
        assert r["verdict"] == "FAIL" and r["reasons"].startswith("rejected: "), r
        # a rejected sensor gets a certificate saying why, and no weights a loader could use
        assert sorted(q.name for q in (batch["out"] / p.stem).iterdir()) == ["certificate.html"]
        assert "FAIL" in (batch["out"] / p.stem / "certificate.html").read_text()
    assert "voltage_v" in rows["bad_no_voltage"]["reason"]
    assert "exceeds the design's input" in rows["bad_out_of_family"]["reason"]
    for p in batch["good"]:
        assert rows[p.stem]["status"] == "ok", rows[p.stem]
    # nothing half-written: no temporary files or folders anywhere
    assert not [p for p in batch["out"].rglob(".*")]


def test_certificate_is_self_contained(batch):
    for p in batch["good"]:
        html = (batch["out"] / p.stem / "certificate.html").read_text()
        assert html.count("<svg") == 1 and html.count("<polyline") == 4  # raw, compensated, +-limit
        assert 'src="http' not in html and 'href="http' not in html and "<script" not in html
        man_hash = json.loads((batch["out"] / p.stem / "model.json").read_text())  # readable model
        assert man_hash["terms"] == load_design(batch["design"]).terms
        assert "physical limit" in html and "design sha256" in html


def test_weight_image_reproduces_the_recording(batch):
    """The hex image, through the design's twin, measures the recording as the summary says,
    and stays within one output LSB of the float model written beside it."""
    fam = load_design(batch["design"])
    s = fam.spec
    for p in batch["good"]:
        d = batch["out"] / p.stem
        words = parse_hex((d / "weights.hex").read_text())
        assert len(words) == fam.mem_depth
        # the header names the design the image was calibrated for and its size, as sim --image checks them
        assert header_fields((d / "weights.hex").read_text()) == (design_hash(batch["design"]), fam.mem_depth)
        twin = FlannFamilyTop(fam, words)
        rec = read_recordings(p)
        codes = np.clip(np.floor(rec.voltage_v / s.input_lsb_v + 0.5).astype(int), s.code_min, s.code_max)
        out, _ = twin.process(codes)
        model = load_model(d / "model.json")
        ref = model.predict(codes * s.input_lsb_v)
        assert np.max(np.abs(out * s.output_lsb_mm - ref)) <= s.output_lsb_mm
        err = float(np.max(np.abs(out * s.output_lsb_mm - rec.displacement_mm)))
        assert err == pytest.approx(float(batch["rows"][p.stem]["max_error_mm"]), rel=1e-4)
        # the .mem file holds the same words as the block RAM does: 16-bit halves, low half first
        mem = [int(h, 16) for h in (d / "weights.mem").read_text().split("@0000", 1)[1].split()]
        assert len(mem) == 2 * len(words) and max(mem) < 2 ** 16
        assert [lo | hi << 16 for lo, hi in zip(mem[0::2], mem[1::2])] == words


def test_duplicate_names_and_missing_design(batch, tmp_path, capsys):
    p = batch["good"][0]
    rc = main(["calibrate", str(p), str(p), "-o", str(tmp_path / "o"), "--design", str(tmp_path / "none")])
    assert rc == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_bad_options_stop_before_any_work(batch, tmp_path, capsys):
    p, design = batch["good"][0], batch["design"]
    bad_toml = tmp_path / "bad.toml"
    bad_toml.write_text("x = [\n")
    for extra in (["--diagnosis-points", "-1"], ["--sensor", str(bad_toml)], ["-j", "0"]):
        assert main(["calibrate", str(p), "-o", str(tmp_path / "o"), "--design", str(design), *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("error: ") == 3 and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_spec_verdicts_certificates_and_summary(batch, tmp_path):
    """A tolerance between the good sensors' errors: those above FAIL (certificate, no
    weights), those below PASS; the summary has the verdict and traceability columns; the
    exit code says a sensor failed (1: no bad input among them)."""
    good = batch["good"]
    errs = sorted(float(batch["rows"][p.stem]["max_error_mm"]) for p in good)
    tol = (errs[0] + errs[1]) / 2
    spec = tmp_path / "spec.toml"
    spec.write_text(f'name = "line A"\n[tolerance]\nmax_error_mm = {tol}\n')
    out = tmp_path / "o"
    rc = main(["calibrate", *map(str, good), "-o", str(out), "--design", str(batch["design"]), "-j", "1",
               "--spec", str(spec), "--station", "S1", "--operator", "Ann", "--fixture", "F9",
               "--temperature-c", "23.5"])
    assert rc == 1
    with open(out / "summary.csv", newline="") as fh:
        reader = csv.DictReader(fh)
        rows = {r["sensor"]: r for r in reader}
        cols = reader.fieldnames
    for c in ("verdict", "reasons", "tolerance", "max_error_pct_fs", "diagnosis", "design_sha256",
              "model_sha256", "calibrated_at", "station", "operator", "temperature_c"):
        assert c in cols
    for p in good:
        r = rows[p.stem]
        passed = float(r["max_error_mm"]) <= tol
        assert r["verdict"] == ("PASS" if passed else "FAIL"), r
        assert (r["station"], r["operator"], r["temperature_c"]) == ("S1", "Ann", "23.5")
        # a failed sensor's folder holds no model, and its row names none
        assert len(r["design_sha256"]) == 64 and len(r["model_sha256"]) == (64 if passed else 0) and r["diagnosis"]
        html = (out / p.stem / "certificate.html").read_text()
        assert ("PASS: " if passed else "FAIL: ") in html and "k = 2" in html and "F9" in html
        assert html.count("<polyline") == 6 and "tolerance +-" in html    # the tolerance band
        assert "@page { size: A4" in html and "<script" not in html
        files = sorted(q.name for q in (out / p.stem).iterdir())
        assert (files == ["certificate.html"]) != passed, files          # no weights for a FAIL
    assert sum(r["verdict"] == "FAIL" for r in rows.values()) == 2
