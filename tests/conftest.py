"""Shared fixtures: the repository's data files, located once."""

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
DATA = REPO / "data"


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO


@pytest.fixture(scope="session")
def data_dir() -> Path:
    return DATA


@pytest.fixture(scope="session")
def table1_csv() -> Path:
    return DATA / "paper_table1.csv"


@pytest.fixture(scope="session")
def default_model_json() -> Path:
    return DATA / "default_model.json"
