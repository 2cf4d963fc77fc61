"""The conditioner's twin on simulated waveforms of the seed paper's LVDT: the figures quoted in
docs/waveforms.md ("Through the conditioner").

    PYTHONPATH=gen .venv/bin/python bench/conditioner_linearity.py

For each carrier (2.5 and 10 kHz): waveforms at 32 samples per period, 12-bit converters of
+-5 V, 0.5 mV rms of noise on each secondary, dwell at 2.5 mm steps over +-25 mm (the output is
monotonic to 30 mm), written to CSV and read back; the chain at a 500 Hz output rate.  Printed,
each in % of full scale (25 mm) and judged against the AD598's 0.05 % FS linearity:

* the conditioner's own error: its ratio against a float lock-in's ratio of the same
  secondaries without noise or converter (the electronics: converter, table, divider, noise),
  every window, and averaged per position (what remains without the noise);
* its in-phase difference, in volts, against `flann simulate`'s demodulated output;
* the ratio's straight-line linearity: the sensor's, which the FLANN downstream linearises;
* the ratio's noise as effective bits over the ratio's span;
* the ratio's shift for a quadrature residual of 10 % of the full-scale output.
"""

import math
import sys
import tempfile
from pathlib import Path

import numpy as np

from flann.golden.metrics import full_scale_mm, raw_line, raw_output_mm
from flann.hardware.conditioner.condition import condition
from flann.hardware.conditioner.spec import derive_conditioner, reference_phase
from flann.physics.sensor import default_sensor
from flann.physics.simulate import simulate_output_v
from flann.physics.waveforms import WaveformSettings, parse_trajectory, simulate_waveforms
from flann.recordings.waveform import read_waveforms, write_waveforms

AD598_PCT_FS = 0.05
QUADRATURE_PPM_FS = 50   # a tenth of the AD598's 0.05 % FS
AD2S93_BITS = 14   # the LVDT-to-digital converter's resolution
NOISE_V = 0.5e-3
RANGE_V = 5.0
TRAVEL = (-25.0, 25.0)


def float_ratio(wave, spec, phase: float) -> np.ndarray:
    """Per window, the ratio of a float lock-in at the chain's reference phase."""
    k = np.arange(len(wave))
    theta = 2 * math.pi * k / spec.samples_per_period + phase
    ref = np.cos(theta)
    n = len(wave) // spec.window * spec.window
    ia = (wave.sec_a_v * ref)[:n].reshape(-1, spec.window).sum(axis=1)
    ib = (wave.sec_b_v * ref)[:n].reshape(-1, spec.window).sum(axis=1)
    return (ia - ib) / (ia + ib)


def figures(carrier_hz: float, out_dir: Path) -> dict:
    s = default_sensor().replace(excitation_frequency_hz=carrier_hz)
    spec = derive_conditioner(adc_bits=12, carrier_hz=carrier_hz, output_rate_hz=500.0)
    traj = parse_trajectory("steps:0.02")
    common = dict(carrier_hz=carrier_hz, sample_rate_hz=spec.samples_per_period * carrier_hz)
    noisy = simulate_waveforms(s, WaveformSettings(adc_bits=12, adc_range_v=RANGE_V, noise_v=NOISE_V, seed=1,
                                                   **common), traj, travel_mm=TRAVEL, step_mm=2.5)
    path = out_dir / f"wave_{carrier_hz:g}.csv"
    write_waveforms(path, noisy)
    wave = read_waveforms(path, announce=False)
    exact = simulate_waveforms(s, WaveformSettings(adc_bits=32, adc_range_v=20.0, **common), traj,
                               travel_mm=TRAVEL, step_mm=2.5)
    c = condition(wave, spec, RANGE_V)
    keep = c.steady & (c.sat == 0)
    x, r = c.displacement_mm[keep], c.ratio[keep]
    fs = full_scale_mm(x)
    slope, _ = raw_line(r, x)
    ref = float_ratio(exact, spec, reference_phase(spec, c.ref))[keep]
    dc = simulate_output_v(s, x)
    per_position = [np.std(r[x == v]) for v in np.unique(x)]
    bias = [abs(np.mean((r - ref)[x == v])) for v in np.unique(x)]
    noise = float(np.median(per_position))
    return {
        "carrier_hz": carrier_hz, "window": spec.window, "ratio_frac_bits": spec.ratio_frac_bits,
        "electronics_pct_fs": 100 * float(np.max(np.abs(slope * (r - ref)))) / fs,
        "systematic_pct_fs": 100 * abs(slope) * float(np.max(bias)) / fs,
        "dc_difference_pct_fs": 100 * float(np.max(np.abs(s.demodulator_gain_ratio * c.difference_v[keep] - dc)))
        / float(np.ptp(dc) / 2),
        "straight_line_pct_fs": 100 * float(np.max(np.abs(raw_output_mm(r, x) - x))) / fs,
        "effective_bits": math.log2(float(np.ptp(r)) / (noise * math.sqrt(12))),
    }


