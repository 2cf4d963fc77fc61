"""flann_chain_top: the conditioner and the FLANN behind it in one entity.  The twin wires the
ratio's top bits into the FLANN and never wraps; a FLANN slower than the ratio is refused; under
GHDL the chain matches its twin on a waveform through the divider's saturation, at its latency."""

import numpy as np
import pytest

from flann.errors import SpecError
from flann.hardware.conditioner.chain import CHAIN_TOP, ChainSpec, FlannChainTop, render_chain
from flann.hardware.conditioner.condition import calibrate_reference
from flann.hardware.conditioner.render import render
from flann.hardware.conditioner.spec import derive_conditioner, identity
from flann.hardware.conditioner.twin import ConditionerChain
from flann.hardware.conditioner.verify import lvdt_codes, run_chain_top
from flann.hardware.fixed import render as fixed_render

# the FLANN behind the conditioner takes the ratio's top 16 bits: flann gen says so, as here
pytestmark = pytest.mark.filterwarnings("ignore:.*-bit ADC. the design takes its top")
# one carrier period a window: the shortest run (32 strobes a ratio)
COND = dict(carrier_hz=5000.0, output_rate_hz=5000.0)


@pytest.fixture(scope="module")
def chain(flann_behind):
    cond = derive_conditioner(**COND)
    return ChainSpec(cond, flann_behind(cond))


@pytest.fixture(scope="module")
def stimulus(chain):
    a, b, x = lvdt_codes(chain.conditioner)
    ref, _phase = calibrate_reference(chain.conditioner, ConditionerChain(chain.conditioner).process(
        a, b, identity(chain.conditioner)), x)
    return a, b, ref, x


def test_the_flann_takes_the_ratios_top_bits_and_nothing_wraps(chain, stimulus):
    a, b, ref, x = stimulus
    out = FlannChainTop(chain).process(a, b, ref)
    assert chain.dropped == chain.conditioner.ratio_bits - 16 > 0
    # the low bits are not wired: a floor, not a rounding, of the ratio in the FLANN's codes
    assert [int(c) for c in out.flann_code] == [int(r) // 2 ** chain.dropped for r in out.ratio]
    # beyond the stroke the divider saturates and says so; the displacement code follows the
    # position monotonically through the clamp and the saturation (nothing wraps)
    assert out.ratio_sat[x > 1].all() and out.ratio_sat[x < -1].all() and out.out_sat[np.abs(x) > 1].all()
    assert np.all(np.diff(out.out_data) >= 0) and out.out_data[0] < 0 < out.out_data[-1]
    assert not out.out_sat[np.abs(x) < 0.5].any()


def test_a_flann_slower_than_the_ratio_is_refused(flann_behind):
    # 8 strobes of 9 clocks a ratio
    cond = derive_conditioner(adc_bits=4, carrier_hz=5000.0, sample_rate_hz=40000.0, output_rate_hz=5000.0)
    with pytest.raises(SpecError, match="--output-rate-hz"):
        ChainSpec(cond, flann_behind(cond))


def test_the_chain_top_lints(chain, tmp_path):
    from flann.implement.synth import lint_vhdl   # VSG with the repository's configuration

    (name, text), = render_chain(chain).items()
    (tmp_path / name).write_text(text)
    assert lint_vhdl([tmp_path / name]) == []


@pytest.mark.sim
def test_chain_top_matches_twin_under_ghdl(chain, stimulus, sources, tmp_path):
    a, b, ref, _x = stimulus
    # compile order: the conditioner's, the FLANN's, the chain
    files = sources({**render(chain.conditioner), **fixed_render.render(chain.flann), **render_chain(chain)},
                    tmp_path / "hdl")
    r = run_chain_top(files, chain, a, b, ref, tmp_path / "sim", seed=3)
    assert r.ok, f"{r.failed_tests} (see {tmp_path / 'sim'})"
    rec = r.records["cond_chain"]
    assert rec["windows"] == len(_x) and rec["mismatches"] == 0 and rec["saturated"] >= 2
    # a window the divider saturates on comes out earlier (no division)
    assert rec["latency_cycles"] == sorted({chain.latency, chain.latency - chain.conditioner.ratio_frac_bits - 1})
    assert files[-1].name == f"{CHAIN_TOP}.vhd"
