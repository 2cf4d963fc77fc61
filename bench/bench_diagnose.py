"""Benchmark: `flann diagnose` runtime on 2,000 recorded points (target < 10 s).

Run: .venv/bin/python bench/bench_diagnose.py
Prints wall-clock and CPU time of diagnose() (calibration, noise, outliers, regions, forward
selection with cross-validation) for a control, a one-effect and a two-effect recording of
2,000 points (one out-and-back sweep of the paper's LVDT, 5 mV noise), for the two slowest
kinds of case on the independent forward model (a lead screw; thermal drift beside rails)
stretched to 2,000 points, for the whole `flann diagnose` command on the two-effect file
(process start, CSV read, plot, JSON), and for the production line's budgeted diagnosis
(`flann calibrate`: 250 bin means of a 2,000-point sweep of a sensor with +-5 % geometry,
diagnosed with the nominal sensor file; CPU per sensor, target well under 1.2 s).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

from flann.diagnose import demo_independent as IND
from flann.diagnose import diagnose
from flann.physics import filament as F
from flann.physics.sensor import default_sensor
from flann.physics.simulate import simulate_recordings
from flann.production.calibrate import DIAGNOSIS_POINTS, diagnosis_sample
from flann.production.demo import NOISE_V, varied_sensor
from flann.recordings import write_recordings

POINTS = 2000


def recordings(effects: dict, seed: int):
    s = default_sensor().replace(effects={}, adc_bits=None, adc_full_scale_v=None)
    for name, params in effects.items():
        s = s.with_effect(name, **params)
    step = 2 * s.stroke_mm / (POINTS / 2)
    return simulate_recordings(s, sweeps=1, step_mm=step, noise_v=0.005, seed=seed)


def independent(case_name: str):
    """The independent model's demo case, re-recorded with 1,000 points per pass."""
    case = next(c for c in IND.CASES if c.name == case_name)
    d = IND.draw(case.seed, case.layout, case.both, case.rectified)
    h = d.travel_mm[1]
    return F.simulate_recording(d.sensor.with_effects(**IND.resolved(case, d)), d.travel_mm,
                                2 * h / (POINTS / 2 - 1), IND.NOISE_V, seed=case.seed,
                                origin_mm=d.origin_mm, both_directions=True,
                                temperature=IND.rise_then_hold if case.thermal else None)


def main() -> int:
    cases = {
        "control (nothing missing)": {},
        "backlash 20 um": {"backlash": {"deadband_mm": 0.02}},
        "backlash 20 um + null_offset 3 mV": {"backlash": {"deadband_mm": 0.02},
                                              "null_offset": {"offset_v": 0.003}},
    }
    recs = {label: recordings(effects, seed=42) for label, effects in cases.items()}
    for name in ("leadscrew_periodic below noise", "two at once: thermal_drift + rails"):
        recs[f"independent: {name.split(' below')[0]}"] = independent(name)
    worst = 0.0
    for label, rec in recs.items():
        w0, c0 = time.perf_counter(), time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            dg = diagnose(rec)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        worst = max(worst, wall)
        print(f"{label[:44]:44s} {len(rec):5d} points: {wall:6.2f} s wall, {cpu:6.2f} s CPU; "
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
    print(f"{'flann diagnose CLI (two effects)':44s} {POINTS + 1:5d} points: {cli:6.2f} s wall "
          "(incl. start-up, plot, JSON)")
    print(f"worst diagnose() wall time: {worst:.2f} s (target < 10 s): "
          f"{'OK' if max(worst, cli) < 10 else 'OVER'}")
    production()
    return 0


def production(n: int = 8) -> None:
    """The budgeted diagnosis `flann calibrate` runs per sensor (seed-1 batch, as
    bench/bench_calibrate.py simulates it)."""
    nominal = default_sensor()
    cpu, named = [], 0
    for k in range(n):
        s = varied_sensor(k, seed=1, spread=0.05)
        rec = simulate_recordings(s, step_mm=2 * s.stroke_mm / (POINTS / 2 - 1), noise_v=NOISE_V,
                                  seed=100003 + k)
        small = diagnosis_sample(rec, DIAGNOSIS_POINTS)[0]
        c0 = time.process_time()
        dg = diagnose(small, sensor=nominal)
        cpu.append(time.process_time() - c0)
        named += bool(dg.named)
    print(f"{'production: ' + str(DIAGNOSIS_POINTS) + ' bin means, nominal sensor file':44s} "
          f"{n:5d} sensors: {sum(cpu) / n:6.2f} s CPU mean, {max(cpu):.2f} s worst; "
          f"sensors with an effect named: {named} of {n}")


if __name__ == "__main__":
    sys.exit(main())
