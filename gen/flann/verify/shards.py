"""Splitting an exhaustive run over the cores, and watching its progress (shared by the RTL sweep
and the netlist simulation)."""

from __future__ import annotations

import os
import signal
import sys
import time
from pathlib import Path

import numpy as np


def cores() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


GRACE_S = 2.0   # a simulator told to stop has this long before it is killed


def _children(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (Linux /proc; none elsewhere)."""
    kids = []
    for entry in Path("/proc").glob("[0-9]*"):
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        # the command name in parentheses may hold spaces: the fields follow its last ')'
        if int(stat[stat.rfind(")") + 2:].split()[1]) == pid:
            kids.append(int(entry.name))
    return kids


def end_children() -> None:
    """End every process this one started (the simulators of an interrupted run) and theirs:
    SIGTERM, then SIGKILL after :data:`GRACE_S`.  A shard left running would write into a build
    directory flann deletes as it exits."""
    todo = [pid for pid in _children(os.getpid())]
    for pid in list(todo):
        todo += _children(pid)
    for sig in (signal.SIGTERM, signal.SIGKILL):
        alive = []
        for pid in todo:
            try:
                os.kill(pid, sig)
                alive.append(pid)
            except (ProcessLookupError, PermissionError):
                pass
        if not alive or sig == signal.SIGKILL:
            return
        end = time.monotonic() + GRACE_S
        while time.monotonic() < end and any(Path(f"/proc/{pid}").exists() and not _zombie(pid) for pid in alive):
            time.sleep(0.05)
        todo = [pid for pid in alive if Path(f"/proc/{pid}").exists() and not _zombie(pid)]


def _zombie(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return True
    return stat[stat.rfind(")") + 2] == "Z"


def split(lo: int, hi: int, n: int) -> list[tuple[int, int]]:
    """lo..hi (inclusive) in ``n`` contiguous, nearly equal ranges."""
    edges = np.linspace(lo, hi + 1, n + 1).round().astype(int)
    return [(int(a), int(b) - 1) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def count_lines(path: Path) -> int:
    """Samples a shard has written so far (0 before the file exists)."""
    try:
        with open(path, "rb") as fh:
            return sum(chunk.count(b"\n") for chunk in iter(lambda: fh.read(1 << 16), b""))
    except OSError:
        return 0


def read_results(path, temps: bool = False) -> dict:
    """A shard's lines "code data sat latency" as arrays (VHDL harness and netlist driver alike);
    with ``temps``, a fifth column: the temperature code (``temps``)."""
    cols = 5 if temps else 4
    rows = np.loadtxt(path, dtype=np.int64, ndmin=2) if Path(path).is_file() else np.zeros((0, cols), np.int64)
    if rows.size == 0:
        rows = np.zeros((0, cols), dtype=np.int64)
    got = {"codes": rows[:, 0], "data": rows[:, 1], "sat": rows[:, 2].astype(bool), "latency": rows[:, 3]}
    if temps:
        got["temps"] = rows[:, 4]
    return got


def merge(parts: list[dict]) -> dict:
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


def terminal_progress(label: str):
    """A progress callback (done, total, elapsed_s) writing one updating line on a terminal's
    stderr; None when stderr is not a terminal."""
    if not sys.stderr.isatty():
        return None

    def show(done: int, total: int, elapsed: float) -> None:
        rate = done / elapsed if elapsed > 0 else 0.0
        left = f"{(total - done) / rate:.0f} s left" if rate > 0 else "starting"
        end = "\n" if done >= total else ""
        print(f"\r{label}: {done}/{total} codes, {rate:.0f} codes/s, {left}   ", end=end, file=sys.stderr,
              flush=True)

    return show
