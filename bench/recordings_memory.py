"""Peak memory of `flann train` on long recordings, and the refusal beyond MAX_ROWS.

    python bench/recordings_memory.py [ROWS ...]     (default: 2000000 10000000)

Writes a synthetic sweep of ROWS rows to a temporary file, runs `flann train REC -o M
--terms 11` in a child process and prints its exit code, wall time and peak RSS (the
child's ru_maxrss).  The figures in README ("Resource bounds") come from this script.
"""

from __future__ import annotations

import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def write_sweep(path: Path, rows: int) -> None:
    x = np.linspace(-20.0, 20.0, rows)
    v = 0.25 * x - 1e-4 * x ** 3
    with open(path, "w") as fh:
        fh.write("displacement_mm,voltage_v\n")
        step = 1_000_000
        for i in range(0, rows, step):
            block = np.column_stack((x[i:i + step], v[i:i + step]))
            np.savetxt(fh, block, fmt="%.6f", delimiter=",")


def main(argv: list[str]) -> int:
    sizes = [int(a) for a in argv] or [2_000_000, 10_000_000]
    with tempfile.TemporaryDirectory() as tmp:
        for rows in sizes:
            rec = Path(tmp) / f"r{rows}.csv"
            write_sweep(rec, rows)
            before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
            t0 = time.monotonic()
            proc = subprocess.run([sys.executable, "-m", "flann.cli", "train", str(rec), "-o",
                                   str(Path(tmp) / "m.json"), "--terms", "11"],
                                  capture_output=True, text=True)
            wall = time.monotonic() - t0
            peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
            last = (proc.stderr.strip().splitlines() or [""])[-1]
            print(f"{rows:>10,} rows  {rec.stat().st_size / 1e6:7.1f} MB  exit {proc.returncode}  "
                  f"{wall:6.1f} s  peak RSS {max(peak, before) / 1024:7.0f} MB  {last[:100]}")
            rec.unlink()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
