"""Effective bits of the conditioner's ratio at a 250 Hz bandwidth with 12-bit converters,
against the issue's 16, as the sample rate (samples per carrier period N) grows.

    PYTHONPATH=gen .venv/bin/python bench/conditioner_enob.py

The seed paper's LVDT at 2.5 and 10 kHz, 0.5 mV rms of noise on each secondary, converters of
+-5 V; the output rate the one whose boxcar bandwidth (0.443 x output rate) is nearest 250 Hz
(whole carrier periods a window); 8 windows at each of 6 positions over +-25 mm.  Effective
bits: log2 of the ratio's span over its noise (the median per position of the windows' standard
deviation) times sqrt(12).  Each N is checked against the serial demodulator's rate: one sample
every ``cycles_per_sample`` clocks at the 50 MHz the Spartan-II must reach.
"""

import math
import sys

import numpy as np

from flann.hardware.conditioner.condition import condition
from flann.hardware.conditioner.render import cycles_per_sample
from flann.hardware.conditioner.spec import bandwidth_hz, derive_conditioner
from flann.physics.sensor import default_sensor
from flann.physics.waveforms import WaveformSettings, parse_trajectory, simulate_waveforms

TARGET_BITS = 16       # the figure at 250 Hz with 12-bit converters
BANDWIDTH_HZ = 250.0
CLOCK_HZ = 50e6        # the Fmax the chain must reach on the Spartan-II
NOISE_V = 0.5e-3
RANGE_V = 5.0


def effective_bits(carrier_hz: float, n: int) -> tuple:
    spec = derive_conditioner(adc_bits=12, carrier_hz=carrier_hz, sample_rate_hz=n * carrier_hz,
                              output_rate_hz=BANDWIDTH_HZ / 0.4429, table_bits=max(8, n.bit_length() - 1))
    s = default_sensor().replace(excitation_frequency_hz=carrier_hz)
    dwell = 8 * spec.periods_per_output / carrier_hz
    wave = simulate_waveforms(s, WaveformSettings(carrier_hz=carrier_hz, sample_rate_hz=n * carrier_hz, adc_bits=12,
                                                  adc_range_v=RANGE_V, noise_v=NOISE_V, seed=1),
                              parse_trajectory(f"steps:{dwell}"), travel_mm=(-25.0, 25.0), step_mm=10.0)
    c = condition(wave, spec, RANGE_V)
    keep = c.steady & (c.sat == 0)
    x, r = c.displacement_mm[keep], c.ratio[keep]
    noise = float(np.median([np.std(r[x == v]) for v in np.unique(x)]))
    bits = math.log2(float(np.ptp(r)) / (noise * math.sqrt(12)))
    clock = n * carrier_hz * cycles_per_sample(spec)
    return spec, bandwidth_hz(spec, carrier_hz), bits, clock


def main() -> int:
    for carrier in (2500.0, 10000.0):
        for n in (32, 64, 128, 256):
            spec, bw, bits, clock = effective_bits(carrier, n)
            rate = "within" if clock <= CLOCK_HZ else "beyond"
            print(f"carrier {carrier:g} Hz, N {n} ({n * carrier / 1e6:g} MS/s), window {spec.window}, bandwidth "
                  f"{bw:.0f} Hz: {bits:.1f} effective bits, {'at least' if bits >= TARGET_BITS else 'below'} "
                  f"{TARGET_BITS}; needs a {clock / 1e6:.1f} MHz clock, {rate} {CLOCK_HZ / 1e6:g} MHz", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
