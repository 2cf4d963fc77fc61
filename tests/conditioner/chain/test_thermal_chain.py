"""flann_chain_top with a two-input FLANN behind the conditioner: the temperature code at each
window's last strobe is the one the window's displacement is computed at (the twin's rule,
checked from outside: changing any other strobe's code changes nothing); temperature codes are
given to a two-input chain and only to it; under GHDL the chain matches its twin with the
temperature code changing on every strobe and crossing the calibrated range's clamp."""

import numpy as np
import pytest

from flann.errors import SpecError
from flann.golden.thermal_train import fit_thermal
from flann.hardware.conditioner.chain import ChainSpec, FlannChainTop, render_chain
from flann.hardware.conditioner.condition import calibrate_reference
from flann.hardware.conditioner.render import render
from flann.hardware.conditioner.spec import derive_conditioner, identity
from flann.hardware.conditioner.twin import ConditionerChain
from flann.hardware.conditioner.verify import lvdt_codes, run_chain_top, swept_temperatures
from flann.hardware.options import GenOptions
from flann.hardware.thermal import render as thermal_render

# the one-input FLANN takes the ratio's top 16 bits: flann gen says so, as here
pytestmark = pytest.mark.filterwarnings("ignore:.*-bit ADC. the design takes its top")
# five carrier periods a window: a ratio every 160 strobes outlasts the two-input FLANN's sample
COND = dict(carrier_hz=5000.0, output_rate_hz=1000.0)
TEMPS_C = (0.0, 25.0, 50.0)


def thermal_behind(cond):
    """A two-input FLANN of an LVDT curve whose gain and null move with temperature, over the
    ratio +-0.8, taking the ratio's top 16 bits as flann gen does behind the conditioner."""
    x = np.tile(np.linspace(-25.0, 25.0, 101), len(TEMPS_C))
    t = np.repeat(TEMPS_C, 101)
    v = 0.8 * np.tanh(x / 20.0) / np.tanh(1.25) * (1 + 2e-3 * (t - 25)) + 4e-3 * (t - 25) / 25
    model = fit_thermal(v, t, x, (7, 3, 1))
    drop = cond.ratio_bits - 16
    return thermal_render.derive(model, GenOptions(input_bits=16, input_lsb_v=2.0 ** (drop - cond.ratio_frac_bits),
                                                   temp_bits=10, temp_lsb_c=0.25))


@pytest.fixture(scope="module")
def chain():
    cond = derive_conditioner(**COND)
    return ChainSpec(cond, thermal_behind(cond), thermal_render.TOP)


@pytest.fixture(scope="module")
def stimulus(chain):
    a, b, x = lvdt_codes(chain.conditioner)
    ref, _phase = calibrate_reference(chain.conditioner, ConditionerChain(chain.conditioner).process(
        a, b, identity(chain.conditioner)), x)
    return a, b, ref, swept_temperatures(chain.flann, a.size)


def test_a_window_is_computed_at_the_temperature_of_its_last_strobe(chain, stimulus):
    a, b, ref, temps = stimulus
    twin, m = FlannChainTop(chain), chain.conditioner.window
    base = twin.process(a, b, ref, temps)
    last = np.zeros(temps.size, dtype=bool)
    last[m - 1::m] = True
    rng = np.random.default_rng(7)
    # any other strobe's code, anywhere in the temperature codes: the same displacement codes
    others = np.where(last, temps, rng.integers(chain.flann.temp_code_min, chain.flann.temp_code_max + 1, temps.size))
    again = twin.process(a, b, ref, others)
    assert np.array_equal(again.out_data, base.out_data) and np.array_equal(again.out_sat, base.out_sat)
    # the last strobe's code moved from the coldest calibrated code to the hottest: every window
    # within the stroke moves (the curve's gain and null move with temperature)
    cold, hot = (np.where(last, code, temps) for code in (chain.flann.temp_lo, chain.flann.temp_hi))
    inside = ~twin.process(a, b, ref, cold).ratio_sat.astype(bool)
    assert np.all(twin.process(a, b, ref, cold).out_data[inside] != twin.process(a, b, ref, hot).out_data[inside])
    # beyond the calibrated temperatures the FLANN clamps and says so
    assert base.out_sat[(base.temp_code < chain.flann.temp_lo) | (base.temp_code > chain.flann.temp_hi)].all()


def test_temperature_codes_go_to_a_two_input_chain_and_only_there(chain, stimulus, flann_behind):
    a, b, ref, temps = stimulus
    with pytest.raises(SpecError, match="temperature"):
        FlannChainTop(chain).process(a, b, ref)
    one = ChainSpec(chain.conditioner, flann_behind(chain.conditioner))
    with pytest.raises(SpecError, match="temperature"):
        FlannChainTop(one).process(a, b, ref, temps)
    assert "in_temp" not in render_chain(one)["flann_chain_top.vhd"]


def test_the_two_input_chain_top_lints(chain, tmp_path):
    from flann.implement.synth import lint_vhdl

    (name, text), = render_chain(chain).items()
    (tmp_path / name).write_text(text)
    assert "in_temp" in text and lint_vhdl([tmp_path / name]) == []


@pytest.mark.sim
def test_two_input_chain_top_matches_twin_under_ghdl(chain, stimulus, sources, tmp_path):
    a, b, ref, temps = stimulus
    # compile order: the conditioner's, the FLANN's, the chain
    files = sources({**render(chain.conditioner), **thermal_render.render(chain.flann), **render_chain(chain)},
                    tmp_path / "hdl")
    r = run_chain_top(files, chain, a, b, ref, tmp_path / "sim", seed=5, temp_codes=temps)
    assert r.ok, f"{r.failed_tests} (see {tmp_path / 'sim'})"
    rec = r.records["cond_chain"]
    assert rec["windows"] == a.size // chain.conditioner.window and rec["mismatches"] == 0
