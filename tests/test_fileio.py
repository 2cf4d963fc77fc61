"""The atomic writers leave no temporary file behind and respect the umask (not mkstemp's 0600)."""

import os
import stat

import pytest

from flann.fileio import atomic_save_figure, atomic_write_json, atomic_write_text


@pytest.fixture
def umask_027():
    old = os.umask(0o027)
    yield
    os.umask(old)


def test_files_get_the_umask_permissions(tmp_path, umask_027):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    atomic_write_text(tmp_path / "a.txt", "x\n")
    atomic_write_json(tmp_path / "b.json", {"a": 1})
    fig = plt.figure()
    atomic_save_figure(fig, tmp_path / "c.png")
    plt.close(fig)
    for name in ("a.txt", "b.json", "c.png"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o640, name
    assert (tmp_path / "c.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.json", "c.png"]


def test_failed_write_leaves_nothing(tmp_path):
    class Boom:
        def savefig(self, *a, **k):
            raise RuntimeError("boom")

    with pytest.raises(RuntimeError):
        atomic_save_figure(Boom(), tmp_path / "x.png")
    assert list(tmp_path.iterdir()) == []


# -- outputs the file system refuses: one line through the CLI, nothing written -------------
@pytest.mark.parametrize("argv", [
    ["train", "{table1}", "-o", "{blocker}/m.json"],
    ["gen", "{model}", "-o", "{blocker}/hdl"],
    ["predict", "{model}", "{table1}", "-o", "{blocker}/p.csv"],
    ["train", "{table1}", "-o", "{tmp}"],                       # a directory as the file name
])
def test_unwritable_output_is_one_line(argv, tmp_path, capsys, table1_csv, default_model_json):
    from flann.cli import main

    blocker = tmp_path / "blocker"
    blocker.write_text("a file where a directory is needed\n")
    names = dict(table1=table1_csv, model=default_model_json, blocker=blocker, tmp=tmp_path)
    rc = main([a.format(**names) for a in argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and err[-1].startswith("error: ") and "Traceback" not in "".join(err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blocker"]


def test_permission_refused_on_the_temporary_file(tmp_path, monkeypatch):
    import tempfile

    from flann.errors import FlannError

    def refuse(*a, **k):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    with pytest.raises(FlannError, match="cannot write .permission denied"):
        atomic_write_text(tmp_path / "x.txt", "x\n")


def test_directory_is_replaced_as_a_whole(tmp_path):
    from flann.fileio import atomic_directory
    d = tmp_path / "out"
    with atomic_directory(d, lambda p: True) as tmp:
        (tmp / "a.txt").write_text("1")
        (tmp / "b.txt").write_text("1")
    with atomic_directory(d, lambda p: (p / "a.txt").exists()) as tmp:
        (tmp / "a.txt").write_text("2")
    assert sorted(p.name for p in d.iterdir()) == ["a.txt"]
    assert (d / "a.txt").read_text() == "2"
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_foreign_directory_is_refused_and_untouched(tmp_path):
    from flann.errors import FlannError
    from flann.fileio import atomic_directory
    d = tmp_path / "mine"
    d.mkdir()
    (d / "thesis.tex").write_text("keep")
    with pytest.raises(FlannError, match="not empty"):
        with atomic_directory(d) as tmp:
            (tmp / "x").write_text("x")
    assert [p.name for p in d.iterdir()] == ["thesis.tex"]
    assert [p.name for p in tmp_path.iterdir()] == ["mine"]


def test_failure_inside_leaves_old_directory(tmp_path):
    from flann.fileio import atomic_directory
    d = tmp_path / "out"
    d.mkdir()
    (d / "old").write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_directory(d, lambda p: True) as tmp:
            (tmp / "new").write_text("new")
            raise RuntimeError("boom")
    assert [p.name for p in d.iterdir()] == ["old"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
