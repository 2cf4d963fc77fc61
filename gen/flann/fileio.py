"""Atomic output: a command that fails leaves no half-written file or directory behind.

One writer for every file kind (text, JSON, bytes, a matplotlib figure as PNG, a directory
of files).  Files come out with the permissions the umask gives any new file (usually
0644), not the 0600 of the temporary file they are written through.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import tempfile
from pathlib import Path

from .errors import FlannError


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _cannot_write(path, exc: OSError) -> FlannError:
    """An output the file system refuses is bad input like any other: one line naming it."""
    if isinstance(exc, (FileExistsError, NotADirectoryError)):
        why = "a part of the path is a file, not a directory"
    elif isinstance(exc, PermissionError):
        why = "permission denied"
    else:
        why = exc.strerror or exc.__class__.__name__
    return FlannError(f"{path}: cannot write ({why})")


def _parent_dir(path: Path) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _cannot_write(path, exc) from None


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    path = Path(path)
    _parent_dir(path)
    if path.is_dir():
        raise FlannError(f"{path}: is a directory, expected a file name")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    except OSError as exc:
        raise _cannot_write(path, exc) from None
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(exc, OSError):   # disk full, a quota: still one line
            raise _cannot_write(path, exc) from None
        raise


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    # no newline translation: generated text is byte-identical on every platform
    atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_json(path: str | os.PathLike, obj) -> None:
    atomic_write_text(path, json.dumps(obj, indent=2, sort_keys=False) + "\n")


def atomic_save_figure(fig, path: str | os.PathLike, dpi: int = 110) -> None:
    """A matplotlib figure as PNG (rendered in memory first, so a failure writes nothing)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    atomic_write_bytes(path, buf.getvalue())


@contextlib.contextmanager
def atomic_directory(path: str | os.PathLike):
    """Yield a temporary directory that replaces/merges into ``path`` only on success.

    Files written into the yielded directory are moved into ``path`` (created if needed)
    when the block exits cleanly; on error nothing in ``path`` is touched.
    """
    path = Path(path)
    _parent_dir(path)
    if path.exists() and not path.is_dir():
        raise FlannError(f"{path}: exists and is not a directory")
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    except OSError as exc:
        raise _cannot_write(path, exc) from None
    try:
        yield tmp
        try:
            path.mkdir(parents=True, exist_ok=True)
            for item in sorted(tmp.rglob("*")):
                if item.is_file():
                    dest = path / item.relative_to(tmp)
                    dest.parent.mkdir(parents=True, exist_ok=True)
                    os.replace(item, dest)
        except OSError as exc:
            raise _cannot_write(path, exc) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


__all__ = ["atomic_write_bytes", "atomic_write_text", "atomic_write_json", "atomic_save_figure",
           "atomic_directory"]
