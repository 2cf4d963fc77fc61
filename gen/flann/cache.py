"""A content-addressed cache of what the external tools make (a Yosys-mapped netlist, a
Verilator-compiled simulation), so that ``flann synth DIR`` then ``flann ise DIR`` (which
synthesises for its timing check) or ``flann sim --netlist`` run Yosys and the C++ compiler once
per design, not once per command.

An entry is keyed by everything its files depend on: the input files' bytes, the tool versions,
the flow's own source and options (:func:`key`).  A cached result is therefore the result the
tools would give again; an edited file, another tool or another flann is another key.  Only a
finished run is stored (a failure is not), atomically: a run killed while storing leaves nothing.

Where: ``$FLANN_CACHE_DIR``, else ``$XDG_CACHE_HOME/flann``, else ``~/.cache/flann``;
``FLANN_CACHE_DIR=off`` (or empty) turns it off.  A cache that cannot be read or written is
skipped, never an error: the tools run as without it.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import os
import shutil
import tempfile
from pathlib import Path

ENV = "FLANN_CACHE_DIR"


def root() -> Path | None:
    """The cache directory, or None when the cache is off."""
    if ENV in os.environ:
        value = os.environ[ENV].strip()
        return Path(value) if value and value.lower() != "off" else None
    base = os.environ.get("XDG_CACHE_HOME") or (Path.home() / ".cache")
    return Path(base) / "flann"


def key(*parts) -> str:
    """sha256 of ``parts`` in order: bytes, str, Path (its bytes) or numbers."""
    h = hashlib.sha256()
    for p in parts:
        data = Path(p).read_bytes() if isinstance(p, Path) else p if isinstance(p, bytes) else str(p).encode()
        h.update(len(data).to_bytes(8, "little"))
        h.update(data)
    return h.hexdigest()


@contextlib.contextmanager
def entry(kind: str, digest: str, work: Path, names: list[str]):
    """``with entry(kind, digest, work, names) as hit:`` -- ``hit`` True: the files ``names`` were
    copied into ``work`` from the cache; False: make them in ``work`` inside the block, and they
    are stored when it ends without an exception.  Concurrent makers of one entry wait for the
    first (a lock per entry)."""
    base = root()
    work = Path(work)
    work.mkdir(parents=True, exist_ok=True)
    if base is None:
        yield False
        return
    final = base / kind / digest
    try:
        final.parent.mkdir(parents=True, exist_ok=True)
        lock = open(final.parent / f"{digest}.lock", "w")
    except OSError:
        yield False
        return
    with lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if _restore(final, work, names):
            yield True
            return
        yield False
        _store(final, work, names)


def _restore(final: Path, work: Path, names: list[str]) -> bool:
    if not all((final / n).is_file() for n in names):
        return False
    try:
        for n in names:
            (work / n).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(final / n, work / n)
    except OSError:
        return False
    return True


def _store(final: Path, work: Path, names: list[str]) -> None:
    if final.exists() or not all((work / n).is_file() for n in names):
        return
    tmp = None
    try:
        tmp = Path(tempfile.mkdtemp(prefix=".new-", dir=final.parent))
        for n in names:
            (tmp / n).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(work / n, tmp / n)
        os.rename(tmp, final)
    except OSError:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)


__all__ = ["ENV", "root", "key", "entry"]
