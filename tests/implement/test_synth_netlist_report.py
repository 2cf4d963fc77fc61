"""flann synth reports its netlist check: the mapped netlist simulated over every input code
against the twin (with or without --model: the manifest keeps the model), in the table as
`netlist check` and in --json as netlist_check (null when it did not run)."""

import json
import shutil
from pathlib import Path

import pytest

from flann.cli import main

GOOD = Path(__file__).parent / "fixtures" / "synth" / "good"

needs_tools = pytest.mark.skipif(
    not (shutil.which("ghdl") and shutil.which("yosys") and shutil.which("verilator")),
    reason="ghdl, yosys and verilator are required (scripts/ensure_tools.sh)")


def _run(capsys, *argv):
    rc = main(["synth", *map(str, argv)])
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.mark.synth
@needs_tools
def test_passing_check_is_reported_in_json_and_text(small_synths):
    """The run's one synthesis of the small fixed design (8-bit input: 2^8 = 256 codes; no
    --model, the manifest's model is the twin's): the JSON report and the text table."""
    rc, out, err, report = small_synths("fixed")
    assert rc == 0, err
    check = report["netlist_check"]
    assert check["codes"] == 256 and check["mismatches"] == 0 and check["passed"] is True
    line = next(ln for ln in out.splitlines() if "netlist check" in ln)
    assert "256 input codes" in line and "0 mismatches" in line and line.endswith("passed")


@pytest.mark.synth
@needs_tools
def test_check_not_run_is_null_and_said(tmp_path, capsys):
    # the fixture is a hand-written design: no twin to simulate against
    rc, out, err = _run(capsys, GOOD, "--no-lint", "--abc", "fast", "--json")
    assert rc == 0, err
    assert json.loads(out)["netlist_check"] is None
    rc, out, err = _run(capsys, GOOD, "--no-lint", "--abc", "fast", "--no-netlist-check")
    assert rc == 0, err
    assert "netlist check        not run: --no-netlist-check" in out


def test_help_says_the_check_runs_without_model(capsys):
    with pytest.raises(SystemExit):
        main(["synth", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    # the old help said the netlist is simulated only when --model is given
    assert "then simulated" not in text
    assert "manifest" in text and "netlist_check" in text


def test_output_directory_on_a_spartan_ii_part_is_refused(capsys, tmp_path):
    """-o names an iCE40 bitstream's directory; on a Spartan-II part it was silently ignored
    (a 90 s synthesis later, no files): refused in one line before any tool runs."""
    rc, out, err = _run(capsys, GOOD, "--no-lint", "-o", tmp_path / "out")
    assert rc == 2 and err.strip().startswith("error: -o ") and len(err.strip().splitlines()) == 1
    assert "iCE40" in err and not (tmp_path / "out").exists()
