"""The conditioner's spec: widths from its range analysis, the user's rates checked against the
carrier; the design directory it writes and the manifest its datapath record reads back."""

import json

import numpy as np
import pytest

from flann.errors import FlannError, SpecError
from flann.hardware.conditioner.datapath import DATAPATH, rebuild, write_conditioner
from flann.hardware.conditioner.spec import bandwidth_hz, derive_conditioner, output_rate_hz


def test_accumulator_holds_the_largest_window_and_no_more():
    s = derive_conditioner(adc_bits=12, carrier_hz=2500.0, output_rate_hz=250.0)
    bound = s.window * 2048 * s.amplitude
    assert -(1 << (s.acc_bits - 1)) <= -bound and bound <= (1 << (s.acc_bits - 1)) - 1
    assert bound > (1 << (s.acc_bits - 2))


def test_output_rate_is_whole_periods_and_bandwidth_follows():
    s = derive_conditioner(carrier_hz=10000.0, output_rate_hz=250.0)
    assert s.periods_per_output == 40 and output_rate_hz(s, 10000.0) == 250.0
    assert bandwidth_hz(s, 10000.0) == pytest.approx(110.7, abs=0.1)


def test_a_period_of_more_samples_than_table_entries_reads_each_entry_in_turn():
    """N = 1024 samples a period on a 256-entry table: the phase accumulator has 10 bits and
    each entry serves four consecutive samples, k * 256 / 1024 rounded down."""
    s = derive_conditioner(carrier_hz=2500.0, sample_rate_hz=2.56e6, output_rate_hz=625.0, table_bits=8)
    assert (s.phase_bits, s.step) == (10, 1)
    k = np.arange(3 * 1024)
    np.testing.assert_array_equal(s.phases(k.size), (k % 1024) * 256 // 1024)
    # a table at least N long: the accumulator is the table's address, as before
    t = derive_conditioner(carrier_hz=2500.0, sample_rate_hz=80000.0, table_bits=8)
    assert (t.phase_bits, t.step) == (8, 8)
    np.testing.assert_array_equal(t.phases(64), (np.arange(64) * 8) % 256)


@pytest.mark.parametrize("kw, words", [
    (dict(carrier_hz=5000.0, sample_rate_hz=200000.0), "power of two"),
    (dict(carrier_hz=5000.0, output_rate_hz=6000.0), "at most the carrier"),
    (dict(carrier_hz=5000.0, sample_rate_hz=20000.0), "at least 8"),
    (dict(table_bits=1), "2..16"),
    (dict(carrier_hz=10.0, sample_rate_hz=10.0 * 2 ** 17, output_rate_hz=10.0), "at most 65536 samples a period"),
    (dict(carrier_hz=20000.0, output_rate_hz=0.5, adc_bits=24, sine_bits=18), "accumulator"),
])
def test_bad_choices_are_refused_naming_the_option(kw, words):
    with pytest.raises(SpecError, match=words):
        derive_conditioner(**kw)


def test_design_directory_and_its_manifest(tmp_path, default_model_json):
    s = derive_conditioner()
    man = write_conditioner(s, tmp_path / "d", adc_range_v=5.0)
    on_disk = json.loads((tmp_path / "d" / "manifest.json").read_text())
    assert on_disk == man and sorted(p.name for p in (tmp_path / "d").iterdir()) == sorted(man["files"] + ["manifest.json"])
    DATAPATH.check(on_disk, "d")
    assert rebuild(None, on_disk)[0] == s
    on_disk["output_bits"] += 1
    with pytest.raises(FlannError, match="output_bits"):
        rebuild(None, on_disk, "d")
    with pytest.raises(FlannError, match="has no conditioner"):
        DATAPATH.generate(default_model_json, tmp_path / "e")
