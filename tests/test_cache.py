"""flann's cache of tool outputs: a finished run is stored and given back, a failed one is not,
another input is another entry, and the cache can be turned off."""

from __future__ import annotations

from pathlib import Path

import pytest

from flann import cache


@pytest.fixture
def store(tmp_path, monkeypatch) -> Path:
    monkeypatch.setenv(cache.ENV, str(tmp_path / "cache"))
    return tmp_path / "cache"


def make(work: Path, text: str, digest: str) -> bool:
    with cache.entry("k", digest, work, ["out.txt"]) as hit:
        if not hit:
            (work / "out.txt").write_text(text)
    return hit


def test_a_finished_run_is_given_back_into_another_work_directory(store, tmp_path):
    d = cache.key("a", b"b", 3)
    assert make(tmp_path / "w1", "first", d) is False
    assert make(tmp_path / "w2", "second", d) is True
    assert (tmp_path / "w2" / "out.txt").read_text() == "first"
    assert make(tmp_path / "w3", "third", cache.key("a", b"b", 4)) is False   # another key


def test_a_failed_run_is_not_stored(store, tmp_path):
    d = cache.key("x")
    with pytest.raises(RuntimeError):
        with cache.entry("k", d, tmp_path / "w1", ["out.txt"]) as hit:
            assert not hit
            (tmp_path / "w1" / "out.txt").write_text("half")
            raise RuntimeError("the tool failed")
    assert make(tmp_path / "w2", "whole", d) is False
    assert (tmp_path / "w2" / "out.txt").read_text() == "whole"


def test_a_file_key_is_its_bytes(store, tmp_path):
    f = tmp_path / "f.vhd"
    f.write_text("entity a is end;")
    k1 = cache.key(f)
    f.write_text("entity b is end;")
    assert cache.key(f) != k1 and cache.key(Path(f)) == cache.key(f.read_bytes())


@pytest.mark.parametrize("value", ["off", ""])
def test_the_cache_can_be_turned_off(monkeypatch, tmp_path, value):
    monkeypatch.setenv(cache.ENV, value)
    assert cache.root() is None
    d = cache.key("y")
    assert make(tmp_path / "w1", "one", d) is False and make(tmp_path / "w2", "two", d) is False


def test_an_unwritable_cache_is_skipped(monkeypatch, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    monkeypatch.setenv(cache.ENV, str(blocker / "cache"))
    assert make(tmp_path / "w", "one", cache.key("z")) is False
    assert (tmp_path / "w" / "out.txt").read_text() == "one"
