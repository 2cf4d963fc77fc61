"""flann synth says each warning once, from one list: what it prints on stderr is what its JSON's
"warnings" holds; its table names the smallest device that fits as the JSON does.  The report
is built by hand (no GHDL/Yosys): the figures here are the test's, not a synthesis's."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from flann.commands import synth as synth_cmd
from flann.hardware.target import parse_part
from flann.implement import ice40
from flann.implement.synth import Resources, SynthReport
from flann.implement.timing import Timing

FIX = Path(__file__).parent / "fixtures" / "synth" / "good"
PART = "xc2s200-pq208-5"


def _report(delay_ns: float, yosys=("a yosys warning",)) -> SynthReport:
    # 100 LUT4 and 10 pins fit every PQ208 part; the XC2S15 comes in no PQ208
    res = Resources(luts=100, ffs=50, brams=1, carry=0, xorcy=0, mult_and=0, muxf5=0, muxf6=0, io=10)
    t = Timing("5", delay_ns=delay_ns, logic_levels=9, carry_bits=0, routed_nets=9, start="a", end="b")
    return SynthReport(parse_part(PART), "flann_top", res, tuple(yosys), {}, timing=t)


@pytest.fixture
def synth_cli(cli, monkeypatch, tmp_path):
    """flann synth on a copy of the fixture with ``report`` standing in for the synthesis."""
    design = tmp_path / "d"
    shutil.copytree(FIX, design)

    def run(report, *flags):
        monkeypatch.setattr(synth_cmd.synth, "synthesize", lambda *a, **k: report)
        return cli(["synth", design, "--no-lint", "--no-netlist-check", *flags])
    return run


def _printed(err: str) -> list[str]:
    return [ln[len("warning: "):] for ln in err.splitlines() if ln.startswith("warning: ")]


@pytest.mark.parametrize("flags", [["--json"], []])
def test_every_printed_warning_is_in_the_json(synth_cli, flags):
    slow = _report(delay_ns=40.0)   # 25 MHz, below the 50 MHz clock
    rc, out, err = synth_cli(slow, *flags)
    assert rc == 0, err
    printed = _printed(err)
    assert printed == slow.to_dict()["warnings"]
    assert printed[0] == "yosys: a yosys warning"
    assert "estimated at 25.0 MHz" in printed[1] and "below the design's clock 50 MHz" in printed[1]
    if flags:
        rep = json.loads(out)
        assert rep["warnings"] == printed and rep["yosys_warnings"] == ["a yosys warning"]
        assert rep["timing"]["meets_clock"] is False


def test_a_design_meeting_its_clock_has_no_timing_warning(synth_cli):
    rc, out, err = synth_cli(_report(delay_ns=10.0, yosys=()), "--json")
    assert rc == 0 and _printed(err) == [] and json.loads(out)["warnings"] == []


def test_table_names_the_smallest_device_as_the_json_does(synth_cli):
    report = _report(delay_ns=10.0, yosys=())
    rc, out, err = synth_cli(report)
    assert rc == 0, err
    assert report.to_dict()["smallest_device"] == "xc2s30-pq208-5"
    assert f"  fits {PART}; smallest device that fits: xc2s30-pq208-5" in out.splitlines()


def test_ice40_timing_warning_is_in_its_json():
    rep = ice40.Ice40Report(part=ice40.parse_ice40("ice40-hx8k-ct256"), top="flann_top", cells={}, logic_cells=1,
                            brams=0, io=1, fmax_mhz=20.0, clock_mhz=50.0, output="o", seconds=1.0)
    (w,) = rep.to_dict()["warnings"]
    assert "Fmax 20.0 MHz is below the design's clock 50 MHz" in w
