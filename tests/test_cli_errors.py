"""Wrong flags and values: one line on stderr starting 'error:', exit code 2, nothing written."""

import pytest

from flann.cli import main


@pytest.mark.parametrize("argv, fragment", [
    (["train", "r.csv", "-o", "m.json", "--terms", "abc"], "--terms"),
    (["train", "r.csv"], "-o/--output"),
    (["train", "r.csv", "-o", "m.json", "--method", "newton"], "--method"),
    (["gen", "m.json", "-o", "d", "--input-bits", "twelve"], "--input-bits"),
    (["eval", "m.json"], "recordings"),
    (["--bogus"], "--bogus"),
    (["frobnicate"], "frobnicate"),
    (["paper", "--epochs", "1.5"], "--epochs"),
    (["train", "r.csv", "-o", "m.json", "--terms", "11", "--normalise", "1.2"], "(0, 1]"),
    (["paper", "--normalise", "full"], "(0, 1]"),
])
def test_wrong_flag_or_value_is_one_line(argv, fragment, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error: ") and fragment in lines[0]
    assert list(tmp_path.iterdir()) == []
