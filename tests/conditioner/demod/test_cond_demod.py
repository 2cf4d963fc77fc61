"""The I/Q demodulator: the twin recovers a sampled carrier's in-phase and quadrature parts and
rejects its harmonics over whole periods; under GHDL it matches the twin."""

import math

import numpy as np
import pytest

from flann.hardware.conditioner.spec import derive_conditioner
from flann.hardware.conditioner.twin import FlannCondDemod


def test_twin_measures_amplitude_and_phase_and_rejects_harmonics():
    spec = derive_conditioner(adc_bits=16, carrier_hz=5000.0, output_rate_hz=1000.0)
    n = spec.window
    k = np.arange(n)
    phi, amp = 0.7, 20000.0
    theta = 2 * math.pi * k / spec.samples_per_period
    x = np.floor(amp * np.cos(theta + phi) + 0.3 * amp * np.cos(3 * theta + 0.2) + 0.5).astype(np.int64)
    phases = (k * spec.step) % (1 << spec.table_bits)
    d = FlannCondDemod(spec).process(x, phases, 0)
    scale = n / 2 * spec.amplitude
    # I = M/2 A amp cos(phi), Q = M/2 A amp sin(phi): the third harmonic integrates to nothing
    assert d.out_i[0] / scale == pytest.approx(amp * math.cos(phi), rel=2e-4)
    assert d.out_q[0] / scale == pytest.approx(amp * math.sin(phi), rel=2e-4)


def test_window_is_whole_periods_and_accumulator_holds_the_rails():
    spec = derive_conditioner(adc_bits=12, carrier_hz=2500.0, output_rate_hz=250.0)
    assert spec.window == 10 * 32
    rail = FlannCondDemod(spec).process([-2048] * spec.window, [0] * spec.window, 0).out_i[0]
    assert -(1 << (spec.acc_bits - 1)) <= rail < -(1 << (spec.acc_bits - 2))   # no bit to spare


@pytest.mark.sim
@pytest.mark.parametrize("options, windows", [
    (dict(adc_bits=12, carrier_hz=1000.0, sample_rate_hz=8000.0, output_rate_hz=1000.0), 60),
    (dict(adc_bits=12, carrier_hz=5000.0, output_rate_hz=1000.0), 4),
])
def test_demod_matches_twin_under_ghdl(block, tmp_path, options, windows):
    spec = derive_conditioner(**options)
    r = block(spec, "flann_cond_demod", "cond_demod_bench", tmp_path / "sim", seed=5, windows=windows)
    assert r.ok, f"{r.failed_tests} (see {tmp_path / 'sim'})"
