"""flann train --terms auto says what it is doing on a terminal, and nothing extra in a log."""

import sys

import pytest

from flann.cli import main


@pytest.mark.parametrize("terminal", [True, False])
def test_auto_stages_on_a_terminal_only(table1_csv, tmp_path, capsys, monkeypatch, terminal):
    monkeypatch.setattr(sys.stderr, "isatty", lambda: terminal)
    assert main(["train", str(table1_csv), "-o", str(tmp_path / "m.json")]) == 0
    stages = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("train: ")]
    if terminal:
        assert len(stages) == 3, stages
        assert "13 readings at 13 positions" in stages[0]
        assert "cross-validation" in stages[1] and "forward curve" in stages[2]
    else:
        assert stages == []
