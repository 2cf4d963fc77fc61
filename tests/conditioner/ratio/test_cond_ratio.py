"""The serial divider: the twin is (A - B) / (A + B) truncated to F bits, saturating beyond one;
under GHDL it matches the twin on boundary and random pairs."""

from fractions import Fraction

import pytest

from flann.hardware.conditioner.spec import derive_conditioner
from flann.hardware.conditioner.twin import FlannCondRatio


def test_twin_is_the_exact_quotient_truncated():
    spec = derive_conditioner()
    f = spec.ratio_frac_bits
    a, b = [1000, 300, 7, 123456, 10, 0, -3], [200, 900, 7, 1, 0, 10, 1]
    out = FlannCondRatio(spec).process(a, b)
    for ia, ib, q, sat in zip(a, b, out.out_ratio, out.out_sat):
        if ia + ib <= 0:
            assert (q, sat) == (0, 1)
        elif abs(ia - ib) >= ia + ib:
            assert abs(q) == (1 << f) - 1 and sat == 1
        else:
            exact = Fraction(ia - ib, ia + ib) * (1 << f)
            assert sat == 0 and abs(exact - q) < 1 and abs(q) <= abs(exact)


@pytest.mark.sim
@pytest.mark.parametrize("options", [dict(), dict(adc_bits=16, carrier_hz=2500.0, output_rate_hz=250.0)])
def test_ratio_matches_twin_under_ghdl(block, tmp_path, options):
    spec = derive_conditioner(**options)
    r = block(spec, "flann_cond_ratio", "cond_ratio_bench", tmp_path / "sim", seed=7, pairs=400)
    assert r.ok, f"{r.failed_tests} (see {tmp_path / 'sim'})"
