"""flann explore on a model with very few terms: the rows that cannot apply (a narrower
width preset when the terms are already at the narrowest, the seed's first-5/9/17-term
slices of a model with fewer terms, the seed's tables for a straight line) are skipped with
a note saying why instead of failing in an internal width check or in GHDL."""

from pathlib import Path

import numpy as np
import pytest

from flann.cli import main
from flann.analysis import explore


@pytest.fixture
def models(tmp_path, capsys):
    # three collinear points: a straight line, fitted with 1 and with 2 terms
    data = tmp_path / "three.csv"
    data.write_text("displacement_mm,voltage_v\n0,0\n1,0.1\n2,0.2\n")
    out = {}
    for t in (1, 2):
        out[t] = tmp_path / f"o{t}.json"
        assert main(["train", str(data), "-o", str(out[t]), "--terms", str(t)]) == 0
    capsys.readouterr()
    return out


@pytest.fixture
def measured(monkeypatch):
    """Synthesis replaced by a record of what was synthesised (no GHDL/Yosys needed)."""
    seen = []

    def fake(row, design_dir, device, work, abc):
        seen.append(Path(design_dir).name)
        row.luts, row.ffs, row.brams, row.fits, row.smallest_device = 100, 10, 0, True, "xc2s15"
    monkeypatch.setattr(explore, "_measure", fake)
    return seen


@pytest.mark.parametrize("terms", [1, 2])
def test_narrow_preset_is_skipped_with_the_reason(models, measured, terms):
    rows = explore.explore(models[terms], lanes=(1,), styles=("lut",), widths=("narrow",),
                           seed=False, progress=False)
    assert len(rows) == 1
    note = rows[0].note
    assert note.startswith("skipped: nothing to narrow") and f"{terms}-term model" in note
    assert "product_frac_bits" not in note and "\n" not in note
    assert measured == []                      # nothing generated or synthesised for it


def test_seed_of_a_straight_line_is_not_synthesised(models, measured):
    rows = explore.seed_rows(models[1], "xc2s200-pq208-5", progress=False)
    assert [r.design for r in rows] == ["seed (paper), 1 terms"]
    assert rows[0].note.startswith("skipped synthesis: a 1-term model is a straight line")
    assert rows[0].max_err_mm is not None     # its twin's accuracy is still given
    assert measured == []


def test_seed_of_two_terms_is_synthesised_once_whole(models, measured):
    rows = explore.seed_rows(models[2], "xc2s200-pq208-5", progress=False)
    assert [r.design for r in rows] == ["seed (paper), 2 terms"]
    assert measured == ["seed"]
    assert rows[0].luts == 100 and "synthesised whole" in rows[0].note
    assert not rows[0].note.startswith("extrapolated")


def test_a_long_model_still_extrapolates_from_the_slices(tmp_path, monkeypatch):
    # 21 positions of an S curve, 19 terms: more than the 17-term slice
    x = np.linspace(-10, 10, 41)
    data = tmp_path / "s.csv"
    data.write_text("displacement_mm,voltage_v\n" + "".join(
        f"{float(a)!r},{float(np.tanh(a / 8))!r}\n" for a in x))
    model = tmp_path / "m.json"
    assert main(["train", str(data), "-o", str(model), "--terms", "19", "--ridge", "1e-6"]) == 0
    seen = []

    def fake(row, design_dir, device, work, abc):   # 10 LUT4 a term: 190 at 19 terms
        n = int(Path(design_dir).name[len("seed"):])
        seen.append(n)
        row.luts, row.ffs, row.brams, row.fits, row.smallest_device = 10 * n, n, 0, True, "xc2s15"
    monkeypatch.setattr(explore, "_measure", fake)
    rows = explore.seed_rows(model, "xc2s200-pq208-5", progress=False)
    assert seen == [5, 9, 17]
    assert rows[-1].design == "seed (paper), 19 terms" and rows[-1].luts == 190
    assert rows[-1].note.startswith("extrapolated")


@pytest.mark.parametrize("terms", [1, 2])
def test_more_lanes_than_sin_cos_terms_are_skipped(models, measured, terms):
    rows = explore.explore(models[terms], lanes=(1, 2, 4), styles=("lut",), widths=("budget",),
                           seed=False, progress=False)
    assert [r.lanes for r in rows] == [1, 2, 4]
    assert rows[0].note == "" and rows[0].luts == 100          # one lane: generated and measured
    for r, lanes in zip(rows[1:], (2, 4)):
        # a 1-term line is given one zero-weight sin/cos term; 2 terms have one of their own
        assert r.note.startswith(f"skipped: {lanes} lanes: this {terms}-term model has 1 sin/cos term")
        assert "must be an integer" not in r.note
        assert r.luts is None
    assert len(measured) == 1
