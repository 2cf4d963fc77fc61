"""Shared world for the hostile-input suite: small designs and recordings built once."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from flann.cli import main
from flann.production.demo import write_batch

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def world_src(tmp_path_factory) -> Path:
    """rec.csv (the paper's table), m.json, sensor.toml, s0.csv/s1.csv (simulated, 600
    points), design/ (a plain design of m.json) and fam/ (a family design of s0, s1)."""
    w = tmp_path_factory.mktemp("world")
    shutil.copy(REPO / "data" / "paper_table1.csv", w / "rec.csv")
    shutil.copy(REPO / "data" / "default_model.json", w / "m.json")
    shutil.copy(REPO / "data" / "sensors" / "paper_lvdt.toml", w / "sensor.toml")
    sims = write_batch(w / "sims", 2, seed=7, points=600)
    for i, p in enumerate(sims):
        shutil.copy(p, w / f"s{i}.csv")
    shutil.rmtree(w / "sims")
    assert main(["gen", str(w / "m.json"), "-o", str(w / "design"), "--input-bits", "10"]) == 0
    assert main(["gen", "--family", str(w / "s0.csv"), str(w / "s1.csv"), "-o", str(w / "fam"),
                 "--input-bits", "10"]) == 0
    return w


@pytest.fixture
def world(world_src, tmp_path, monkeypatch) -> Path:
    """A private copy of the world as the working directory."""
    w = tmp_path / "w"
    shutil.copytree(world_src, w, symlinks=True)
    monkeypatch.chdir(w)
    return w
