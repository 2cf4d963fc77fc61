"""The atomic writers leave no temporary file behind and respect the umask (not mkstemp's 0600)."""

import json
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


# -- the output policy --------------------------------------------------------------------
@pytest.mark.parametrize("name, safe", [("..", "_"), (".", "_"), ("...", "_"), ("", "_"), (".hidden", "hidden"),
                                        ("a/../b", "a_.._b"), ("a\nb", "a_b"), ("x\x00y", "x_y"),
                                        ("sensor-01.v2+A", "sensor-01.v2+A")])
def test_safe_name_never_leaves_its_directory(name, safe, tmp_path):
    from flann.fileio import child, safe_name

    assert safe_name(name) == safe
    assert child(tmp_path, safe_name(name)).parent == tmp_path


def test_output_that_is_an_input_is_refused_and_left_alone(tmp_path):
    from flann.errors import FlannError
    from flann.fileio import guarding_inputs, note_input

    src = tmp_path / "rec.csv"
    src.write_text("keep me\n")
    hard = tmp_path / "hard.csv"
    os.link(src, hard)           # the same file under another name is the same input
    with guarding_inputs():
        note_input(src)
        for out in (src, hard):
            with pytest.raises(FlannError, match="also an input"):
                atomic_write_text(out, "x\n")
    assert src.read_text() == "keep me\n"
    atomic_write_text(src, "library use, outside a command: not guarded\n")


def test_a_symlinked_output_writes_its_target(tmp_path):
    (tmp_path / "t.json").write_text("old\n")
    os.symlink("t.json", tmp_path / "l.json")
    atomic_write_json(tmp_path / "l.json", {"a": 1})
    assert (tmp_path / "l.json").is_symlink() and json.loads((tmp_path / "t.json").read_text()) == {"a": 1}


def test_remove_output_directory_only_removes_our_own(tmp_path):
    from flann.fileio import remove_output_directory

    ours, theirs = tmp_path / "ours", tmp_path / "theirs"
    for d in (ours, theirs):
        d.mkdir()
    (ours / "certificate.html").write_text("x")
    (theirs / "notes.txt").write_text("x")
    mine = lambda d: (d / "certificate.html").is_file()   # noqa: E731
    remove_output_directory(ours, mine)
    remove_output_directory(theirs, mine)
    assert not ours.exists() and (theirs / "notes.txt").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["theirs"]


# -- the input layer ------------------------------------------------------------------------
@pytest.mark.parametrize("text, why", [
    ("[" * 40 + "]" * 40, "nested deeper"), ("[" * 100000 + "]" * 100000, "nested deeper"),
    ('{"a": ' + "1" * 20 + "}", "digits"), ('{"a": 1e999}', "not finite"), ('{"a": NaN}', "not a number"),
    ('{"a": -Infinity}', "not a number"),
])
def test_json_bounds(text, why):
    from flann.errors import ModelFileError
    from flann.inputs import parse_json

    with pytest.raises(ModelFileError, match=why):
        parse_json(text, "f.json", ModelFileError)
    assert parse_json('{"a": [1, 2.5, -9223372036854775808]}', "f.json", ModelFileError)["a"][2] == -2 ** 63


@pytest.mark.parametrize("text, why", [
    ("a = " + "[" * 40 + "]" * 40, "nested deeper"), ("a = " + "[" * 3000 + "]" * 3000, "nested deeper"),
    ("a = " + "7" * 5000, "too large"), ("a = 99999999999999999999", "beyond 64 bits"), ("a = inf", "not finite"),
])
def test_toml_bounds(text, why):
    from flann.errors import SensorError
    from flann.inputs import parse_toml

    with pytest.raises(SensorError, match=why):
        parse_toml(text, "f.toml", SensorError)
