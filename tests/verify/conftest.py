"""Fixtures of the verification tests."""

from __future__ import annotations

from pathlib import Path

import pytest

from flann.cli import main

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def small_model(tmp_path):
    """model.json of a FLANN with ``terms`` terms trained on the seed's Table 1 (flann train)."""

    def make(terms: int = 11, name: str = "m.json") -> Path:
        out = tmp_path / name
        assert main(["train", str(REPO / "data" / "paper_table1.csv"), "--terms", str(terms),
                     "--method", "lstsq", "-o", str(out)]) == 0
        return out

    return make
