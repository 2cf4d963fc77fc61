"""flann trace: exact attribution, and naming the block that was made worse on purpose."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from flann.cli import main
from flann.hardware.float18.spec import FlannF18Top, derive_f18_spec
from flann.golden.model import load_model, term_kind
from flann.recordings import read_recordings
from flann.hardware.fixed.spec import derive_spec
from flann.analysis.trace import attribute, run_trace
from flann.hardware.fixed.analysis import stages as stages_fixed
from flann.hardware.float18.analysis import stages as stages_float18
from flann.golden.train import fit_lstsq
from flann.hardware.fixed.twin import FlannTop

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = ROOT / "data" / "default_model.json"


@pytest.fixture(scope="module")
def default_model():
    return load_model(DEFAULT)


@pytest.fixture(scope="module")
def paper_model():
    rec = read_recordings(ROOT / "data" / "paper_table1.csv")
    return fit_lstsq(rec.voltage_v, rec.displacement_mm, 51, norm="none")


def test_contributions_add_up_to_twin_minus_golden(default_model):
    spec = derive_spec(default_model)
    codes = np.arange(spec.clamp_lo, spec.clamp_hi + 1, 7)
    want = FlannTop(spec).process(codes)[0] * spec.output_lsb_mm - default_model.predict(codes * spec.input_lsb_v)
    got = sum(s.contrib for s in attribute(stages_fixed(spec, codes)))
    assert np.max(np.abs(got - want)) < 1e-9

    fspec = derive_f18_spec(default_model)
    want = FlannF18Top(fspec).out_mm(codes) - default_model.predict(codes * spec.input_lsb_v)
    got = sum(s.contrib for s in attribute(stages_float18(fspec, codes)))
    assert np.max(np.abs(got - want)) < 1e-9


def test_default_fixed_design_is_limited_by_output_rounding(default_model):
    r = run_trace(default_model, "fixed", check_device=False)
    q = derive_spec(default_model).output_lsb_mm
    assert r.dominant["stage"] == "output"
    # rounding to the output LSB: uniform on +-q/2, rms q/sqrt(12)
    assert abs(r.stages["output"]["rms_mm"] - q / np.sqrt(12)) < 0.1 * q / np.sqrt(12)


def _largest_trig_weights(model, k):
    w = np.abs(np.asarray(model.weights[1:]))
    return {int(i) + 1 for i in np.argsort(-w)[:k]}


@pytest.mark.filterwarnings("ignore:these widths bound")
@pytest.mark.parametrize("fmt", ["fixed", "float18"])
def test_short_sin_table_is_named(default_model, fmt):
    """An 8-word quarter-wave table without interpolation: a midpoint-sampled table is off by
    up to sin's slope x half a bin, (pi/2) / 16 ~ 0.1 for every harmonic alike, so the
    expansion block dominates and the worst term is one with a large weight."""
    r = run_trace(default_model, fmt, table_addr_bits=3, interp=False)
    assert r.dominant["stage"] == "expansion"
    assert r.stages["expansion"]["share"] > 0.9
    assert r.dominant["term"] in _largest_trig_weights(default_model, 4)
    kind, m = term_kind(r.dominant["term"])
    assert kind in ("sin", "cos") and f"harmonic {m}" in r.dominant["reason"]
    assert "8-entry quarter-wave table" in r.dominant["reason"]
    # the error is spread over the whole input range
    assert r.dominant["span"]["share"] > 0.5


@pytest.mark.filterwarnings("ignore:these widths bound")
def test_coarse_products_are_named(default_model):
    # products rounded to one output LSB each: 50 independent roundings, rms sqrt(50/12) LSB,
    # well above the final rounding's sqrt(1/12) LSB
    r = run_trace(default_model, "fixed", product_frac_bits=0, check_device=False)
    assert r.dominant["stage"] == "products"
    q = derive_spec(default_model).output_lsb_mm
    assert 0.5 * np.sqrt(50 / 12) * q < r.stages["products"]["rms_mm"] < 2 * np.sqrt(50 / 12) * q


def test_float18_paper_model_error_grows_at_the_ends(paper_model):
    """Float rounding is relative: the running sum's ulp follows |y|, so the error is small
    near the null (y ~ 0) and largest at the ends of the stroke (|y| -> 30 mm)."""
    r = run_trace(paper_model, "float18")
    assert r.dominant["stage"] == "adder"
    v, e = r.volts, r.curves["total"]
    span = v.max() - v.min()
    mid = np.abs(v - 0.5 * (v.max() + v.min())) < 0.125 * span
    ends = (v < v.min() + 0.125 * span) | (v > v.max() - 0.125 * span)
    rms = lambda x: np.sqrt(np.mean(x ** 2))  # noqa: E731
    assert rms(e[ends]) > 3 * rms(e[mid])
    lo, hi = r.dominant["span"]["lo_v"], r.dominant["span"]["hi_v"]
    assert lo < v.min() + 0.2 * span and hi > v.max() - 0.2 * span


def test_cli_json_plot_and_errors(tmp_path, capsys):
    png = tmp_path / "t.png"
    assert main(["trace", str(DEFAULT), "--format", "fixed", "--table-addr-bits", "3", "--no-interp",
                 "--json", "--plot", str(png)]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["dominant"]["stage"] == "expansion" and d["format"] == "fixed"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["trace", str(DEFAULT), "--format", "float18", "--lanes", "3"]) == 2
    assert "lanes" in capsys.readouterr().err
    assert main(["trace", str(tmp_path / "missing.json")]) == 2


def test_cli_compare_at_table_points(tmp_path, capsys):
    png = tmp_path / "fig6b.png"
    table = ROOT / "data" / "paper_table1.csv"
    assert main(["trace", str(DEFAULT), "--format", "float18", "--compare", "--at", str(table),
                 "--json", "--plot", str(png)]) == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d["trace"]) == {"float18", "fixed"} and set(d["at"]) == {"float18", "fixed"}
    rec = read_recordings(table)
    model = load_model(DEFAULT)
    for fmt, rows in d["at"].items():
        assert len(rows) == len(rec.voltage_v)
        for row in rows:
            # golden at the clamped nearest code, recomputed here from the model file
            v = row["code"] * derive_spec(model).input_lsb_v
            assert abs(row["golden_mm"] - float(model.predict([v])[0])) < 1e-9
            assert abs(row["error_mm"] - (row["hardware_mm"] - row["golden_mm"])) < 1e-12
    # float18 (12-bit significand) is coarser than the fixed design sized for 1 output LSB
    assert d["trace"]["float18"]["total"]["rms_mm"] > d["trace"]["fixed"]["total"]["rms_mm"]
    assert png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.sim
def test_cli_hdl_outputs_compared(capsys):
    """--hdl simulates the float18 top over every code of an 8-bit input and compares the
    HDL's own outputs: equal to the twin, so HDL - golden is the twin's error."""
    assert main(["trace", str(DEFAULT), "--format", "float18", "--input-bits", "8", "--hdl", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["hdl"]["codes"] == 256 and d["hdl"]["mismatches"] == 0
    assert abs(d["hdl"]["max_err_mm"] - d["total"]["max_mm"]) < 1e-12
    # the internal stages captured by cocotb equal the twin's, stage by stage
    st = d["hdl"]["stages"]
    assert st["codes"] == 64 and st["all_equal"] and st["missing"] == 0
