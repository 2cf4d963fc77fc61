"""Every golden-model subcommand through flann.cli.main, and bad input -> one line, exit 2."""

import csv
import json

import numpy as np
import pytest

from flann.cli import main
from flann.golden.paper import TABLE1_DISPLACEMENT_MM, TABLE1_VOLTAGE_V, s_curve
from flann.recordings import read_recordings

TABLE1 = "data/paper_table1.csv"


def run(argv, capsys):
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as exc:   # a flag refused by its argparse type: one line, exit 2
        rc = exc.code
    out, err = capsys.readouterr()
    return rc, out, err


def write_csv(path, x, v, extra_header=""):
    lines = ["displacement_mm,voltage_v"] + [f"{float(a)!r},{float(b)!r}" for a, b in zip(x, v)]
    path.write_text(extra_header + "\n".join(lines) + "\n")
    return path


def test_builtin_table1_equals_the_data_file():
    rec = read_recordings(TABLE1)
    np.testing.assert_array_equal(rec.displacement_mm, TABLE1_DISPLACEMENT_MM)
    np.testing.assert_array_equal(rec.voltage_v, TABLE1_VOLTAGE_V)


def test_train_51_lstsq_default_design_is_deterministic(tmp_path, capsys):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    rc, _, err = run(["train", TABLE1, "--terms", 51, "--method", "lstsq", "-o", a], capsys)
    assert rc == 0 and "under-determined" in err and "held-out (cross-validation)" in err
    assert run(["train", TABLE1, "--terms", 51, "--method", "lstsq", "-o", b], capsys)[0] == 0
    assert a.read_bytes() == b.read_bytes()
    d = json.loads(a.read_text())
    assert d["format"] == "flann-model/1" and d["terms"] == 51 and len(d["weights"]) == 51
    # range normalisation by default: midpoint and half span of -5.185 .. 5.276 V
    assert d["input_offset_v"] == pytest.approx(0.0455)
    assert d["input_scale_v"] == pytest.approx(5.2305)
    assert d["training"]["method"] == "lstsq"
    assert d["voltage_range_v"] == [-5.185, 5.276]


def test_checked_in_default_model_matches_a_fresh_training(tmp_path, capsys):
    out = tmp_path / "m.json"
    run(["train", TABLE1, "--terms", 51, "--method", "lstsq", "-o", out], capsys)
    fresh = json.loads(out.read_text())
    committed = json.loads(open("data/default_model.json").read())
    np.testing.assert_allclose(committed["weights"], fresh["weights"], rtol=1e-9, atol=1e-9)
    assert committed["input_scale_v"] == fresh["input_scale_v"]


def test_train_lms_records_mse_per_epoch(tmp_path, capsys):
    out = tmp_path / "m.json"
    rc, _, err = run(["train", TABLE1, "--terms", 11, "--method", "lms", "--eta", "0.01",
                      "--epochs", 20, "--normalise", "none", "-o", out], capsys)
    assert rc == 0 and "lms" in err
    d = json.loads(out.read_text())
    assert d["training"]["eta"] == 0.01 and d["training"]["epochs"] == 20
    assert len(d["training"]["mse_per_epoch"]) == 20
    assert (d["input_offset_v"], d["input_scale_v"]) == (0.0, 1.0)


def test_train_takes_a_fraction_as_its_normalisation(tmp_path, capsys):
    out = tmp_path / "m.json"
    rc, _, err = run(["train", TABLE1, "--terms", 11, "--normalise", "0.85", "-o", out], capsys)
    assert rc == 0, err
    d = json.loads(out.read_text())
    assert d["training"]["normalisation"] == "0.85"
    assert d["input_scale_v"] == pytest.approx((5.276 + 5.185) / 2 / 0.85)


def test_train_auto_reports_held_out_error(tmp_path, capsys):
    x = np.linspace(-30, 30, 61)
    data = write_csv(tmp_path / "s.csv", x, s_curve(x, 1e-3, seed=4))
    out = tmp_path / "m.json"
    rc, _, err = run(["train", data, "-o", out], capsys)
    assert rc == 0 and "held-out error" in err
    assert "cv_heldout_rms_error_mm" in json.loads(out.read_text())["training"]


