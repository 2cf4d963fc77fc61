"""Splitting an exhaustive run over the cores, and watching its progress (shared by the RTL sweep
and the netlist simulation)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np


def cores() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


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
