"""VSG style check with the repository's vsg.yaml (flann.implement.synth.lint_vhdl)."""

import shutil
from pathlib import Path

import pytest

from flann.errors import FlannError
from flann.implement.synth import check_lint, find_vsg_config, lint_vhdl

ROOT = Path(__file__).resolve().parents[2]
FIX = ROOT / "tests" / "implement" / "fixtures" / "synth"

needs_vsg = pytest.mark.skipif(shutil.which("vsg") is None and not (ROOT / ".venv/bin/vsg").exists(),
                               reason="vsg (dev extra) not installed")

BAD = """\
LIBRARY ieee;
use ieee.std_logic_1164.all;

entity t is
  port (a : in std_logic; q : out std_logic);
end t;

architecture rtl of t is
begin
  process (a)
  begin
    Q <= a;
  end process;
end;
"""


def test_config_is_the_checked_in_one():
    assert find_vsg_config(FIX) == ROOT / "vsg.yaml"


@needs_vsg
def test_fixtures_pass():
    files = sorted(FIX.glob("*/*.vhd"))
    assert len(files) == 4
    assert lint_vhdl(files, ROOT / "vsg.yaml") == []


@needs_vsg
def test_bad_style_is_reported_with_rule_names(tmp_path):
    f = tmp_path / "bad.vhd"
    f.write_text(BAD)
    v = lint_vhdl([f], ROOT / "vsg.yaml")
    rules = {x.split()[1] for x in v}
    assert "library_007" in rules or any(r.startswith("library_") for r in rules)  # upper-case LIBRARY
    assert any(r.startswith("process_") for r in rules)  # unlabelled process
    with pytest.raises(FlannError, match="VSG style check failed"):
        check_lint([f], ROOT / "vsg.yaml")


def test_missing_config_is_an_error(tmp_path):
    with pytest.raises(FlannError, match="not found"):
        lint_vhdl([tmp_path / "x.vhd"], tmp_path / "none.yaml")