def test_train_trim(tmp_path, capsys):
    x = np.arange(-45.0, 45.5, 0.5)
    v = 6.0 * (x / 35.0) * np.exp(0.5 - 0.5 * (x / 35.0) ** 2)   # peaks at +-35 mm
    data = write_csv(tmp_path / "f.csv", x, v)
    out = tmp_path / "m.json"
    rc, _, err = run(["train", data, "--terms", 7, "--trim", "-o", out], capsys)
    assert rc == 0 and "output turns back at +35 mm and -35 mm: trained on -35..35 mm" in err
    assert json.loads(out.read_text())["displacement_range_mm"] == [-35.0, 35.0]


def hand_model(tmp_path):
    # y = 0.5 + 2 * v (one term, raw volts)
    m = {"format": "flann-model/1", "terms": 1, "input_offset_v": 0.0, "input_scale_v": 1.0,
         "bias": 0.5, "weights": [2.0], "voltage_range_v": [-2.0, 2.0],
         "displacement_range_mm": [-4.0, 4.0], "training": {}}
    p = tmp_path / "hand.json"
    p.write_text(json.dumps(m))
    return p


def test_readings_past_the_range_by_the_training_noise_are_flagged_not_warned(tmp_path, capsys):
    # a curve-fitted model's range ends at the curve's ends; the noisiest end readings of its
    # own training file pass them: 2.03 V is 1.5 sigma of 20 mV past 2 V, 2.2 V is 10 sigma
    m = json.loads(hand_model(tmp_path).read_text())
    m["training"] = {"noise_v": 0.02}
    model = tmp_path / "noisy.json"
    model.write_text(json.dumps(m))
    data = tmp_path / "v.csv"
    out = tmp_path / "p.csv"
    data.write_text("voltage_v\n2.03\n-2.05\n1\n")
    code, _, err = run(["predict", model, data, "-o", out], capsys)
    assert code == 0 and err == ""
    assert [r["clamped"] for r in csv.DictReader(out.open())] == ["1", "1", "0"]
    data.write_text("voltage_v\n2.03\n2.2\n1\n")
    code, _, err = run(["predict", model, data, "-o", out], capsys)
    assert code == 0 and "1 of 3 voltages outside" in err
    assert "1 more past its ends by less than 4x the training noise" in err
    assert [r["clamped"] for r in csv.DictReader(out.open())] == ["1", "1", "0"]


def test_predict_writes_every_row(tmp_path, capsys):
    data = write_csv(tmp_path / "r.csv", [-4.0, 0.0, 4.0], [-2.0, 0.0, 1.0])
    out = tmp_path / "p.csv"
    assert run(["predict", hand_model(tmp_path), data, "-o", out], capsys)[0] == 0
    rows = list(csv.DictReader(out.open()))
    assert list(rows[0]) == ["voltage_v", "displacement_mm", "predicted_mm", "clamped"]
    assert [float(r["predicted_mm"]) for r in rows] == [-3.5, 0.5, 2.5]
    assert [r["clamped"] for r in rows] == ["0", "0", "0"]


def test_predict_clamps_outside_the_trained_range_like_the_hardware(tmp_path, capsys):
    # trained range [-2, 2] V, y = 0.5 + 2 v: 3 V and -7 V are clamped to 2 V and -2 V
    data = tmp_path / "v.csv"
    data.write_text("voltage_v\n3\n-7\n1\n")
    out = tmp_path / "p.csv"
    code, _, err = run(["predict", hand_model(tmp_path), data, "-o", out], capsys)
    assert code == 0 and "2 of 3 voltages outside" in err and "clamped" in err
    assert out.read_text() == "voltage_v,predicted_mm,clamped\n3,4.5,1\n-7,-3.5,1\n1,2.5,0\n"
    code, _, err = run(["predict", hand_model(tmp_path), data, "-o", out, "--extrapolate"], capsys)
    # evaluated outside the range, and each row says so
    assert out.read_text() == "voltage_v,predicted_mm,extrapolated\n3,6.5,1\n-7,-13.5,1\n1,2.5,0\n"


