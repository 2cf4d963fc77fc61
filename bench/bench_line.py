#!/usr/bin/env python3
"""A production line on a sensor the project has no file for: verdicts, certificates, throughput.

    .venv/bin/python bench/bench_line.py [--n 50] [--fail 5] [-j 2] [--points 2000] [--out build/line]

Simulates N sensors of one design with the independent forward model
(``flann.physics.filament``: a geometry the project has no sensor file for, drawn once,
then +-2 % per sensor, +-3 mV null offset), ``--fail`` of them with a 50 um lead-screw
ripple in their fixture, plus 5 bad files (not a CSV, no voltage column, outside the
family, a last line cut off, an empty file).  Sizes one family design from the first three
(``flann gen --family``), writes a spec (tolerance from the good sensors' own spread), and
times ``flann calibrate --spec`` with station, operator and fixture.  Prints sensors per
minute (wall clock, load average beside it: the machine may be shared) and CPU seconds per
sensor (all workers; the figure to compare), and checks that the batch behaved as a line
needs: N + 5 certificates, the rippled sensors FAIL the tolerance, the bad files FAIL as
rejected, every good sensor PASSes, summary.csv has every column, exit code non-zero.
Exit 0 when all of that holds.
"""

from __future__ import annotations

import argparse
import csv
import os
import resource
import shutil
import sys
import time
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from flann.cli import main as flann  # noqa: E402
from flann.physics import filament as F  # noqa: E402
from flann.production.calibrate import SUMMARY_FIELDS  # noqa: E402
from flann.production.demo import bad_files  # noqa: E402
from flann.recordings import write_recordings  # noqa: E402

NOISE_V = 0.2e-3
RIPPLE_MM = 0.05


def _cpu_s() -> float:
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def write_line(out: Path, n: int, n_fail: int, points: int, seed: int = 11) -> tuple[list[Path], list[Path]]:
    """n recordings of one filament-model design; the last n_fail with a lead-screw ripple."""
    rng = np.random.default_rng(seed)
    base = F.random_geometry(rng)
    h = F.monotonic_half_range(base) * 0.8
    base = F.scaled_to(base, 4.0, h)
    good, rippled = [], []
    for k in range(n):
        r = np.random.default_rng([seed, k])
        m = replace(base, **{f: getattr(base, f) * float(r.uniform(0.98, 1.02))
                             for f in ("primary_length_mm", "secondary_length_mm", "core_length_mm",
                                       "secondary_turns")})
        eff = {"offset": {"offset_v": float(r.uniform(-0.003, 0.003))}}
        bad = k >= n - n_fail
        if bad:
            eff["leadscrew"] = {"amplitude_mm": RIPPLE_MM, "period_mm": 2 * h / 12, "phase_rad": 0.0}
        rec = F.simulate_recording(m.with_effects(**eff), (-h, h), 2 * h / (points // 2 - 1), NOISE_V,
                                   seed=1000 + k, source="line")
        p = out / f"sn{k:04d}.csv"
        write_recordings(p, rec, comments=(f"serial: SN-{seed:02d}-{k:04d}",
                                           f"temperature_c: {21.5 + 0.1 * (k % 7):.1f}"))
        (rippled if bad else good).append(p)
    return good, rippled


def more_bad_files(out: Path, like: Path) -> list[Path]:
    """A recording cut off in its last line, and an empty file (beside the demo's three)."""
    text = like.read_text()
    cut = out / "bad_truncated.csv"
    cut.write_text(text[: text.rindex("\n", 0, len(text) - 1) + 6])
    empty = out / "bad_empty.csv"
    empty.write_text("")
    return [cut, empty]


def run() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=50)
    ap.add_argument("--fail", type=int, default=5)
    ap.add_argument("-j", type=int, default=2)
    ap.add_argument("--points", type=int, default=2000)
    ap.add_argument("--out", default="build/line")
    a = ap.parse_args()
    out = Path(a.out)
    shutil.rmtree(out, ignore_errors=True)
    (out / "recordings").mkdir(parents=True)
    good, rippled = write_line(out / "recordings", a.n, a.fail, a.points)
    bad = bad_files(out / "recordings") + more_bad_files(out / "recordings", good[0])
    rc = flann(["gen", "--family", *map(str, good[:3]), "-o", str(out / "design")])
    if rc:
        return rc
    # the tolerance: twice the worst good sensor of a pilot run on the first three
    pilot = out / "pilot"
    flann(["calibrate", *map(str, good[:3]), "-o", str(pilot), "--design", str(out / "design"), "-j", str(a.j)])
    with open(pilot / "summary.csv", newline="") as fh:
        tol = 2 * max(float(r["max_error_mm"]) for r in csv.DictReader(fh))
    spec = out / "spec.toml"
    spec.write_text(f'name = "filament LVDT, line bench"\n[tolerance]\nmax_error_mm = {tol:.4f}\n'
                    '[limits]\nfail_on_effects = ["adc_clipping"]\n')
    paths = good + rippled + bad
    load0 = os.getloadavg()[0]
    cpu0 = _cpu_s()
    t = time.monotonic()
    rc = flann(["calibrate", *map(str, paths), "-o", str(out / "calibrated"), "--design", str(out / "design"),
                "-j", str(a.j), "--spec", str(spec), "--station", "bench line 1", "--operator", "bench",
                "--fixture", "F-01"])
    dt = time.monotonic() - t
    cpu = _cpu_s() - cpu0
    load = (load0 + os.getloadavg()[0]) / 2
    with open(out / "calibrated" / "summary.csv", newline="") as fh:
        reader = csv.DictReader(fh)
        columns = reader.fieldnames or []
        rows = {r["sensor"]: r for r in reader}
    certs = sorted((out / "calibrated").glob("*/certificate.html"))
    verdicts = {s: r["verdict"] for s, r in rows.items()}
    n = len(paths)
    print(f"calibrate: {n} recordings ({a.n} sensors x {a.points} points, no sensor file, + {len(bad)} bad files) "
          f"in {dt:.1f} s on -j {a.j} = {n / dt * 60:.0f} sensors/min (load average {load:.1f} on "
          f"{os.cpu_count()} cores)")
    print(f"  CPU {cpu:.1f} s = {cpu / n:.2f} s per recording: {n / cpu * 60 * 2:.0f} sensors/min on 2 idle cores")
    print(f"  tolerance {tol:.4f} mm; {sum(v == 'PASS' for v in verdicts.values())} PASS, "
          f"{sum(v == 'FAIL' for v in verdicts.values())} FAIL; {len(certs)} certificates; exit code {rc}")
    for s, r in rows.items():
        if r["verdict"] != "PASS":
            print(f"  FAIL {s}: {r['reasons'][:110]}")
    checks = {
        "every recording has a certificate": len(certs) == n,
        "the rippled sensors FAIL the tolerance": all(verdicts.get(p.stem) == "FAIL" and "tolerance" in
                                                     rows[p.stem]["reasons"] for p in rippled),
        "the bad files FAIL as rejected": all(verdicts.get(p.stem) == "FAIL" and
                                              rows[p.stem]["reasons"].startswith("rejected") for p in bad),
        "every good sensor PASSes": all(verdicts.get(p.stem) == "PASS" for p in good),
        "summary has every column": all(c in columns for c in SUMMARY_FIELDS),
        "exit code non-zero": rc != 0,
    }
    for what, ok in checks.items():
        print(f"  {'ok ' if ok else 'NOT'} {what}")
    return 0 if all(checks.values()) else 1


if __name__ == "__main__":
    sys.exit(run())
