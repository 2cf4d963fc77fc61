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


def _nobody_else_s(path: Path) -> bool:
    return False


@contextlib.contextmanager
def atomic_directory(path: str | os.PathLike, replaceable=_nobody_else_s, what: str = "directory"):
    """Yield a fresh temporary directory that replaces ``path`` as a whole on success.

    ``path`` may be absent, an empty directory, or a directory ``replaceable(path)`` accepts
    (an earlier output of the same kind); any other existing directory is refused before
    anything is written, so a user's files are never mixed with ours or deleted.  On success
    the old directory is renamed aside, the new one renamed in and the old one removed:
    nothing stale survives and no reader sees a mixture.  On any error ``path`` is untouched.
    A symlink to a directory is followed (its target is replaced).
    """
    path = Path(path)
    if path.is_symlink():
        path = Path(os.path.realpath(path))
    _parent_dir(path)
    if path.exists():
        if not path.is_dir():
            raise FlannError(f"{path}: exists and is not a directory")
        if any(path.iterdir()) and not replaceable(path):
            raise FlannError(f"{path}: directory is not empty and is not a {what}; "
                             f"choose a new or empty directory")
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.new.", dir=path.parent))
    except OSError as exc:
        raise _cannot_write(path, exc) from None
    aside = None
    try:
        yield tmp
        try:
            os.chmod(tmp, 0o777 & ~_umask())
            if path.exists():
                aside = Path(tempfile.mkdtemp(prefix=f".{path.name}.old.", dir=path.parent))
                os.replace(path, aside / "d")
            try:
                os.replace(tmp, path)
            except OSError:
                if aside is not None:
                    os.replace(aside / "d", path)
                raise
        except OSError as exc:
            raise _cannot_write(path, exc) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        if aside is not None:
            shutil.rmtree(aside, ignore_errors=True)


__all__ = ["atomic_write_bytes", "atomic_write_text", "atomic_write_json", "atomic_save_figure",
           "atomic_directory"]
