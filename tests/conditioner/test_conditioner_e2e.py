"""A simulated waveform file through the conditioner's twin gives the simulator's demodulated
output and the float ratio of the same secondaries; it ignores the excitation's drift."""

import math

import numpy as np
import pytest

from flann.golden.metrics import full_scale_mm, raw_line
from flann.hardware.conditioner.condition import condition
from flann.hardware.conditioner.spec import derive_conditioner, reference_phase
from flann.physics.sensor import default_sensor
from flann.physics.simulate import simulate_output_v
from flann.physics.waveforms import WaveformSettings, parse_trajectory, simulate_waveforms
from flann.recordings.waveform import read_waveforms, write_waveforms

AD598_PCT_FS = 0.05
CARRIER = 2500.0
RANGE_V = 5.0


def _wave(tmp_path, name, **settings):
    s = default_sensor().replace(excitation_frequency_hz=CARRIER)
    wave = simulate_waveforms(s, WaveformSettings(carrier_hz=CARRIER, sample_rate_hz=32 * CARRIER, **settings),
                              parse_trajectory("steps:0.004"), travel_mm=(-25.0, 25.0), step_mm=5.0)
    path = tmp_path / f"{name}.csv"
    write_waveforms(path, wave)
    return s, read_waveforms(path, announce=False)


@pytest.fixture(scope="module")
def spec():
    return derive_conditioner(adc_bits=12, carrier_hz=CARRIER, output_rate_hz=500.0)


def _float_ratio(wave, spec, phase):
    k = np.arange(len(wave))
    ref = np.cos(2 * math.pi * k / spec.samples_per_period + phase)
    n = len(wave) // spec.window * spec.window
    ia = (wave.sec_a_v * ref)[:n].reshape(-1, spec.window).sum(axis=1)
    ib = (wave.sec_b_v * ref)[:n].reshape(-1, spec.window).sum(axis=1)
    return (ia - ib) / (ia + ib)


def test_chain_gives_the_dc_output_and_the_float_ratio(tmp_path, spec):
    s, wave = _wave(tmp_path, "adc", adc_bits=12, adc_range_v=RANGE_V)
    _s, exact = _wave(tmp_path, "exact", adc_bits=32, adc_range_v=20.0)
    c = condition(wave, spec, RANGE_V)
    assert c.steady.all() and not c.sat.any()
    x = c.displacement_mm
    fs = full_scale_mm(x)
    slope, _ = raw_line(c.ratio, x)
    chain_error = 100 * np.max(np.abs(slope * (c.ratio - _float_ratio(exact, spec, reference_phase(spec, c.ref))))) / fs
    dc = simulate_output_v(s, x)
    dc_error = 100 * np.max(np.abs(s.demodulator_gain_ratio * c.difference_v - dc)) / (np.ptp(dc) / 2)
    # a 12-bit converter's rounding, integrated over 160 samples: far inside the AD598's 0.05 % FS
    assert chain_error < AD598_PCT_FS / 5
    # the simulator's demodulator at its own reference phase, the chain at the calibrated one
    assert dc_error < AD598_PCT_FS


def test_excitation_drift_does_not_move_the_ratio(tmp_path):
    # 16-bit converters: a 12-bit one's rounding alone moves an undithered ratio by ~250 ppm FS
    # when the amplitude changes (bench/conditioner_linearity.py: dithered by noise it averages)
    spec = derive_conditioner(adc_bits=16, carrier_hz=CARRIER, output_rate_hz=500.0)
    _s, steady = _wave(tmp_path, "steady", adc_bits=16, adc_range_v=RANGE_V)
    _s, drift = _wave(tmp_path, "drift", adc_bits=16, adc_range_v=RANGE_V, excitation_drift_pct=10.0)
    a, b = condition(steady, spec, RANGE_V), condition(drift, spec, RANGE_V)
    slope, _ = raw_line(a.ratio, a.displacement_mm)
    moved_ppm = 1e6 * np.max(np.abs(slope * (b.ratio - a.ratio))) / full_scale_mm(a.displacement_mm)
    # the difference alone grows by up to 10 %; the ratio stays within the converter's rounding
    off_null = np.abs(a.difference_v) > 0.1
    assert np.max(np.abs(b.difference_v[off_null] / a.difference_v[off_null] - 1)) > 0.09
    assert moved_ppm < 100   # the bound for a 10 % drift: 10 ppm FS per %
