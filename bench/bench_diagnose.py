"""Benchmark: `flann diagnose` runtime on 2,000 recorded points (target < 10 s).

Run: .venv/bin/python bench/bench_diagnose.py
Prints wall-clock and CPU time of diagnose() (calibration, noise, outliers, regions, forward
selection with cross-validation) for a control, a one-effect and a two-effect recording of
2,000 points (one out-and-back sweep of the paper's LVDT, 5 mV noise), and for the whole
`flann diagnose` command on the two-effect file (process start, CSV read, plot, JSON).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

from flann.diagnose import diagnose
from flann.physics.sensor import default_sensor
from flann.physics.simulate import simulate_recordings
from flann.recordings import write_recordings

POINTS = 2000


def recordings(effects: dict, seed: int):
    s = default_sensor().replace(effects={}, adc_bits=None, adc_full_scale_v=None)
    for name, params in effects.items():
        s = s.with_effect(name, **params)
    step = 2 * s.stroke_mm / (POINTS / 2)
    return simulate_recordings(s, sweeps=1, step_mm=step, noise_v=0.005, seed=seed)


def main() -> int:
    cases = {
        "control (nothing missing)": {},
        "backlash 20 um": {"backlash": {"deadband_mm": 0.02}},
        "backlash 20 um + null_offset 3 mV": {"backlash": {"deadband_mm": 0.02},
                                              "null_offset": {"offset_v": 0.003}},
    }
    worst = 0.0
    for label, effects in cases.items():
        rec = recordings(effects, seed=42)
        w0, c0 = time.perf_counter(), time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            dg = diagnose(rec)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        worst = max(worst, wall)
        print(f"{label:36s} {len(rec):5d} points: {wall:6.2f} s wall, {cpu:6.2f} s CPU; "
              f"named: {', '.join(dg.named) or 'nothing'}")
    with tempfile.TemporaryDirectory() as tmp:
        csv = Path(tmp) / "rec.csv"
        write_recordings(csv, recordings(cases["backlash 20 um + null_offset 3 mV"], seed=42))
        flann = Path(sys.executable).with_name("flann")
        w0 = time.perf_counter()
        subprocess.run([str(flann), "diagnose", str(csv), "--json", str(Path(tmp) / "d.json"),
                        "--plot", str(Path(tmp) / "d.png"), "--quiet"], check=True,
                       stdout=subprocess.DEVNULL)
        cli = time.perf_counter() - w0
    print(f"{'flann diagnose CLI (two effects)':36s} {POINTS + 1:5d} points: {cli:6.2f} s wall "
          "(incl. start-up, plot, JSON)")
    print(f"worst diagnose() wall time: {worst:.2f} s (target < 10 s): "
          f"{'OK' if max(worst, cli) < 10 else 'OVER'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
