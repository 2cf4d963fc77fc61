"""Atomic output: a command that fails leaves no half-written file or directory behind.

One writer for every file kind (text, JSON, bytes, a matplotlib figure as PNG, a directory
of files).  Files come out with the permissions the umask gives any new file (usually
0644), not the 0600 of the temporary file they are written through.

Every output goes through :func:`_target`, which decides what may be written where:

* a symlink is followed (its target is written, the link stays a link);
* a FIFO, device, socket or (for a file) directory is refused, never replaced;
* a file the running command has read as input (:func:`note_input`, called by every
  reader, inside :func:`guarding_inputs`) is refused as an output, and so is a directory holding one, so no command overwrites what
  it reads;
* names derived from input files (:func:`safe_name`) are sanitised and confined under their
  output directory (:func:`child`).

Errors of the file system (disk full, permission, a file where a directory is needed) come
out as one :class:`FlannError` line naming the output.
"""

from __future__ import annotations

import contextlib
import glob
import io
import json
import os
import re
import shutil
import stat
import tempfile
import warnings
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


# (st_dev, st_ino) -> resolved path of every file read as input by the running command;
# None outside a command (library use: nothing is guarded)
_INPUTS: dict[tuple[int, int], Path] | None = None


@contextlib.contextmanager
def guarding_inputs():
    """While a command runs (the CLI wraps each in this), the files it reads may not be
    written over by its outputs.  Forked workers inherit the guard."""
    global _INPUTS
    outer, _INPUTS = _INPUTS, {}
    try:
        yield
    finally:
        _INPUTS = outer


def note_input(path: str | os.PathLike) -> None:
    """Remember that ``path`` is an input of the running command: it may not be written over."""
    if _INPUTS is None:
        return
    try:
        st = os.stat(path)
    except OSError:
        return
    _INPUTS[(st.st_dev, st.st_ino)] = Path(os.path.realpath(path))


_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _target(path: str | os.PathLike, directory: bool = False) -> Path:
    """The path to write for output ``path``: a symlink resolved; special files, inputs and
    (for a file) directories refused with one line."""
    shown = Path(path)
    # a symlink is followed: what it points to is judged and written (a dangling one
    # creates its target)
    path = Path(os.path.realpath(shown)) if shown.is_symlink() else shown
    try:
        st = os.stat(shown)
    except FileNotFoundError:
        return path
    except OSError as exc:
        raise _cannot_write(shown, exc) from None
    for test, kind in _KINDS:
        if test(st.st_mode):
            raise FlannError(f"{shown}: is {kind}; flann writes only regular files (give a file name)")
    if stat.S_ISDIR(st.st_mode):
        if not directory:
            raise FlannError(f"{shown}: is a directory, expected a file name")
        real = Path(os.path.realpath(path))
        for src in (_INPUTS or {}).values():
            if real == src or real in src.parents:
                raise FlannError(f"{shown}: holds {src.name}, an input of this command; "
                                 "it would be replaced: choose another output directory")
        return path
    if directory:
        raise FlannError(f"{shown}: exists and is not a directory")
    if (st.st_dev, st.st_ino) in (_INPUTS or {}):
        raise FlannError(f"{shown}: is also an input of this command; writing it would destroy "
                         "the input: choose another output name")
    return path


_UNSAFE = re.compile(r"[^A-Za-z0-9._+\-]")


def safe_name(name: str) -> str:
    """A file/directory name derived from input (a recording's stem), safe to join to an
    output directory: only letters, digits and ``._+-`` (others become ``_``), no leading
    dot (so never ``.``/``..`` or hidden), never empty."""
    out = _UNSAFE.sub("_", name).lstrip(".")
    return out or "_"


def child(directory: str | os.PathLike, name: str) -> Path:
    """``directory/name`` for a name from :func:`safe_name`, refused if it would leave
    ``directory`` (one last guard: a safe name never does)."""
    base = Path(os.path.realpath(directory))
    dest = Path(os.path.realpath(base / name))
    if dest.parent != base:
        raise FlannError(f"{name!r}: not a plain name inside {directory}")
    return Path(directory) / name


def _parent_dir(path: Path) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _cannot_write(path, exc) from None


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    path = _target(path)
    _parent_dir(path)
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


