"""The ADC input port under GHDL: every code of the converter against the twin."""

import pytest

from flann.hardware.conditioner.spec import derive_conditioner
from flann.hardware.conditioner.twin import FlannCondAdc


def test_port_maps_straight_binary_to_twos_complement():
    spec = derive_conditioner(adc_bits=12)
    assert list(FlannCondAdc(spec).process([0, 2047, 2048, 4095]).out_sample) == [-2048, -1, 0, 2047]


@pytest.mark.sim
@pytest.mark.parametrize("bits", [12, 16])
def test_adc_port_matches_twin_for_every_code(block, tmp_path, bits):
    spec = derive_conditioner(adc_bits=bits)
    r = block(spec, "flann_cond_adc", "cond_adc_bench", tmp_path / "sim", seed=bits)
    assert r.ok, f"{r.failed_tests} (see {tmp_path / 'sim'})"
