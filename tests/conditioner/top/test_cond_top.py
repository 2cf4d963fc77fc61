"""The whole conditioner under GHDL: a waveform from the simulator through the chain, 0
mismatches against the twin; the top's files analyse as VHDL-93."""

import subprocess
from dataclasses import asdict

import pytest

from flann.hardware.conditioner.condition import adc_codes, calibrate_reference
from flann.hardware.conditioner.render import ENTITIES, cycles_per_sample, render
from flann.hardware.conditioner.spec import derive_conditioner, identity
from flann.hardware.conditioner.twin import ConditionerChain
from flann.physics.sensor import default_sensor
from flann.physics.waveforms import WaveformSettings, parse_trajectory, simulate_waveforms

CARRIER = 2500.0


def test_every_file_analyses_synthesises_without_latches_and_lints(tmp_path):
    files = render(derive_conditioner())
    assert list(files) == [f"{e.name}.vhd" for e in ENTITIES]
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    paths = [str(tmp_path / n) for n in files]
    r = subprocess.run(["ghdl", "-a", "--std=93c", f"--workdir={tmp_path}", *paths], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    r = subprocess.run(["ghdl", "--synth", "--std=93c", f"--workdir={tmp_path}", *paths, "-e", "flann_cond_top"],
                       capture_output=True, text=True)
    assert r.returncode == 0 and "latch" not in r.stderr.lower(), r.stderr
    from flann.implement.synth import lint_vhdl   # VSG with the repository's configuration

    assert lint_vhdl(paths) == []


@pytest.mark.sim
def test_waveform_through_the_whole_chain_matches_twin(block, tmp_path):
    spec = derive_conditioner(adc_bits=12, carrier_hz=CARRIER, output_rate_hz=CARRIER)   # one period a window
    s = default_sensor().replace(excitation_frequency_hz=CARRIER)
    wave = simulate_waveforms(s, WaveformSettings(carrier_hz=CARRIER, sample_rate_hz=32 * CARRIER, adc_bits=12,
                                                  adc_range_v=5.0, noise_v=0.002, seed=2),
                              parse_trajectory("steps:0.0008"), travel_mm=(-30.0, 30.0), step_mm=4.0)
    a, b = adc_codes(wave.sec_a_v, 12, 5.0), adc_codes(wave.sec_b_v, 12, 5.0)
    ref, _phase = calibrate_reference(spec, ConditionerChain(spec).process(a, b, identity(spec)))
    assert ref.tan != 0   # the rotation is exercised
    r = block(spec, "flann_cond_top", "cond_top_bench", tmp_path / "sim", seed=9,
              codes_a=a.tolist(), codes_b=b.tolist(), ref=asdict(ref), cycles_per_sample=cycles_per_sample(spec))
    assert r.ok, f"{r.failed_tests} (see {tmp_path / 'sim'})"