def test_predict_without_displacement_column(tmp_path, capsys):
    data = tmp_path / "v.csv"
    data.write_text("voltage_v\n-2\n1\n")
    out = tmp_path / "p.csv"
    assert run(["predict", hand_model(tmp_path), data, "-o", out], capsys)[0] == 0
    assert out.read_text() == "voltage_v,predicted_mm,clamped\n-2,-3.5,0\n1,2.5,0\n"


def test_eval_json_by_hand(tmp_path, capsys):
    # y = 0.5 + 2 v at v = -2, 0, 1, 2 -> -3.5, 0.5, 2.5, 4.5 vs x = -4, 0, 2, 4:
    # errors 0.5 each; FS = 4 mm; max = RMS = 0.5 mm = 12.5 % FS
    data = write_csv(tmp_path / "r.csv", [-4.0, 0.0, 2.0, 4.0], [-2.0, 0.0, 1.0, 2.0])
    rc, out, _ = run(["eval", hand_model(tmp_path), data, "--json"], capsys)
    assert rc == 0
    r = json.loads(out)
    c = r["compensated"]
    assert r["full_scale_mm"] == 4.0
    assert c["max_error_mm"] == pytest.approx(0.5) and c["rms_error_mm"] == pytest.approx(0.5)
    assert c["max_error_pct_fs"] == pytest.approx(12.5)
    assert c["linearity_pct"] == 0.0                   # 0.5 mm > 2 % of 4 mm
    assert c["stroke_fraction_within_band"] == 0.0
    # raw: x = 2 v exactly -> its LS line is perfect
    assert r["raw"]["max_error_mm"] == pytest.approx(0.0, abs=1e-12)
    assert r["raw"]["linearity_pct"] == 100.0
    rc, out, _ = run(["eval", hand_model(tmp_path), data], capsys)
    assert rc == 0 and "% of linearity range" in out


def test_paper_json_and_plots(tmp_path, capsys):
    rc, out, _ = run(["paper", "--json", "--plot", tmp_path / "fig"], capsys)
    assert rc == 0
    d = json.loads(out)
    assert set(d) == {"raw_linearity_pct", "tolerance_pct_fs", "rows"}
    assert d["raw_linearity_pct"] == 15.38 and d["tolerance_pct_fs"] == 2.0
    rows = {r["terms"]: r for r in d["rows"]}
    assert list(rows) == [11, 25, 51, 61]
    assert all(set(r) == {"terms", "linearity_pct", "paper_pct", "loo_max_error_mm"}
               for r in d["rows"])
    assert rows[51]["linearity_pct"] == 100.0 and rows[61]["linearity_pct"] == 100.0
    # 11 and 25 terms within 2 of 13 points of the paper (one point = 7.69 %)
    assert abs(rows[11]["linearity_pct"] - 38.46) <= 15.39
    assert abs(rows[25]["linearity_pct"] - 84.62) <= 15.39
    assert [rows[t]["paper_pct"] for t in (11, 25, 51, 61)] == [38.46, 84.62, 100.0, 100.0]
    assert all(r["loo_max_error_mm"] > 0 for r in d["rows"])
    pngs = sorted(p.name for p in (tmp_path / "fig").glob("*.png"))
    assert pngs == ["between_points_51.png", "fig5.png"]
    assert all((tmp_path / "fig" / p).read_bytes()[:4] == b"\x89PNG" for p in pngs)


def test_paper_text_report(capsys):
    rc, out, _ = run(["paper", "--epochs", 50], capsys)
    assert rc == 0 and "15.38" in out and "Between the 13 points" in out


# -- bad input: one line on stderr, exit 2, nothing written ------------------------------
BAD_CSV = {
    "missing_column": "displacement_mm\n1\n2\n3\n",
    "non_numeric": "displacement_mm,voltage_v\n0,0\n1,abc\n2,2\n",
    "nan": "displacement_mm,voltage_v\n0,0\n1,nan\n2,2\n",
    "inf": "displacement_mm,voltage_v\n0,0\n1,inf\n2,2\n",
    "too_few": "displacement_mm,voltage_v\n0,0\n1,1\n",
    "duplicate": "displacement_mm,voltage_v\n0,0\n1,1\n1,1.5\n2,2\n",
}


