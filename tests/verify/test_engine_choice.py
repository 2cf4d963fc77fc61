"""flann sim --engine auto: the exhaustive RTL run when it is short, the compiled netlist when not."""

from types import SimpleNamespace

import pytest

from flann.errors import FlannError
from flann.verify import runner


def design(bits, cycles):
    return SimpleNamespace(manifest={"input_bits": bits, "cycles_per_sample": cycles})


@pytest.fixture
def two_cores(monkeypatch):
    monkeypatch.setattr(runner, "cores", lambda: 2)


def test_auto_keeps_the_rtl_sweep_for_the_default_design(two_cores, monkeypatch):
    monkeypatch.setattr(runner.shutil, "which", lambda name: f"/usr/bin/{name}")
    assert runner.choose_engine(design(12, 611)) == "ghdl"
    assert runner.choose_engine(design(14, 667)) == "ghdl"  # 5.5 M cycles per core


def test_auto_compiles_the_netlist_for_a_16_bit_design(two_cores, monkeypatch):
    monkeypatch.setattr(runner.shutil, "which", lambda name: f"/usr/bin/{name}")
    assert runner.choose_engine(design(16, 723)) == "verilator"


def test_auto_without_verilator_stays_on_ghdl(two_cores, monkeypatch):
    monkeypatch.setattr(runner.shutil, "which", lambda name: None)
    assert runner.choose_engine(design(16, 723)) == "ghdl"


def test_explicit_engine_is_kept_and_unknown_refused(two_cores):
    assert runner.choose_engine(design(16, 723), "ghdl") == "ghdl"
    assert runner.choose_engine(design(8, 100), "verilator") == "verilator"
    with pytest.raises(FlannError):
        runner.choose_engine(design(12, 611), "icarus")
