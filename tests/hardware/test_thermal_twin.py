"""The two-input datapath's spec and bit-true twin: |twin - float| <= 1 output LSB over every
voltage code at every temperature code, clamping, and the option checks."""

import numpy as np
import pytest

from flann.errors import SpecError
from flann.golden.thermal_train import fit_thermal
from flann.hardware.thermal.spec import derive_thermal_spec
from flann.hardware.thermal.twin import FlannThermalTop


def sensor_v(x, temp):
    """An S-curve sensor (+-10 mm) whose gain falls 0.025 %/degC and whose null and roll-off move."""
    dt = np.asarray(temp, dtype=float) - 25.0
    k = 2.5 * (1 + 1e-4 * dt)
    u = x / 8.0
    return 1.5 * (1 - 2.5e-4 * dt) * u / (1 + np.abs(u) ** k) ** (1 / k) + 1.5 * 4e-6 * dt


@pytest.fixture(scope="module")
def model():
    x = np.tile(np.linspace(-10, 10, 41), 3)
    t = np.repeat([-20.0, 25.0, 80.0], 41)
    # every order in use, with cross terms: the Horner path and each order's datapath
    return fit_thermal(sensor_v(x, t), t, x, (9, 3, 1), norm="range")


@pytest.fixture(scope="module")
def spec(model):
    return derive_thermal_spec(model, input_bits=10, input_lsb_v=0.003, temp_bits=8, temp_lsb_c=1.0)


def test_every_voltage_code_at_every_temperature_code_within_one_lsb(spec):
    assert spec.analysis["pre_rounding_lsb"] <= 0.5
    temps = np.arange(spec.temp_code_min, spec.temp_code_max + 1)    # 256 codes, both ends
    res = FlannThermalTop(spec).error_vs_float(temps)
    assert res["codes"] == 1024 and res["temperature_codes"] == 256
    assert 0.05 < res["max_err_lsb"] <= 1.0
    # the output LSB is not vacuous: finer than 0.1 % of the 10 mm full scale
    assert spec.output_lsb_mm <= 0.01


def test_temperature_normalisation_and_clamping(spec, model):
    top = FlannThermalTop(spec)
    codes = np.array([-300, 0, 300])
    lo = top.trace(codes, spec.temp_lo)
    hi = top.trace(codes, spec.temp_hi)
    one = 1 << spec.t_frac_bits
    assert abs(int(lo.t_n[0]) + one) <= 1 and abs(int(hi.t_n[0]) - one) <= 1   # -20 / 80 degC
    below = top.process(codes, spec.temp_lo - 5)
    np.testing.assert_array_equal(below.out_data, top.process(codes, spec.temp_lo).out_data)
    assert below.out_sat.all() and not top.process(codes, spec.temp_lo).out_sat.any()
    wide = top.process([spec.clamp_hi + 10], 25)
    assert wide.out_sat[0]
    assert wide.out_data[0] == top.process([spec.clamp_hi], 25).out_data[0]


def test_options_are_checked(model):
    with pytest.raises(SpecError, match="temp"):
        derive_thermal_spec(model, input_bits=10, input_lsb_v=0.0025, temp_bits=7, temp_lsb_c=0.5)
    with pytest.raises(SpecError, match="finer than|coarser --output-lsb-mm"):
        derive_thermal_spec(model, input_bits=10, input_lsb_v=0.0025, temp_bits=8, temp_lsb_c=1.0,
                            output_lsb_mm=1e-9)
    with pytest.raises(SpecError, match="input_bits"):
        derive_thermal_spec(model, input_bits=25, input_lsb_v=0.0025, temp_bits=8, temp_lsb_c=1.0)


def test_sixteen_bit_input_interpolates_below_the_adc_step(model):
    """No finer grid than a 16-bit ADC's: the order datapaths are interpolated between codes,
    so the output LSB is finer than half an ADC step over the steepest slope."""
    spec = derive_thermal_spec(model, input_bits=16, input_lsb_v=2.0 / 32768, temp_bits=8,
                               temp_lsb_c=1.0)
    assert spec.fine_bits == 0 and spec.interp_bits > 0
    assert spec.output_lsb_mm < 0.5 * spec.analysis["slope_mm_per_v"] * spec.input_lsb_v
    res = FlannThermalTop(spec).error_vs_float([spec.temp_lo, 25, spec.temp_hi])
    assert res["codes"] == 65536 and 0.05 < res["max_err_lsb"] <= 1.0


def test_an_adc_wider_than_the_order_datapaths_keeps_its_low_bits(model):
    """An 18-bit ADC: the order datapaths' grid is 4 codes wide (fine_bits -2) and the two low
    bits reach them through the interpolation fraction; every code within 1 output LSB of the
    float model, and finer than the same ADC cut to 16 bits could give."""
    lsb = 2.0 / (1 << 17)
    spec = derive_thermal_spec(model, input_bits=18, input_lsb_v=lsb, temp_bits=8, temp_lsb_c=1.0)
    assert spec.fine_bits == -2 and spec.interp_bits >= 2
    top = FlannThermalTop(spec)
    res = top.error_vs_float([spec.temp_lo, 25, spec.temp_hi])
    assert res["codes"] == 1 << 18 and res["max_err_lsb"] <= 1.0
    # where a code moves the output by more than an LSB, neighbouring codes give distinct
    # outputs (cut to 16 bits, every 4 codes would share one)
    c = np.arange(40000, 40400)
    out = top.process(c, 25).out_data
    assert np.ptp(out) > c.size and np.unique(out).size > c.size // 2
