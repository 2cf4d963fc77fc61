#!/usr/bin/env python3
"""The production line with temperature on sensors the project did not make, end to end.

    .venv/bin/python bench/thermal_line.py [--out build/thermal_line] [--input-bits 12] [--terms auto|N]
                                           [--no-sim] [--no-synth]

Writes 3 recordings of a closed-form S-curve family (not the physics simulator; the same
formula as tests/production/test_family_thermal_line.py) whose gain (-1.2e-4 .. -2.6e-4 /degC)
and null (-25 .. +40 uV/degC) move with temperature, each calibrated at -20, 25 and 80 degC
(forward and reverse sweeps of 100 points, 0.2 mV noise, a 14-bit +-3.6 V ADC), then runs::

    flann gen --family a.csv b.csv c.csv -o OUT/design --input-bits B --terms auto
    flann sim OUT/design                      (every voltage code at 9 temperature codes)
    flann synth OUT/design                    (VSG lint, GHDL + Yosys)
    flann calibrate a.csv b.csv c.csv --design OUT/design -o OUT/calibrated

and prints each sensor's max error, raw and hardware drift (ppm FS/degC) from summary.csv.
Exit 0 when the simulation has 0 mismatches and every sensor PASSes.
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from flann.recordings import Recordings, write_recordings

SPAN_MM, W_MM, SHARP = 10.0, 7.0, 2.5
ADC_LSB_V = 2 * 3.6 / 2 ** 14
TEMPS = (-20.0, 25.0, 80.0)
SENSORS = {"a": (3.0, -2.0e-4, 40e-6), "b": (3.1, -1.2e-4, -25e-6), "c": (2.9, -2.6e-4, 10e-6)}


def volts(x, temp, amp, gain_tc, null_tc):
    u = x / W_MM
    dt = temp - 25.0
    return amp * (1 + gain_tc * dt) * u / (1 + np.abs(u) ** SHARP) ** (1 / SHARP) + null_tc * dt


def recording(params, seed, steps=100):
    x = np.linspace(-SPAN_MM, SPAN_MM, steps)
    xs = np.concatenate([np.concatenate([x, x[::-1]]) for _ in TEMPS])
    ds = np.tile(np.concatenate([np.ones(steps), -np.ones(steps)]), len(TEMPS))
    ts = np.repeat(TEMPS, 2 * steps)
    noise = np.random.default_rng(seed).normal(0, 0.2e-3, xs.size)
    v = np.round((volts(xs, ts, *params) + noise) / ADC_LSB_V) * ADC_LSB_V
    return Recordings(displacement_mm=xs, voltage_v=v, direction=ds, temperature_c=ts)


def flann(*args) -> int:
    cmd = [str(Path(sys.executable).with_name("flann")), *map(str, args)]
    print("$ flann " + " ".join(map(str, args)), flush=True)
    return subprocess.call(cmd)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="build/thermal_line")
    ap.add_argument("--input-bits", type=int, default=12)
    ap.add_argument("--terms", default="auto", help="gen --family --terms (auto: the default; 15: the former fixed count)")
    ap.add_argument("--no-sim", action="store_true")
    ap.add_argument("--no-synth", action="store_true")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for k, (name, params) in enumerate(SENSORS.items()):
        paths.append(out / f"{name}.csv")
        write_recordings(paths[-1], recording(params, seed=k))
    ok = flann("gen", "--family", *paths, "-o", out / "design", "--input-bits", args.input_bits,
               "--terms", args.terms) == 0
    if ok and not args.no_sim:
        ok = flann("sim", out / "design", "--summary-json", out / "sim.json") == 0
        s = json.loads((out / "sim.json").read_text())
        print(f"sim: {s['codes_tested']} samples, {s['mismatches']} mismatches, temperature codes "
              f"{s['temperature_codes']}")
    if ok and not args.no_synth:
        flann("synth", out / "design")
    rc = flann("calibrate", *paths, "--design", out / "design", "-o", out / "calibrated", "-j", "2")
    with open(out / "calibrated" / "summary.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    print(f"{'sensor':<8}{'verdict':<9}{'max mm':>9}{'raw max mm':>12}{'drift hw':>10}")
    for r in rows:
        print(f"{r['sensor']:<8}{r['verdict']:<9}{r['max_error_mm']:>9}{r['raw_max_error_mm']:>12}"
              f"{r['drift_ppm_fs_per_c']:>10}")
    return 0 if ok and rc == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