def assert_one_line_error(rc, out, err, fragment):
    assert rc == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and fragment in lines[0]
    assert "Traceback" not in err


def test_train_keeps_the_part_before_a_fold_back(tmp_path, capsys):
    """An output that turns back 5 mm before the end: trained on the part before, said in one line."""
    data = tmp_path / "fold.csv"
    data.write_text("displacement_mm,voltage_v\n" + "".join(
        f"{x},{v!r}\n" for x, v in zip(range(-10, 11), [*range(-10, 6), 4, 3, 2, 1, 0])))
    rc, _, err = run(["train", data, "-o", tmp_path / "m.json"], capsys)
    assert rc == 0 and "output turns back at +5 mm: trained on -10..5 mm" in err
    assert "verdict: GOOD" in err


@pytest.mark.parametrize("case, fragment", [
    ("missing_column", "missing column"), ("non_numeric", "not a number"),
    ("nan", "not finite"), ("inf", "not finite"), ("too_few", "need at least 3"),
    ("duplicate", "appears twice"),
])
def test_train_bad_recordings(tmp_path, capsys, case, fragment):
    data = tmp_path / "bad.csv"
    data.write_text(BAD_CSV[case])
    out = tmp_path / "m.json"
    rc, o, err = run(["train", data, "--terms", 3, "-o", out], capsys)
    assert_one_line_error(rc, o, err, fragment)
    assert not out.exists()


def test_train_auto_on_three_points_names_the_file_and_the_way_out(tmp_path, capsys):
    data = tmp_path / "three.csv"
    data.write_text("displacement_mm,voltage_v\n-1,-0.2\n0,0\n1,0.21\n")
    out = tmp_path / "m.json"
    assert_one_line_error(*run(["train", data, "-o", out], capsys), "three.csv: 3 distinct positions")
    data.write_text("displacement_mm,voltage_v,direction\n-1,-0.2,1\n0,0,1\n1,0.21,1\n"
                    "1,0.22,-1\n0,0.01,-1\n-1,-0.19,-1\n")            # two sweeps: still 3 positions
    assert_one_line_error(*run(["train", data, "-o", out], capsys), "three.csv: 3 distinct positions")
    data.write_text("displacement_mm,voltage_v\n-1,-0.2\n0,0\n1,0.21\n")
    assert not out.exists()
    rc, _, err = run(["train", data, "-o", out, "--terms", 2], capsys)
    assert rc == 0 and out.exists(), err


def test_train_missing_file(tmp_path, capsys):
    out = tmp_path / "m.json"
    assert_one_line_error(*run(["train", tmp_path / "nope.csv", "-o", out], capsys),
                          "no such file")
    assert not out.exists()


@pytest.mark.parametrize("content, fragment", [
    ("{not json", "not valid JSON"),
    ('{"format": "other/1"}', "expected 'flann-model/1'"),
    ('{"format": "flann-model/1", "terms": 1}', "missing field"),
])
def test_bad_model_file(tmp_path, capsys, content, fragment):
    model = tmp_path / "m.json"
    model.write_text(content)
    data = write_csv(tmp_path / "r.csv", [0.0, 1.0, 2.0], [0.0, 1.0, 2.0])
    out = tmp_path / "p.csv"
    assert_one_line_error(*run(["predict", model, data, "-o", out], capsys), fragment)
    assert not out.exists()
    assert_one_line_error(*run(["eval", model, data], capsys), fragment)


def test_missing_model_file(tmp_path, capsys):
    data = write_csv(tmp_path / "r.csv", [0.0, 1.0, 2.0], [0.0, 1.0, 2.0])
    assert_one_line_error(*run(["eval", tmp_path / "none.json", data], capsys), "no such file")


def test_bad_options(tmp_path, capsys):
    out = tmp_path / "m.json"
    assert_one_line_error(*run(["train", TABLE1, "--terms", 5, "--method", "lms", "--eta",
                                "-1", "-o", out], capsys), "--eta")
    assert_one_line_error(*run(["train", TABLE1, "--method", "lms", "-o", out], capsys),
                          "--terms auto")
    assert not out.exists()
    assert_one_line_error(*run(["paper", "--epochs", 0], capsys), "--epochs")
