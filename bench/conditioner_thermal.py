"""The conditioner with temperature compensation: the seed paper's LVDT with its construction's
temperature model (data/sensors/paper_lvdt_thermal.toml), from waveforms of a calibration at
several temperatures to a chain whose FLANN takes the temperature too.

    PYTHONPATH=gen .venv/bin/python bench/conditioner_thermal.py [--hardware] [--noise-v 0.0001]

Training: waveforms at 0, 10, 20, 30, 40 and 50 degC (2.5 kHz, 64 samples a period, 12-bit
converters ranged +-2 V, 101 positions 0.5 mm apart over +-25 mm, 4 ms dwells; noise seed 1:
0.77 M samples, within a recording's million rows), `flann train --temperature` (the ratio at
625 Hz, a 277 Hz bandwidth), `flann gen` (``--output-lsb-mm``, default 0.0005 mm).  Held out:
the same trajectory at 5, 25 and 45 degC (noise seed 2), `flann eval --design`.  Printed: the
drift of the ratio alone (the straight line through each temperature's readings moved by the
temperature), of the float chain and of the design's words, each in ppm FS/degC against the
AD598's 50 ppm FS/degC (gain and offset drift, max) and against the ratio's own; then every
data-sheet figure as bench/conditioner_lvdt.py prints it.  ``--hardware`` also runs `flann sim`
(the two-input FLANN over every ratio code at 17 temperature codes: minutes) and `flann synth`
(Spartan-II estimate, iCE40-HX8K place and route).  Exit 0 when the compensated drift, float
and hardware, is within the AD598's and below the ratio's own, and the linearity within 0.05 %
FS.
"""

import argparse
import sys
import tempfile
from pathlib import Path

from conditioner_closed_form import eval_result, hardware_steps, judge, run_steps
from conditioner_lvdt import output_rate_hz

SENSOR = Path("data/sensors/paper_lvdt_thermal.toml")
AD598_DRIFT_PPM_FS_PER_C = 50.0   # AD598: gain and offset drift, max
TRAIN_C, HELD_C = "0,10,20,30,40,50", "5,25,45"


def drift_verdict(res: dict) -> int:
    """The drift figures against the AD598's and the ratio's own; 1 when one misses."""
    drift = res.get("drift_ppm_fs_per_c") or {}
    raw = drift.get("raw")
    if raw is None:
        print("drift: not measured (the held-out recording holds one temperature)")
        return 1
    missed = 0
    print(f"drift of the ratio alone: {raw:.3g} ppm FS/degC (the straight line through each temperature's dwells)")
    for name in ("float", "hardware"):
        value = drift.get(name)
        if value is None:
            print(f"drift ({name}): not measured")
            missed += 1
            continue
        ok = value <= AD598_DRIFT_PPM_FS_PER_C and value < raw
        missed += not ok
        against_raw = (f"{raw / value if value else float('inf'):.1f}x below the ratio's own" if value < raw
                       else "not below the ratio's own")
        print(f"drift ({name}) {value:.3g} ppm FS/degC: {'within' if value <= AD598_DRIFT_PPM_FS_PER_C else 'beyond'} "
              f"the AD598's {AD598_DRIFT_PPM_FS_PER_C:g} (max), {against_raw}")
    for name in ("raw", "compensated"):
        rows = res[name].get("by_temperature") or []
        print(f"max error by temperature ({name}): " + ", ".join(
            f"{r['temperature_c']:g} degC {r['max_error_mm']:.4g} mm" for r in rows))
    return missed


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--noise-v", type=float, default=1e-4, help="rms on each secondary (default 0.1 mV)")
    ap.add_argument("--output-lsb-mm", type=float, default=0.0005, help="the design's output LSB (default 0.0005)")
    ap.add_argument("--hardware", action="store_true", help="also flann sim and flann synth the design")
    a = ap.parse_args()
    if not SENSOR.is_file():
        print(f"error: {SENSOR}: not found (run from the repository's root)", file=sys.stderr)
        return 2
    common = ["--waveforms", "--carrier-hz", 2500, "--sample-rate-hz", 160000, "--adc-bits", 12,
              "--adc-range-v", 2, "--from-mm", -25, "--to-mm", 25, "--step-mm", 0.5,
              "--trajectory", "steps:0.004", "--noise-v", a.noise_v]
    with tempfile.TemporaryDirectory(prefix="thermal_chain_") as tmp:
        d = Path(tmp)
        steps = [("simulate", ["simulate", SENSOR, "-o", d / "wave.csv", *common, "--seed", 1,
                               "--temperatures", TRAIN_C]),
                 ("simulate", ["simulate", SENSOR, "-o", d / "held_out.csv", *common, "--seed", 2,
                               "--temperatures", HELD_C]),
                 ("train", ["train", d / "wave.csv", "--temperature", "-o", d / "model.json",
                            "--output-rate-hz", output_rate_hz(2500.0)]),
                 ("gen", ["gen", d / "model.json", "-o", d / "design", "--output-lsb-mm", a.output_lsb_mm]),
                 ("eval", ["eval", d / "model.json", d / "held_out.csv", "--design", d / "design", "--json",
                           "--quiet"])]
        print(f"{SENSOR}: trained at {TRAIN_C} degC, held out at {HELD_C} degC, {1e3 * a.noise_v:g} mV rms",
              flush=True)
        outs = run_steps(steps)
        if outs is None:
            return 1
        # each hardware step on its own: a chain that does not fit a part still simulates
        for step in hardware_steps(d / "design") if a.hardware else ():
            outs += run_steps([step]) or []
        res = eval_result(outs)
        missed = drift_verdict(res)
        lin = res["linearity_pct_fs"]
        judge(outs)   # every data-sheet figure and the synth lines, printed with their verdicts
    missed += any(lin[c] is None or lin[c] > lin["reference_pct_fs"] for c in ("float", "hardware"))
    print(f"\n{'drift and linearity met' if not missed else 'missed: see above'}")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
