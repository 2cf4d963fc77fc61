"""What a non-editable install ships: every file the commands read, and their runtime deps.

A wheel built without these works in the checkout (files found next to the sources) and
fails on a user's machine, so the check reads pyproject.toml as setuptools does.
"""

import re
import sys
from pathlib import Path

import pytest

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "gen" / "flann"


@pytest.fixture(scope="module")
def project() -> dict:
    return tomllib.loads((REPO / "pyproject.toml").read_text())


def _shipped(project) -> set[str]:
    patterns = project["tool"]["setuptools"]["package-data"]["flann"]
    return {p.relative_to(PACKAGE).as_posix()
            for pat in patterns for p in PACKAGE.glob(pat) if p.is_file()}


def _data_files() -> set[str]:
    """Every non-Python file inside the package tree (symlinked folders followed)."""
    out = set()
    for p in PACKAGE.rglob("*"):
        rel = p.relative_to(PACKAGE)
        if "__pycache__" in rel.parts or p.is_dir() or p.suffix in (".py", ".pyc"):
            continue
        out.add(rel.as_posix())
    return out


def test_every_data_file_in_the_package_ships(project):
    missing = _data_files() - _shipped(project)
    assert not missing, f"not in [tool.setuptools.package-data]: {sorted(missing)}"


@pytest.mark.parametrize("needed", [
    "vsg.yaml",                             # flann synth lints with it by default
    "data/sensors/miniature_reversed.toml",  # flann diagnose --demo
    "data/sensors/paper_lvdt.toml",
    "verify/benches/flann_harness.vhd",     # flann sim
    "hardware/templates/macros.j2",         # flann gen
])
def test_files_read_at_run_time_ship(project, needed):
    assert needed in _shipped(project)


@pytest.mark.parametrize("module", ["cocotb", "find_libpython", "vsg"])
def test_user_commands_deps_are_not_dev_only(project, module):
    # flann sim imports cocotb_tools, flann synth runs vsg: both are user commands.
    names = {re.split(r"[=<>;\[ ]", d, maxsplit=1)[0].lower()
             for d in project["project"]["dependencies"]}
    assert module in names
