"""One twin protocol for every datapath's top-level twin: entity, latency, process -> port-named
record, all_codes, error_vs_float (checked against the float model the test computes itself)."""

from __future__ import annotations

import numpy as np
import pytest

from flann.golden.train import fit_lstsq
from flann.hardware.registry import DATAPATHS
from flann.hardware.family.spec import derive_family
from flann.hardware.fixed.spec import derive_spec
from flann.hardware.float18.spec import derive_f18_spec


@pytest.fixture(scope="module")
def model():
    v = np.linspace(-4, 4, 200)
    return fit_lstsq(v, 10 * np.tanh(v / 3), 5, norm="half")


SPECS = {
    "fixed": lambda m: derive_spec(m, input_bits=8),
    "float18": lambda m: derive_f18_spec(m, input_bits=8),
    "family": lambda m: derive_family([m], input_bits=8),
}


@pytest.mark.parametrize("name", sorted(SPECS))
def test_top_twin_protocol(model, name):
    twin = DATAPATHS[name].twin(SPECS[name](model))
    assert twin.entity == DATAPATHS[name].top
    assert isinstance(twin.latency, int) and twin.latency > 0
    codes = twin.all_codes()
    assert codes[0] == -128 and codes[-1] == 127
    out, sat = twin.process(codes)
    assert out.shape == sat.shape == codes.shape
    e = twin.error_vs_float(codes)
    assert e["codes"] == codes.size and 0 <= e["max_err_mm"] < 1.0