def quadrature_ppm_fs(carrier_hz: float) -> float:
    """Ratio shift (ppm FS) for a quadrature residual of 10 % of the full-scale output, with
    16-bit converters and no noise (a 12-bit converter's rounding alone moves an undithered
    ratio by a few hundred ppm when the signal changes)."""
    base = default_sensor().replace(excitation_frequency_hz=carrier_hz)
    spec = derive_conditioner(adc_bits=16, carrier_hz=carrier_hz, output_rate_hz=500.0)
    settings = WaveformSettings(carrier_hz=carrier_hz, sample_rate_hz=spec.samples_per_period * carrier_hz,
                                adc_bits=16, adc_range_v=RANGE_V)
    full_scale_v = float(np.max(np.abs(simulate_output_v(base, np.array(TRAVEL)))))
    runs = []
    for s in (base, base.with_effect("quadrature_null", quadrature_v=0.1 * full_scale_v)):
        wave = simulate_waveforms(s, settings, parse_trajectory("steps:0.004"), travel_mm=TRAVEL, step_mm=5.0)
        runs.append(condition(wave, spec, RANGE_V))
    x = runs[0].displacement_mm
    slope, _ = raw_line(runs[0].ratio, x)
    return 1e6 * float(np.max(np.abs(slope * (runs[1].ratio - runs[0].ratio)))) / full_scale_mm(x)


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        for carrier in (2500.0, 10000.0):
            f = figures(carrier, Path(tmp))
            ok = "within" if f["electronics_pct_fs"] <= AD598_PCT_FS else "beyond"
            print(f"carrier {carrier:g} Hz (window {f['window']} samples, ratio {f['ratio_frac_bits']} fraction bits):")
            print(f"  conditioner's own error {f['electronics_pct_fs']:.4f} % FS: {ok} the AD598's "
                  f"{AD598_PCT_FS} % FS linearity (every window, noise included); averaged per position "
                  f"{f['systematic_pct_fs']:.4f} % FS")
            print(f"  in-phase difference against flann simulate's demodulated output: "
                  f"{f['dc_difference_pct_fs']:.4f} % FS ({'within' if f['dc_difference_pct_fs'] <= AD598_PCT_FS else 'beyond'} "
                  f"{AD598_PCT_FS} % FS)")
            print(f"  ratio's straight-line linearity {f['straight_line_pct_fs']:.2f} % FS: "
                  f"{'beyond' if f['straight_line_pct_fs'] > AD598_PCT_FS else 'within'} {AD598_PCT_FS} % FS "
                  "(the sensor's own curve; the FLANN linearises it)")
            quad = quadrature_ppm_fs(carrier)
            print(f"  quadrature of 10 % of the full-scale output moves the ratio {quad:.1f} ppm FS "
                  f"({'within' if quad <= QUADRATURE_PPM_FS else 'beyond'} {QUADRATURE_PPM_FS} ppm FS, an "
                  "AD598's 0.05 % FS linearity a tenth of it)")
            bits = f["effective_bits"]
            print(f"  noise: {bits:.1f} effective bits over the ratio's span at 500 Hz: "
                  f"{'above' if bits >= AD2S93_BITS else 'below'} the AD2S93's {AD2S93_BITS} bits")
    return 0


if __name__ == "__main__":
    sys.exit(main())