def check_output_directory(path: str | os.PathLike, replaceable=_nobody_else_s, what: str = "directory") -> Path:
    """The directory :func:`atomic_directory` would write for ``path``, or its one-line
    refusal now: a command with a long run before its output checks it first."""
    path = _target(path, directory=True)
    _parent_dir(path)
    if path.exists() and any(path.iterdir()) and not replaceable(path):
        raise FlannError(f"{path}: directory is not empty and is not a {what}; choose a new or empty directory")
    return path


def _swap_prefix(path: Path, kind: str) -> str:
    """The name of a swap's temporary sibling: the process that owns it is in the name, so a
    later run can tell an abandoned one (its process gone) from one being written now."""
    return f".{path.name}.{kind}.{os.getpid()}."


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def recover_swap(path: str | os.PathLike) -> list[str]:
    """Undo what a killed run left of :func:`atomic_directory`'s swap beside ``path``: a process
    killed between its two renames leaves no ``path``, the old directory at
    ``.<name>.old.<pid>.*/d`` and the new one at ``.<name>.new.<pid>.*``.  The old one goes back
    (the last complete output), then every sibling of a process that is gone is removed.
    Returns what was done, one phrase each (said on stderr by the caller's warning)."""
    path = Path(os.path.abspath(path))
    try:
        siblings = list(path.parent.glob(f".{glob.escape(path.name)}.[no][el][wd].*"))
    except OSError:
        return []
    done = []
    for sib in sorted(siblings):
        m = re.fullmatch(rf"\.{re.escape(path.name)}\.(new|old)\.(\d+)\.[^/]+", sib.name)
        if m is None or not sib.is_dir() or sib.is_symlink() or _alive(int(m[2])):
            continue
        if m[1] == "old" and (sib / "d").is_dir() and not os.path.lexists(path):
            os.replace(sib / "d", path)
            done.append(f"restored {path.name} from an interrupted replacement")
        shutil.rmtree(sib, ignore_errors=True)
        done.append(f"removed {sib.name}")
    if done:
        warnings.warn(f"{path}: a run killed while replacing it left its swap behind: {'; '.join(done)}")
    return done


@contextlib.contextmanager
def atomic_directory(path: str | os.PathLike, replaceable=_nobody_else_s, what: str = "directory"):
    """Yield a fresh temporary directory that replaces ``path`` as a whole on success.

    ``path`` may be absent, an empty directory, or a directory ``replaceable(path)`` accepts
    (an earlier output of the same kind); any other existing directory is refused before
    anything is written, so a user's files are never mixed with ours or deleted.  On success
    the old directory is renamed aside, the new one renamed in and the old one removed:
    nothing stale survives and no reader sees a mixture.  On any error ``path`` is untouched
    (a file-system error while the body writes into the temporary directory -- disk full --
    becomes one line naming ``path``).  A symlink to a directory is followed (its target is
    replaced); a directory holding one of the command's inputs is refused.
    """
    shown = Path(path)
    recover_swap(path)
    path = check_output_directory(path, replaceable, what)
    try:
        tmp = Path(tempfile.mkdtemp(prefix=_swap_prefix(path, "new"), dir=path.parent))
    except OSError as exc:
        raise _cannot_write(path, exc) from None
    aside = None
    try:
        try:
            yield tmp
        except OSError as exc:
            raise _cannot_write(shown, exc) from None
        try:
            os.chmod(tmp, 0o777 & ~_umask())
            if path.exists():
                aside = Path(tempfile.mkdtemp(prefix=_swap_prefix(path, "old"), dir=path.parent))
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


def remove_output_directory(path: str | os.PathLike, replaceable) -> None:
    """Remove ``path`` if it is an earlier output ``replaceable`` accepts (a result that is no
    longer true must not survive beside a report that says so); anything else is left."""
    path = Path(path)
    recover_swap(path)
    if path.is_dir() and not path.is_symlink() and replaceable(path):
        try:
            aside = Path(tempfile.mkdtemp(prefix=_swap_prefix(path, "old"), dir=path.parent))
            os.replace(path, aside / "d")
        except OSError as exc:
            raise _cannot_write(path, exc) from None
        shutil.rmtree(aside, ignore_errors=True)


__all__ = ["check_output_directory", "atomic_write_bytes", "atomic_write_text", "atomic_write_json", "atomic_save_figure",
           "atomic_directory", "note_input", "guarding_inputs", "safe_name", "child",
           "remove_output_directory", "recover_swap"]
