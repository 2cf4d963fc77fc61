#!/usr/bin/env python3
"""A logger's file: `flann train` on a million-row recordings CSV, wall time and peak memory.

    .venv/bin/python bench/bench_train_large.py [--rows 1000000] [--out build/bench_large]

Writes a closed-form S-curve sensor (3 tanh(x / 15) V over +-25 mm, 0.1 mV noise, with
time_s) as CSV, runs `flann train` on it in a child process and prints the wall time, the
child's peak resident memory and the held-out error auto reports.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--out", default="build/bench_large")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(1)
    x = np.linspace(-25.0, 25.0, a.rows)
    v = 3.0 * np.tanh(x / 15.0) + rng.normal(0.0, 1e-4, a.rows)
    csv = out / "large.csv"
    np.savetxt(csv, np.c_[np.arange(a.rows) * 1e-3, x, v], delimiter=",", fmt="%.9g",
               header="time_s,displacement_mm,voltage_v", comments="")
    flann = Path(sys.executable).with_name("flann")
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    t0 = time.perf_counter()
    p = subprocess.run([str(flann), "train", str(csv), "-o", str(out / "model.json")],
                       capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(p.stderr.strip())
    print(f"{a.rows} rows ({csv.stat().st_size / 1e6:.1f} MB): flann train exit {p.returncode}, "
          f"{wall:.1f} s wall, peak {peak_mb:.0f} MB")
    return p.returncode


if __name__ == "__main__":
    sys.exit(main())
