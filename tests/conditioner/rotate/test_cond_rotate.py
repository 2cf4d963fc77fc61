"""The fine rotation: the twin turns (I, Q) by the calibrated angle (without its cos, common to
both secondaries) within a count of the exact value and saturates at the sums' range; under
GHDL it matches the twin."""

import math

import pytest

from flann.hardware.conditioner.spec import derive_conditioner, reference, reference_phase
from flann.hardware.conditioner.twin import FlannCondRotate


def test_twin_turns_by_the_calibrated_angle():
    spec = derive_conditioner()
    step = 2 * math.pi / (1 << spec.table_bits)
    for phase in (0.3, 1.0 + 0.49 * step, -2.0 - 0.49 * step):
        ref = reference(spec, phase)
        # the registers set the phase within the rotation's step, far below the table's
        assert abs(math.remainder(reference_phase(spec, ref) - phase, 2 * math.pi)) < 2.0 ** -spec.rotation_bits
        rest = phase - 2 * math.pi * ref.offset / (1 << spec.table_bits)
        i, q = 123456789, -98765432
        got = FlannCondRotate(spec).one(i, q, ref.tan)
        assert abs(got - (i + q * math.tan(rest))) < abs(q) * 2.0 ** -spec.rotation_bits + 1


def test_twin_saturates_at_the_sums_range():
    spec = derive_conditioner()
    hi = (1 << (spec.acc_bits - 1)) - 1
    rot = FlannCondRotate(spec)
    big = (1 << (spec.tan_bits - 1)) - 1
    assert rot.one(hi, hi, big) == hi
    assert rot.one(-hi - 1, -hi - 1, big) == -hi - 1


# the default sums, and the widest a 16-bit converter over 50 carrier periods gives
@pytest.mark.sim
@pytest.mark.parametrize("adc_bits, output_rate_hz", [(12, 500.0), (16, 50.0)])
def test_rotate_matches_twin_under_ghdl(block, tmp_path, adc_bits, output_rate_hz):
    spec = derive_conditioner(adc_bits=adc_bits, carrier_hz=2500.0, output_rate_hz=output_rate_hz)
    assert block(spec, "flann_cond_rotate", "cond_rotate_bench", tmp_path / "sim", seed=5, cases=300).ok
