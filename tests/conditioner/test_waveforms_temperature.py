"""The conditioner with temperature compensation, as a user runs it: waveforms of a calibration at
several temperatures (flann simulate --waveforms --temperatures), a two-input model trained on
the conditioner's ratio and the temperature (flann train --temperature), the chain written with
its temperature port (flann gen), and its drift judged on waveforms held out at temperatures
it was not trained at (flann eval --design)."""

import json

import numpy as np
import pytest

from flann.golden.thermal import ThermalModel, load_any_model
from flann.hardware.conditioner.settings import of_model
from flann.recordings.waveform import read_waveforms

SENSOR = "paper_lvdt_thermal.toml"   # its ratio drifts: the core's permeability, the balance


def simulate(in_process, data_dir, out, temperatures: str, seed: int):
    rc, _out, err = in_process(["simulate", data_dir / "sensors" / SENSOR, "--waveforms", "-o", out,
                                "--carrier-hz", 2500, "--sample-rate-hz", 80000, "--adc-bits", 12,
                                "--adc-range-v", 2, "--from-mm", -25, "--to-mm", 25, "--step-mm", 2.5,
                                "--trajectory", "steps:0.004", "--noise-v", 0.0002, "--seed", seed,
                                "--temperatures", temperatures])
    assert rc == 0, err
    return out


@pytest.fixture(scope="module")
def chain(tmp_path_factory, in_process, data_dir):
    d = tmp_path_factory.mktemp("wave_temperature")
    wave = simulate(in_process, data_dir, d / "wave.csv", "0,25,50", seed=1)
    # the expansion set (the structure search is the demodulated path's, tested there)
    rc, _out, err = in_process(["train", wave, "--temperature", "--terms", 11, "-o", d / "model.json"])
    assert rc == 0, err
    # words fine enough to resolve the drift's change over the held-out temperatures
    rc, _out, err = in_process(["gen", d / "model.json", "-o", d / "design", "--output-lsb-mm", 0.001])
    assert rc == 0, err
    return d


def test_the_record_holds_each_soak_and_the_model_keeps_its_conditioner(chain):
    wave = read_waveforms(chain / "wave.csv")
    assert sorted(set(wave.temperature_c.tolist())) == [0.0, 25.0, 50.0]
    model = load_any_model(chain / "model.json")
    assert isinstance(model, ThermalModel) and list(model.temperature_range_c) == [0.0, 50.0]
    assert of_model(model).carrier_hz == pytest.approx(2500.0, rel=1e-3)


def test_gen_joins_the_conditioner_to_a_two_input_flann_with_a_temperature_port(chain):
    man = json.loads((chain / "design" / "manifest.json").read_text())
    assert man["top"] == "flann_chain_top" and man["flann"]["datapath"] == "thermal"
    assert man["chain"]["flann_temp_bits"] == man["flann"]["temp_bits"]
    assert man["cfg_port"]["ports"]["in_temp"]["width"] == man["flann"]["temp_bits"]
    top = (chain / "design" / "flann_chain_top.vhd").read_text()
    assert "in_temp   : in  std_logic_vector" in top and "in_temp   => window_temp" in top


def test_eval_judges_the_drift_at_held_out_temperatures(chain, in_process, data_dir):
    held = simulate(in_process, data_dir, chain / "held.csv", "10,40", seed=2)
    rc, out, err = in_process(["eval", chain / "model.json", held, "--design", chain / "design", "--json"])
    assert rc == 0, err
    res = json.loads(out)
    drift = res["drift_ppm_fs_per_c"]
    # the ratio alone drifts (its gain and null move with the core); the compensated chain a
    # fraction of it, in float and in the design's words (within one output LSB over the span)
    assert drift["float"] < drift["raw"] / 2
    lsb_drift = 1e6 * man_lsb(chain) / res["full_scale_mm"] / 30.0
    assert drift["hardware"] <= drift["float"] + lsb_drift
    temps = [r["temperature_c"] for r in res["compensated"]["by_temperature"]]
    assert temps == [10.0, 40.0] and res["linearity_pct_fs"]["hardware"] is not None
    assert np.isfinite(res["excitation_rejection_ppm_fs_per_pct"]["value"])
    # the design's drift is judged against the float chain's, as a demodulated design's is
    judged = {c["name"]: c["ok"] for c in res["verdict"]["checks"]}
    assert judged["hardware_vs_float_drift"] is True


def test_a_drifting_temperature_column_keeps_its_dwells(in_process, data_dir, tmp_path):
    # a slow ramp over the record (0.25 degC a window) is a drift, not a soak's step: every
    # steady window is kept, one reading a dwell, as without a temperature column
    rc, _out, err = in_process(["simulate", data_dir / "sensors" / SENSOR, "--waveforms", "-o", tmp_path / "ramp.csv",
                                "--carrier-hz", 2500, "--sample-rate-hz", 80000, "--adc-bits", 12,
                                "--adc-range-v", 2, "--from-mm", -25, "--to-mm", 25, "--step-mm", 5,
                                "--trajectory", "steps:0.004", "--temperature-profile", "ramp:20:45"])
    assert rc == 0, err
    rc, _out, err = in_process(["train", tmp_path / "ramp.csv", "--terms", 7, "-o", tmp_path / "m.json"])
    assert rc == 0, err
    assert "11 positions, 21 dwells" in err and "(0 left out" in err


def man_lsb(chain) -> float:
    return json.loads((chain / "design" / "manifest.json").read_text())["output_lsb_mm"]
