#!/usr/bin/env python3
"""Production line figure: a batch of simulated sensors of varied geometry plus 3 bad files.

    .venv/bin/python bench/bench_calibrate.py [--n 200] [-j 2] [--points 2000] [--out build/production]

Simulates N sensors (flann.production.demo: the paper's LVDT, geometry +-5 %), sizes one
family design from the first three (`flann gen --family`), then times
`flann calibrate` over the N recordings + 3 bad ones and prints sensors per minute (wall
clock, with the machine's load average beside it), the CPU seconds per sensor (all workers)
and what that makes on two otherwise idle cores, the rows that failed and whether every good
sensor got its certificate.  Add --sensor to give the diagnosis the nominal geometry (faster).  Exit 0 when the batch behaved as a line needs:
N certificates, 3 failed rows, a non-zero exit of calibrate, nothing half-written.
"""

from __future__ import annotations

import argparse
import csv
import os
import resource
import shutil
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from flann.cli import main as flann  # noqa: E402
from flann.production.demo import bad_files, write_batch  # noqa: E402


def _cpu_s() -> float:
    """User + system CPU seconds of this process and its reaped children (the workers)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def run() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("-j", type=int, default=2)
    ap.add_argument("--points", type=int, default=2000)
    ap.add_argument("--out", default="build/production")
    ap.add_argument("--sensor", action="store_true", help="diagnose with the nominal sensor TOML")
    a = ap.parse_args()
    out = Path(a.out)
    shutil.rmtree(out, ignore_errors=True)
    t = time.monotonic()
    good = write_batch(out / "recordings", a.n, points=a.points)
    bad = bad_files(out / "recordings")
    print(f"simulated {a.n} sensors x {a.points} points + {len(bad)} bad files in {time.monotonic() - t:.1f} s")
    rc = flann(["gen", "--family", *map(str, good[:3]), "-o", str(out / "design")])
    if rc:
        return rc
    extra = ["--sensor", "data/sensors/paper_lvdt.toml"] if a.sensor else []
    load0 = os.getloadavg()[0]
    cpu0 = _cpu_s()
    t = time.monotonic()
    rc = flann(["calibrate", *map(str, good + bad), "-o", str(out / "calibrated"), "--design", str(out / "design"),
                "-j", str(a.j), *extra])
    dt = time.monotonic() - t
    cpu = _cpu_s() - cpu0  # the pool's workers are reaped when calibrate returns
    load = (load0 + os.getloadavg()[0]) / 2
    with open(out / "calibrated" / "summary.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    ok = [r for r in rows if r["status"] == "ok"]
    failed = [r for r in rows if r["status"] != "ok"]
    certs = list((out / "calibrated").glob("*/certificate.html"))
    stray = [p for p in (out / "calibrated").rglob(".*")]
    ratios = sorted(float(r["ratio_to_limit"]) for r in ok)
    print(f"calibrate: {len(rows)} recordings in {dt:.1f} s on -j {a.j} = {len(rows) / dt * 60:.0f} sensors/min "
          f"({'nominal sensor' if a.sensor else 'geometry calibrated by the diagnosis'}; "
          f"load average {load:.1f} on {os.cpu_count()} cores)")
    print(f"  CPU {cpu:.1f} s = {cpu / len(rows):.2f} s per recording: {len(rows) / cpu * 60 * 2:.0f} sensors/min "
          f"on 2 idle cores (CPU-bound estimate)")
    print(f"  {len(ok)} ok, {len(failed)} failed, {len(certs)} certificates, exit code {rc}, "
          f"{len(stray)} stray temporary files")
    if ratios:
        print(f"  max error / physical limit: median {ratios[len(ratios) // 2]:.2f}, worst {ratios[-1]:.2f}")
    for r in failed:
        print(f"  failed {r['sensor']}: {r['reason']}")
    good_run = (len(certs) == a.n and len(failed) == len(bad) and rc != 0 and not stray)
    return 0 if good_run else 1


if __name__ == "__main__":
    sys.exit(run())
