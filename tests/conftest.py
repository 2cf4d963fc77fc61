"""Shared fixtures: the repository's data files, located once."""

from pathlib import Path

import pytest

from flann.cli import main

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


@pytest.fixture
def cli(capsys):
    """flann in process: ``cli(argv)`` -> (exit code, stdout, stderr); a flag its argparse type
    refuses exits 2 through SystemExit, as on the command line."""
    def run(argv):
        try:
            rc = main([str(a) for a in argv])
        except SystemExit as exc:
            rc = exc.code
        out, err = capsys.readouterr()
        return rc, out, err
    return run
