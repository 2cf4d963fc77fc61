"""A converter's grid printed to the export's resolution (1 µV, or 1 mV for a coarse converter)
is found: each reading carries up to half the last digit, so the step is fitted over the span,
not taken from the smallest gap; readings with analogue noise still give no grid."""

from argparse import Namespace

import numpy as np
import pytest

from flann.commands.train import converter
from flann.recordings import checks, converter_step, parse_recordings


def _codes(bits: int, full_scale_v: float, seed: int = 0, positions: int = 121):
    """A sensor read out and back through a converter of ``bits`` over +-``full_scale_v``."""
    rng = np.random.default_rng(seed)
    lsb = 2 * full_scale_v / 2 ** bits
    x = np.linspace(-3, 3, positions)
    x = np.r_[x, x[::-1]]
    u = x / 3
    v = 2.5 * (u + 0.12 * u ** 2 - 0.25 * u ** 3) + rng.normal(0, 2e-4, x.size)
    return x, np.round(v / lsb) * lsb, lsb


def _csv(x, v, header="voltage_v", fmt=".6f", scale=1.0):
    return f"displacement_mm,{header}\n" + "".join(f"{a:g},{b * scale:{fmt}}\n" for a, b in zip(x, v))


@pytest.mark.parametrize("bits, fs, header, fmt, scale", [
    (14, 5.0, "voltage_v", ".6f", 1.0),      # µV: the step 0.61 mV off by up to 0.5 µV a reading
    (14, 5.0, "voltage_mv", ".3f", 1e3),     # the same in mV
    (16, 5.0, "voltage_v", ".6f", 1.0),
    (10, 5.0, "voltage_v", ".3f", 1.0),      # 1 mV digits of a 9.8 mV step
    (16, 5.0, "voltage_v", ".9g", 1.0),      # nine significant digits: 5 nV at 5 V
])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_grid_printed_to_its_last_digit_is_found(bits, fs, header, fmt, scale, seed):
    x, v, lsb = _codes(bits, fs, seed)
    rec = parse_recordings(_csv(x, v, header, fmt, scale), source="p.csv")
    step = converter_step(rec.voltage_v)
    assert abs(step / lsb - 1) * 2 ** bits < 0.05     # within a twentieth of a code over the range
    found = converter(Namespace(input_bits=None, input_lsb_v=None), rec)
    assert found["from"] == "the recording's converter grid"
    assert found["input_bits"] == bits - 1            # the readings span half the range
    assert abs(found["input_lsb_v"] / lsb - 1) * 2 ** bits < 0.05


def test_few_positions_printed_in_microvolts():
    x, v, lsb = _codes(14, 5.0, positions=25)
    assert abs(converter_step(parse_recordings(_csv(x, v)).voltage_v) / lsb - 1) < 1e-6


@pytest.mark.parametrize("fmt", [".9g", ".6f", ".5f", ".4f", ".3f"])
@pytest.mark.parametrize("positions", [8, 13, 121])
def test_analogue_readings_printed_to_any_digit_have_no_converter_grid(fmt, positions):
    """Noise of 0.2 mV, printed: no step coarser than the printed digit (which holds them all)."""
    rng = np.random.default_rng(positions)
    x = np.linspace(-3, 3, positions)
    v = 2.5 * np.tanh(x / 2) + rng.normal(0, 2e-4, x.size)
    rec = parse_recordings(_csv(x, v, fmt=fmt))
    assert converter_step(rec.voltage_v) <= checks.printed_resolution(rec.voltage_v) * (1 + 1e-9)


def test_printed_resolution():
    assert checks.printed_resolution([0.5, 1.25, -3]) == pytest.approx(0.01)
    assert checks.printed_resolution(np.array([1.234, -0.5]) * 1e-3) == pytest.approx(1e-6)   # mV, 3 decimals
    assert checks.printed_resolution([0.1 + 1e-12, np.pi]) == 0.0


@pytest.mark.parametrize("fmt, noise", [(".6f", 1e-3), (".5f", 1e-2)])
def test_a_long_noisy_file_printed_to_fixed_decimals_is_no_converter(fmt, noise):
    """4,002 readings with 1 mV (10 mV) of noise fill every printed digit: a grid of the last digit
    at 23 (19) bits is the printing, and training judges at the generator's converters."""
    rng = np.random.default_rng(1)
    x = np.linspace(-10, 10, 2001)
    x = np.r_[x, x[::-1]]
    v = 4 * np.tanh(x / 6) + rng.normal(0, noise, x.size)
    rec = parse_recordings(_csv(x, v, fmt=fmt))
    assert converter_step(rec.voltage_v) == pytest.approx(checks.printed_resolution(rec.voltage_v))
    assert converter(Namespace(input_bits=None, input_lsb_v=None), rec) is None


def test_a_converter_of_one_millivolt_printed_to_it_is_kept():
    """A 1 mV step (13 bits on +-4.096 V), printed '%.3f': the last digit, and a converter."""
    x, v, lsb = _codes(13, 4.096)
    rec = parse_recordings(_csv(x, v, fmt=".3f"))
    found = converter(Namespace(input_bits=None, input_lsb_v=None), rec)
    assert found["input_lsb_v"] == pytest.approx(1e-3) and found["input_bits"] == 13   # +-2.2 V read


@pytest.mark.parametrize("noise", [1e-5, 3e-4])
def test_a_straight_sensor_at_even_steps_is_no_converter(noise):
    """A straight sensor read at evenly spaced positions gives evenly spaced readings, each off
    that spacing by its noise: no converter (it was taken for a 6-bit one of 25 mV), while the
    same readings quantised by a 12-bit converter are found at its step."""
    rng = np.random.default_rng(3)
    x = np.linspace(-5, 5, 41)
    v = np.round((0.1 * x + 1e-5 * x ** 3 + rng.normal(0, noise, x.size)) * 1e6) / 1e6
    assert checks.converter_of(v) is None
    lsb = 2.0 / 4096
    assert checks.converter_of(np.round(v / lsb) * lsb) == (12, pytest.approx(lsb))


@pytest.mark.parametrize("bits, amp, seed", [(16, 1.19, 1), (12, 1.19, 2), (16, 7.9, 3), (14, 0.6, 4)])
def test_a_converter_grid_printed_to_nine_digits_is_found(bits, amp, seed):
    """Readings of a converter printed '%.9g' are on its grid to the ninth digit's rounding
    (5e-9 of the reading, more than the step's share of 4e-9 first allowed: 8 of 150 sensors
    of the shared check lost their converter)."""
    rng = np.random.default_rng(seed)
    x = np.tile(np.linspace(-1, 1, 300), 2)
    lsb = 2 * amp * 1.05 / 2 ** bits
    v = np.round((amp * np.tanh(2 * x) / np.tanh(2) + rng.normal(0, 1e-3, x.size)) / lsb) * lsb
    printed = np.array([float(f"{a:.9g}") for a in v])
    assert checks.converter_of(printed) == (bits, pytest.approx(lsb, rel=1e-6))
