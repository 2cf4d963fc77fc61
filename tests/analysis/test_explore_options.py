"""flann explore's list options are checked where they are parsed: a bad lane count,
multiplier style or width preset stops the command with one line and exit code 2 before any
design is built (not a table of empty rows with the reason in their notes)."""

import dataclasses
from pathlib import Path

import pytest

from flann.cli import main
from flann.analysis import explore
from flann.analysis.plugin import insight
from flann.commands import explore as explore_command

MODEL = Path(__file__).resolve().parents[2] / "data" / "default_model.json"


@pytest.fixture
def explored(monkeypatch):
    """The explorers replaced by a record of what they were asked (nothing built)."""
    calls = []

    def record(model, device, **kw):
        calls.append(dict(kw, device=device))
        return []
    monkeypatch.setattr(explore_command, "insight", lambda dp: dataclasses.replace(insight(dp), explore=record))
    return calls


@pytest.mark.parametrize("flag, value, said", [
    ("--widths", "foo", "'foo'"),
    ("--widths", "budget,foo", "'foo'"),
    ("--mult", "foo", "'foo'"),
    ("--mult", "lut,", "''"),
    ("--lanes", "0", "0"),
    ("--lanes", "1,-2", "-2"),
    ("--lanes", "1,,2", "''"),
    ("--lanes", "x", "'x'"),
    ("--lanes", "1000", "1000"),   # more lanes than any model's 60 sin/cos terms
])
def test_bad_value_stops_before_any_work(capsys, explored, flag, value, said):
    with pytest.raises(SystemExit) as exc:   # argparse's exit, or the old code's return code
        raise SystemExit(main(["explore", str(MODEL), flag, value, "--no-seed", "--input-bits", "8"]))
    out, err = capsys.readouterr()
    assert exc.value.code == 2
    assert out == ""
    assert len(err.splitlines()) == 1 and err.startswith(f"error: flann explore: argument {flag}: ")
    assert said in err
    assert explored == []


def test_good_lists_reach_the_explorer_as_values(capsys, explored):
    rc = main(["explore", str(MODEL), "--lanes", "1, 3", "--mult", "lut", "--widths", "narrow",
               "--no-seed", "--input-bits", "8", "--json"])
    assert rc == 0, capsys.readouterr().err
    assert len(explored) == 1
    kw = explored[0]
    assert kw["lanes"] == (1, 3) and kw["styles"] == ("lut",) and kw["widths"] == ("narrow",)


def test_defaults_reach_the_explorer(capsys, explored):
    assert main(["explore", str(MODEL), "--no-seed", "--input-bits", "8", "--json"]) == 0
    kw = explored[0]
    # None: the explorer's own default (a float18 design takes no lanes or styles)
    assert kw["lanes"] is None and kw["styles"] is None
    assert kw["widths"] == ("budget", "narrow")


def test_a_design_directory_is_explored_on_its_own_part(capsys, explored, tmp_path):
    """explore DIR explored the default XC2S200 whatever part the design was generated for,
    where synth and ise take the manifest's."""
    assert main(["gen", str(MODEL), "-o", str(tmp_path / "d"), "--input-bits", "8", "--device", "xc2s50-tq144-5"]) == 0
    assert main(["explore", str(tmp_path / "d"), "--no-seed", "--json"]) == 0, capsys.readouterr().err
    assert main(["explore", str(MODEL), "--no-seed", "--input-bits", "8", "--json"]) == 0
    assert [kw["device"] for kw in explored] == ["xc2s50-tq144-5", "xc2s200-pq208-5"]


def test_library_refuses_a_bad_preset_or_style_before_any_row(monkeypatch):
    monkeypatch.setattr(explore, "_measure", lambda *a: pytest.fail("nothing is synthesised"))
    with pytest.raises(explore.FlannError, match="width preset 'foo'"):
        explore.explore(MODEL, lanes=(1,), styles=("lut",), widths=("foo",), seed=False, progress=False)
    with pytest.raises(explore.FlannError, match="mult_style 'foo'"):
        explore.explore(MODEL, lanes=(1,), styles=("foo",), seed=False, progress=False)
