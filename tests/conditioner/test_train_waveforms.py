"""flann train on a waveform recording: the conditioner calibrated on the record (carrier,
converters, reference phase), its ratio averaged per dwell as the readings, the settings kept in
model.json and read back through one typed object."""

import json
import math

import pytest

from flann.golden.model import load_model
from flann.errors import FlannError
from flann.hardware.conditioner.settings import ConditionerSettings, of_model
from flann.physics.lvdt import reference_phase_rad
from flann.physics.sensor import load_sensor

CARRIER = 2500.0
RATE = 32 * CARRIER


def simulate(in_process, data_dir, out, *extra, seed=1, carrier=CARRIER, rate=RATE):
    rc, _out, err = in_process(["simulate", data_dir / "sensors" / "paper_lvdt.toml", "--waveforms", "-o", out,
                                "--carrier-hz", carrier, "--sample-rate-hz", rate, "--adc-bits", 12,
                                "--adc-range-v", 5, "--from-mm", -25, "--to-mm", 25, "--step-mm", 5,
                                "--trajectory", "steps:0.004", "--noise-v", 0.0005, "--seed", seed, *extra])
    assert rc == 0, err
    return out


@pytest.fixture(scope="module")
def trained(tmp_path_factory, in_process, data_dir):
    d = tmp_path_factory.mktemp("train_wave")
    wave = simulate(in_process, data_dir, d / "wave.csv")
    # a few terms: the fit is the DC path's own, tested there; --terms auto takes seconds more
    rc, out, err = in_process(["train", wave, "-o", d / "model.json", "--adc-bits", 12, "--adc-range-v", 5,
                               "--terms", 9])
    assert rc == 0, err
    return d, err


def test_train_finds_the_carrier_and_the_phase_and_keeps_the_conditioner(trained, data_dir):
    d, err = trained
    model = load_model(d / "model.json")
    settings = of_model(model)
    # what the simulator was told, found again from the samples
    assert settings.carrier_hz == CARRIER and settings.sample_rate_hz == RATE
    assert settings.spec.samples_per_period == 32 and settings.spec.periods_per_output == 5
    assert (settings.adc_bits, settings.adc_range_v) == (12, 5.0)
    # the detector's reference the simulator demodulates at: the phase of A - B's slope at the null
    sensor = load_sensor(data_dir / "sensors" / "paper_lvdt.toml").replace(excitation_frequency_hz=CARRIER)
    assert abs(math.degrees(settings.phase_rad - reference_phase_rad(sensor))) < 0.2
    # the model's input is the ratio, a fraction of one: its trained range inside (-1, 1)
    lo, hi = model.voltage_range_v
    assert -1 < lo < -0.5 and 0.5 < hi < 1
    line = next(s for s in err.splitlines() if "waveforms:" in s)
    for said in ("carrier 2500 Hz", "32 samples per period", "at 500 Hz", "11 positions"):
        assert said in line
    assert "verdict: GOOD" in err


def test_the_settings_round_trip_and_an_edited_width_is_refused(trained):
    d, _err = trained
    raw = json.loads((d / "model.json").read_text())["conditioner"]
    settings = ConditionerSettings.from_dict(raw)
    assert settings.to_dict() == raw
    edited = {**raw, "spec": {**raw["spec"], "ratio_frac_bits": raw["spec"]["ratio_frac_bits"] + 1}}
    with pytest.raises(FlannError, match="'spec' differs"):
        ConditionerSettings.from_dict(edited)
    with pytest.raises(FlannError, match="'carrier_hz' must be a number"):
        ConditionerSettings.from_dict({**raw, "carrier_hz": "fast"})


def test_a_rate_not_a_power_of_two_per_period_is_refused(tmp_path, in_process, data_dir):
    wave = simulate(in_process, data_dir, tmp_path / "w.csv", carrier=CARRIER, rate=30 * CARRIER)
    rc, _out, err = in_process(["train", wave, "-o", tmp_path / "m.json"])
    assert rc == 2 and err.count("\n") == 1 and "power of two" in err
    assert not (tmp_path / "m.json").exists()


def test_waveform_flags_on_demodulated_readings_are_refused(tmp_path, in_process, table1_csv):
    rc, _out, err = in_process(["train", table1_csv, "-o", tmp_path / "m.json", "--output-rate-hz", 250])
    assert rc == 2 and "--output-rate-hz" in err and "demodulated" in err
