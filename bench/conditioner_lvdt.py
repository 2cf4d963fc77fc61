"""The seed paper's LVDT through the whole conditioner chain at both carriers, from simulated
waveforms: simulate -> train -> gen -> eval on a held-out recording, each figure judged.

    PYTHONPATH=gen .venv/bin/python bench/conditioner_lvdt.py [--noise-v 0.0001] [--carriers 2500 10000]

Both carriers are sampled at 2.56 MS/s (1024 samples a period at 2.5 kHz, 256 at 10 kHz: 43.5 MHz
at the demodulator's 17 clocks a sample), 12-bit converters ranged +-2.5 V (the secondaries
peak at 2.35 V), the ratio at the whole number of carrier periods whose boxcar bandwidth
(0.443 x the rate) is nearest above 250 Hz.  Training dwells 8 ms at 21 positions 2.5 mm apart
over +-25 mm (noise seed 1); the held-out recording is the same trajectory with noise seed 2.
The noise is white on each secondary's samples, before the converters (default 0.1 mV rms:
0.08 LSB, a quiet front end and a converter whose own transition noise is below 0.1 LSB).
The design's output LSB is `flann gen`'s default (at the output's noise as training measured
it, so that its words carry the conditioner's resolution), or ``--output-lsb-mm``.  ``--hardware`` also runs ``flann sim`` and ``flann synth`` (Spartan-II and iCE40-HX8K) on each
design.  Exit 0 when every judged figure meets its reference at every carrier.
"""

import argparse
import math
import sys
import tempfile
from pathlib import Path

from conditioner_closed_form import hardware_steps, judge, run_steps

SENSOR = Path("data/sensors/paper_lvdt.toml")
SAMPLE_RATE_HZ = 2.56e6
RANGE_V = 2.5
BANDWIDTH_HZ = 250.0


def output_rate_hz(carrier_hz: float) -> float:
    """The fastest whole-period rate whose boxcar bandwidth is at least 250 Hz."""
    periods = math.floor(carrier_hz * 0.4429 / BANDWIDTH_HZ)
    return carrier_hz / periods


def carrier(d: Path, hz: float, noise_v: float, hardware: bool, output_lsb_mm: float | None) -> int:
    rate = output_rate_hz(hz)
    print(f"\n== carrier {hz:g} Hz, {SAMPLE_RATE_HZ / hz:g} samples a period, ratio at {rate:.4g} Hz, "
          f"{1e3 * noise_v:g} mV rms", flush=True)
    common = ["--waveforms", "--carrier-hz", hz, "--sample-rate-hz", SAMPLE_RATE_HZ, "--adc-bits", 12,
              "--adc-range-v", RANGE_V, "--from-mm", -25, "--to-mm", 25, "--step-mm", 2.5,
              "--trajectory", "steps:0.008", "--noise-v", noise_v]
    steps = [("simulate", ["simulate", SENSOR, "-o", d / "wave.csv", *common, "--seed", 1]),
             ("simulate", ["simulate", SENSOR, "-o", d / "held_out.csv", *common, "--seed", 2]),
             ("train", ["train", d / "wave.csv", "-o", d / "model.json", "--adc-bits", 12,
                        "--adc-range-v", RANGE_V, "--output-rate-hz", rate]),
             ("gen", ["gen", d / "model.json", "-o", d / "design",
                      *(["--output-lsb-mm", output_lsb_mm] if output_lsb_mm is not None else [])]),
             ("eval", ["eval", d / "model.json", d / "held_out.csv", "--design", d / "design", "--json", "--quiet"])]
    if hardware:
        steps += hardware_steps(d / "design")
    outs = run_steps(steps)
    if outs is None:
        return 1
    return judge(outs)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--noise-v", type=float, default=1e-4, help="rms on each secondary (default 0.1 mV)")
    ap.add_argument("--carriers", type=float, nargs="+", default=[2500.0, 10000.0])
    ap.add_argument("--hardware", action="store_true", help="also flann sim and flann synth each design")
    ap.add_argument("--output-lsb-mm", type=float, default=None,
                    help="the design's output LSB (default flann gen's: at the output's noise as training measured it)")
    a = ap.parse_args()
    if not SENSOR.is_file():
        print(f"error: {SENSOR}: not found (run from the repository's root)", file=sys.stderr)
        return 2
    missed = 0
    for hz in a.carriers:
        with tempfile.TemporaryDirectory(prefix="lvdt_chain_") as tmp:
            missed += carrier(Path(tmp), hz, a.noise_v, a.hardware, a.output_lsb_mm)
    print(f"\n{'every figure met' if not missed else f'{missed} carrier(s) missed a figure'} "
          f"at {1e3 * a.noise_v:g} mV rms")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
