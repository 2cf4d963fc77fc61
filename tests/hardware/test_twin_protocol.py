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
from flann.numeric.float18 import FLOAT18


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


def _block_twins(model):
    """(twin, inputs of process) of every block: the fixed datapath's, float18's converter and arithmetic."""
    from flann.hardware.fixed.twin import FlannAdder, FlannExpansion, FlannMultiplier, FlannNorm
    from flann.hardware.float18.spec import FlannF18Cvt
    from flann.numeric.float18 import FlannF18Add, FlannF18Mul

    s = derive_spec(model, input_bits=8)
    codes = np.arange(-128, 128)
    n = FlannNorm(s).process(codes)
    e = FlannExpansion(s).process(n.out_theta)
    p = FlannMultiplier(s).process(e.out_terms)
    one = FLOAT18.encode_array([1.5] * 4)
    return [(FlannNorm(s), (codes,), "out_theta"), (FlannExpansion(s), (n.out_theta,), "out_terms"),
            (FlannMultiplier(s), (e.out_terms,), "out_products"),
            (FlannAdder(s), (n.out_lin, p.out_products, n.out_sat), "out_data"),
            (FlannF18Cvt(s.term_fmt.frac_bits), (np.arange(-8, 8),), "out_y"),
            (FlannF18Mul(), (one, one), "out_y"), (FlannF18Add(), (one, one), "out_y")]


def test_block_twin_protocol(model):
    for twin, inputs, port in _block_twins(model):
        assert twin.entity.startswith("flann_"), twin
        assert isinstance(twin.latency, int) and twin.latency > 0, twin.entity
        rec = twin.process(*inputs)
        assert getattr(rec, port) is not None, (twin.entity, port)
