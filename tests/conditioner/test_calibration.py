"""The reference phase's calibration on a record's windows, the table's lag when a period holds
more samples than the table has entries, and a waveform's sample rate from its times."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from flann.hardware.conditioner.condition import calibrate_reference
from flann.hardware.conditioner.spec import derive_conditioner, identity
from flann.hardware.conditioner.twin import ConditionerChain
from flann.recordings.waveform import Waveforms

SPEC = derive_conditioner()
X = np.repeat(np.linspace(-10.0, 10.0, 41), 4)       # four windows a position


def windows(diff, total=1000.0 + 0j):
    """Demodulator sums whose A - B is ``diff`` and A + B ``total`` (per window)."""
    a, b = (total + diff) / 2, (total - diff) / 2
    return SimpleNamespace(i_a=a.real, q_a=a.imag, i_b=b.real, q_b=b.imag)


def test_a_phase_that_moves_with_the_core_is_taken_at_the_null():
    # A - B = s(x) e^{i phi(x)}: the phase turns by 0.4 deg at 10 mm, as the seed LVDT's primary
    # current does; a constant quadrature residual beside it
    phi0 = 0.3
    s = 40.0 * np.tanh(X / 8.0)
    phi = phi0 + math.radians(0.4) * (X / 10.0) ** 2
    _ref, phase = calibrate_reference(SPEC, windows(s * np.exp(1j * phi) + 2.0j), X)
    # a line through the linear part would take the phase there, about 0.1 deg off
    assert phase == pytest.approx(phi0, abs=1e-4)


def test_a_fixed_error_of_each_position_averages_over_the_positions():
    # converters too quiet to dither: a fixed error of each position, 1 % of the difference one
    # position from the null (three positions alone turn the slope by about 0.26 deg)
    rng = np.random.default_rng(7)
    err = np.repeat(rng.normal(0, 0.0025, 41) + 1j * rng.normal(0, 0.0025, 41), 4)
    phi0 = -1.2
    s = 4.0 * np.tanh(X / 8.0)
    _ref, phase = calibrate_reference(SPEC, windows(s * np.exp(1j * phi0) + err), X)
    assert abs(math.remainder(phase - phi0, 2 * math.pi)) < math.radians(0.05)


def test_without_displacements_the_phase_is_that_of_the_sum():
    _ref, phase = calibrate_reference(SPEC, windows(np.zeros(8, complex), np.full(8, 3 * np.exp(0.7j))))
    assert phase == pytest.approx(0.7)


def test_four_samples_an_entry_demodulate_a_carrier_at_its_phase_plus_the_table_lag():
    spec = derive_conditioner(carrier_hz=2500.0, sample_rate_hz=2.56e6, output_rate_hz=625.0)
    assert spec.table_lag_rad == pytest.approx(2 * math.pi * 1.5 / 1024)
    n = 4 * spec.window
    for p in (0.0, 1.0, -2.5):
        v = np.round(1500 * np.cos(2 * math.pi * np.arange(n) / 1024 + p)).astype(np.int64) + 2048
        out = ConditionerChain(spec).process(v, v, identity(spec))
        _ref, measured = calibrate_reference(spec, out)
        assert math.remainder(measured - p - spec.table_lag_rad, 2 * math.pi) == pytest.approx(0, abs=1e-4)


@pytest.mark.parametrize("digits", [9, 7])
def test_the_sample_rate_comes_from_the_record_s_whole_duration(digits):
    fs = 2.56e6                      # a 390.625 ns step: to the ns it reads as 390 or 391
    t = np.array([float(f"{v:.{digits}g}") for v in np.arange(200_000) / fs])
    w = Waveforms(time_s=t, sec_a_v=np.zeros(t.size), sec_b_v=np.zeros(t.size), displacement_mm=np.zeros(t.size))
    assert w.sample_rate_hz == pytest.approx(fs, rel=1e-6)
    # a gap of missing samples counts them
    cut = np.delete(t, np.s_[1000:1010])
    w = Waveforms(time_s=cut, sec_a_v=np.zeros(cut.size), sec_b_v=np.zeros(cut.size),
                  displacement_mm=np.zeros(cut.size))
    assert w.sample_rate_hz == pytest.approx(fs, rel=1e-6)
