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


@pytest.mark.parametrize("argv", [
    ["eval", "m.json", "r.csv", "--design", "d", "--plot", "out.txt"],
    ["diagnose", "r.csv", "--plot", "out.txt"],
    ["trace", "m.json", "--plot", "out.txt"],
    ["simulate", "s.toml", "-o", "r.csv", "--plot", "out.txt"],
    ["sim", "m.json", "--plot", "out.txt"],
], ids=lambda a: a[0])
def test_every_plot_is_named_png(argv, cli, tmp_path, monkeypatch):
    """A figure is PNG whichever command draws it: a name that says otherwise is refused before
    any work, so no PNG data lands in a .txt file."""
    monkeypatch.chdir(tmp_path)
    rc, _out, err = cli(argv)
    assert rc == 2 and err.strip().splitlines() == [err.strip()]
    assert err.startswith("error: ") and "out.txt" in err and "*.png" in err
    assert list(tmp_path.iterdir()) == []
