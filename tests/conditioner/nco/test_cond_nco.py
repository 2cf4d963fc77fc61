"""The excitation NCO under GHDL against its twin; the twin against the float cosine."""

import numpy as np
import pytest

from flann.hardware.conditioner.spec import derive_conditioner
from flann.hardware.conditioner.twin import FlannCondNco


def test_dac_word_is_the_rounded_cosine_and_the_bit_density_follows_it():
    spec = derive_conditioner(carrier_hz=1000.0, sample_rate_hz=8000.0, table_bits=6, sine_bits=8)
    out = FlannCondNco(spec).process([1] * 64)
    k = out.out_phase
    np.testing.assert_array_equal(out.out_dac, np.floor(127 * np.cos(2 * np.pi * k / 64) + 0.5))
    # held at one word, the bit's mean over 256 clocks is the word over full scale
    held = FlannCondNco(spec).process([1] + [0] * 4096)
    dens = held.out_sd[2:].mean()
    assert dens == pytest.approx((127 + 128) / 256, abs=1 / 256)


@pytest.mark.sim
@pytest.mark.parametrize("options, cycles, entries", [
    (dict(carrier_hz=100.0, sample_rate_hz=25600.0, output_rate_hz=100.0), 1200, 256),     # step 1: every entry
    (dict(carrier_hz=100.0, sample_rate_hz=102400.0, output_rate_hz=100.0, table_bits=10), 4200, 1024),
    (dict(carrier_hz=5000.0), 1500, 32),                                                   # the default carrier
    (dict(carrier_hz=100.0, sample_rate_hz=102400.0, output_rate_hz=100.0), 2600, 256),    # 4 samples an entry
])
def test_nco_matches_twin_under_ghdl(block, tmp_path, options, cycles, entries):
    spec = derive_conditioner(**options)
    r = block(spec, "flann_cond_nco", "cond_nco_bench", tmp_path / "sim", seed=3, cycles=cycles, p_en=0.6,
              entries=entries)
    assert r.ok, f"{r.failed_tests} (see {tmp_path / 'sim'})"
