#!/usr/bin/env python3
"""A family of 20 sensors the project did not make: the shared design against each member's own.

    .venv/bin/python bench/family_reach.py [--n 20] [--terms auto] [--out build/family_reach]

Draws N closed-form S-curve sensors of one family (the shape of tests/production/
test_calibrate_closed_form.py: amplitude, asymmetry and width varied by a few per cent; 14-bit
converter, 0.5 mV noise, 300 positions forward and back), sizes one design from all of them
(`flann gen --family ... --terms T`), calibrates every sensor on it (`flann calibrate`), and
compares each sensor's hardware max error on its recording with what its own `--terms auto`
model reaches on the same points (calibrate's `own_design_max_error_mm`).  Prints the
medians and their ratio, and how many sensors calibrate flagged.  Exit 0 when the family's
median is within 1.5x of the members' own.
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
from pathlib import Path

import numpy as np

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from flann.cli import main as flann  # noqa: E402
from flann.golden.family import REACH_FACTOR  # noqa: E402
from flann.recordings import Recordings, write_recordings  # noqa: E402

SPAN_MM, W_MM, SHARP = 10.0, 7.0, 2.5
BITS, ADC_LSB_V = 14, 2 * 3.6 / 2 ** 14


def s_curve(x, amp_v, asym, w_mm):
    u = x / w_mm
    return amp_v * np.where(u >= 0, 1 + asym, 1 - asym) * u / (1 + np.abs(u) ** SHARP) ** (1 / SHARP)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--terms", default="auto")
    ap.add_argument("--out", default="build/family_reach")
    a = ap.parse_args()
    out = Path(a.out)
    (out / "rec").mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(7)
    paths = []
    for k in range(a.n):
        amp, asym, w = rng.uniform(2.9, 3.2), rng.uniform(-0.03, 0.03), W_MM * rng.uniform(0.95, 1.05)
        x = np.linspace(-SPAN_MM, SPAN_MM, 300)
        xs = np.concatenate([x, x[::-1]])
        d = np.concatenate([np.ones(300), -np.ones(300)])
        v = np.round((s_curve(xs, amp, asym, w) + rng.normal(0, 0.5e-3, xs.size)) / ADC_LSB_V) * ADC_LSB_V
        paths.append(out / "rec" / f"s{k:02d}.csv")
        write_recordings(paths[-1], Recordings(displacement_mm=xs, voltage_v=v, direction=d))
    design = out / f"design_{a.terms}"
    adc = ["--input-bits", str(BITS), "--input-lsb-v", repr(ADC_LSB_V)]
    if flann(["gen", "--family", *map(str, paths), "-o", str(design), "--terms", a.terms, *adc]):
        return 1
    cal = out / f"cal_{a.terms}"
    flann(["calibrate", *map(str, paths), "-o", str(cal), "--design", str(design), "-j", "2"])
    with open(cal / "summary.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["status"] == "ok"]
    fam_err = {r["sensor"]: float(r["max_error_mm"]) for r in rows}
    own = {r["sensor"]: float(r["own_design_max_error_mm"]) for r in rows}
    names = sorted(fam_err)
    f = np.median([fam_err[n] for n in names])
    o = np.median([own[n] for n in names])
    flagged = sum(fam_err[n] > REACH_FACTOR * own[n] for n in names)
    print(f"family (--terms {a.terms}): {len(names)}/{a.n} calibrated; median hardware max error {f:.4g} mm, "
          f"members' own designs {o:.4g} mm: {f / o:.2f}x; flagged (> {REACH_FACTOR:g}x own): {flagged}")
    return 0 if f <= 1.5 * o else 1


if __name__ == "__main__":
    sys.exit(main())
