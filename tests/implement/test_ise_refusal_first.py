"""flann ise refuses an output directory it may not replace in one line, before any warning
and before the synthesis of its timing check."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from flann.implement import ise

FIX = Path(__file__).parent / "fixtures" / "synth" / "good"


@pytest.fixture
def design(tmp_path) -> Path:
    d = tmp_path / "d"
    shutil.copytree(FIX, d)
    return d


def _never(*_a, **_k):
    raise AssertionError("synthesised before the output directory was checked")


# the XC2S30 in PQ208 draws the pin map's I/O-count warning once the project is written
@pytest.mark.parametrize("timing", [[], ["--no-timing-check"]])
def test_the_design_directory_as_output_is_one_line(design, cli, monkeypatch, timing):
    monkeypatch.setattr(ise, "synthesize", _never)
    rc, out, err = cli(["ise", design, "--device", "xc2s30-pq208-5", "-o", design, *timing])
    assert rc == 2 and out == ""
    assert err.splitlines() == [f"error: {design}: holds manifest.json, an input of this command; it would be "
                                "replaced: choose another output directory"]


def test_a_users_directory_as_output_is_one_line(design, tmp_path, cli, monkeypatch):
    monkeypatch.setattr(ise, "synthesize", _never)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep\n")
    rc, out, err = cli(["ise", design, "--device", "xc2s30-pq208-5", "-o", mine])
    assert rc == 2 and len(err.splitlines()) == 1 and err.startswith(f"error: {mine}: directory is not empty")
    assert (mine / "notes.txt").read_text() == "keep\n"


def test_write_ise_refuses_before_warning(design, recwarn):
    with pytest.raises(ise.FlannError, match="directory is not empty"):
        ise.write_ise(design, "xc2s30-pq208-5", design.parent)
    assert not recwarn.list
