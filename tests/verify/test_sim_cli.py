"""`flann sim` on every datapath it runs: the plot it claims is written and says what it shows,
every weight image given is simulated, a temporary design is not reported as a path.  Each small
design is simulated once per run (``small_sims``); these tests look at that run's outputs."""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from flann.cli import main
from flann.hardware.registry import DATAPATHS
from flann.verify.plugin import bench_of, verification
from flann.verify.results import SimResult, summary as bench_summary

pytestmark = [pytest.mark.sim, pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl not installed")]

BITS = 8

SIMULATED = ["fixed", "float18", "family", "thermal", "family_thermal"]
# simulated without a curve to plot: the conditioner's outputs are ratios of a waveform's windows
UNPLOTTED = ["conditioner"]


@pytest.fixture(scope="module")
def designs(small_designs):
    """Small designs (4-5 terms, 8-bit input) of every datapath flann sim runs."""
    return small_designs


def test_every_datapath_with_a_bench_is_covered():
    assert sorted(n for n, dp in DATAPATHS.items() if verification(dp) is not None) == sorted(SIMULATED + UNPLOTTED)


def test_conditioner_blocks_and_chain_match_their_twins(small_sims):
    """Every block's bench and the closed-form waveform through the whole chain, 0 mismatches; the
    stimulus reaches the divider's saturation beyond the stroke; no plot is claimed."""
    run = small_sims("conditioner")
    s = run.summary
    assert run.rc == 0 and s["all_passed"] and s["mismatches"] == 0, run.err
    assert set(s["benches"]) == {"nco", "adc", "demod", "rotate", "ratio", "top"}
    assert all(b["tests"] >= 1 and b["failures"] == 0 for b in s["benches"].values())
    assert s["windows"] == 11 and s["codes_tested"] == 11 * 32
    assert s["saturated_windows"] >= 2   # the positions beyond the stroke, one each side
    assert "not written" in run.err and not run.png.exists()


def _is_png(path: Path) -> bool:
    return path.is_file() and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("datapath", SIMULATED)
def test_plot_is_written_for_every_datapath(small_sims, datapath):
    run = small_sims(datapath)
    s = run.summary
    assert run.rc == 0 and s["mismatches"] == 0 and s["all_passed"], run.err
    # the verdict: against the twin, and where the design states a bound, against the float model
    assert s["verdict"]["status"] == "good" and s["verdict"]["line"] in run.out
    bounded = [c for c in s["verdict"]["checks"] if c["name"] == "hdl_vs_float_bound"]
    assert len(bounded) == (datapath in ("fixed", "thermal")) and all(c["ok"] for c in bounded)
    if datapath == "family":   # its mapped netlist too, its weight image loaded through the cfg port
        assert s["netlist"]["codes_tested"] == 2 ** BITS and s["netlist"]["mismatches"] == 0
    assert _is_png(run.png) and f"plot: {run.png}" in run.out
    (axes,) = run.figures
    for ax in axes:
        for label, _x, _y in ax["lines"]:
            assert label and not label.startswith("_"), f"{datapath}: an unlabelled line in {ax['title']!r}"
    diff = axes[-1]
    curves = [(label, x, y) for label, x, y in diff["lines"] if "LSB" not in label]  # not the bound
    assert curves, f"{datapath}: no difference drawn"
    for label, x, y in curves:
        # one point per input code of the 8-bit input (each temperature code folded in)
        assert np.unique(x[np.isfinite(x)]).size == 2 ** BITS, label
    if datapath in ("family", "family_thermal"):
        # against each weight image's twin: bit for bit, so the difference is zero everywhere
        assert "twin" in diff["ylabel"]
        assert all(np.all(y == 0) for _l, _x, y in curves)
    else:
        assert "golden" in diff["ylabel"] and any(np.nanmax(np.abs(y)) > 0 for _l, _x, y in curves)
    if datapath in ("thermal", "family_thermal"):
        assert any("degC" in label for ax in axes[:-1] for label, _x, _y in ax["lines"])


@pytest.mark.parametrize("datapath", [d for d in SIMULATED if d != "family"])
def test_netlist_flag_runs_the_mapped_netlist_sweep_for_every_datapath(designs, datapath, tmp_path, capsys,
                                                                      monkeypatch):
    """--netlist is not dropped by any datapath: after the bench (stood in for here: each runs for
    real in the tests above), the design's own netlist sweep runs (stood in for too: the family's
    runs for real above, and the sweeps themselves are checked by flann synth in
    tests/hardware/test_datapath_matrix.py), and a failed sweep fails the run."""
    from flann.verify import datapaths
    calls = []

    def sweep(design, build_dir, progress=None, image=None):
        calls.append((design.datapath.name, image and Path(image["hex"]).name))
        return {"codes_tested": 256, "mismatches": 1, "simulator": "stub", "temperature_codes": None,
                "seconds": 0.0}, False

    def bench(design, build_dir, **_):
        return SimResult.from_summary(bench_summary(design, 256, 0, None, {}, True), None, design.spec)

    monkeypatch.setattr(datapaths, "netlist_summary", sweep)
    monkeypatch.setattr(datapaths, "bench_of", lambda design: dataclasses.replace(bench_of(design), bench=bench))
    d = designs["dir"] / datapath
    # a family design's netlist computes with the image given, as its bench ends
    image = json.loads((d / "manifest.json").read_text())["images"][0]["hex"] if "family" in datapath else None
    rc = main(["sim", str(d), "--json", "--netlist", "--build", str(tmp_path / "b"),
               *(["--image", str(d / image)] if image else [])])
    out, err = capsys.readouterr()
    s = json.loads(out)
    assert calls == [(datapath, image)] and s["netlist"]["mismatches"] == 1
    assert rc == 1 and not s["all_passed"] and s["mismatches"] == 0
    assert s["verdict"]["status"] == "bad" and "disagrees with its twin" in s["verdict"]["line"]
    # with --json too, stderr says why in one line (the JSON on stdout stays parseable)
    assert err.strip().splitlines()[-1] == "error: co-simulation failed (mapped netlist: 1 mismatches)", err


def test_float18_plot_draws_no_lsb_bound(small_sims):
    """The float18 design states no error bound: its difference panel (mm) has no +-1 lines."""
    run = small_sims("float18")
    assert run.rc == 0 and f"plot: {run.png}" in run.out and _is_png(run.png)
    diff = run.figures[0][-1]
    assert "(mm)" in diff["ylabel"]
    for label, _x, y in diff["lines"]:
        y = y[np.isfinite(y)]
        assert not (y.size and np.allclose(np.abs(y), 1.0)), f"a +-1 line drawn: {label}"
        assert "LSB" not in label


def test_fixed_plot_bound_line_is_labelled(small_sims):
    run = small_sims("fixed")
    assert run.rc == 0
    bounds = [(label, y) for label, _x, y in run.figures[0][-1]["lines"] if "LSB" in label]
    assert len(bounds) == 1
    assert sorted(set(bounds[0][1][np.isfinite(bounds[0][1])].tolist())) == [-1.0, 1.0]


def test_family_thermal_simulates_every_image_given(small_sims, designs):
    """Both sensors' images given, the design's last member first: each simulated, named in the
    summary and the text with its mismatches, one plot panel each, and their outputs differ."""
    run = small_sims("family_thermal")
    given = [Path(a) for a, flag in zip(run.argv[1:], run.argv) if flag == "--image"]
    kept = [designs["dir"] / "family_thermal" / im["hex"]
            for im in json.loads((designs["dir"] / "family_thermal" / "manifest.json").read_text())["images"]]
    assert len(kept) == 2 and given == kept[::-1]
    assert run.rc == 0, run.err
    s = run.summary
    names = [h.stem for h in given]
    assert s["images"] == names
    assert s["image_mismatches"] == {n: 0 for n in names}
    assert s["codes_tested"] == len(given) * 2 ** BITS * s["temperature_codes_tested"]
    # one panel per image, titled by it, and the two sensors' HDL outputs differ (both loaded)
    panels = run.figures[0][:-1]
    assert [p["title"].split(":")[0].removeprefix("(a) ").removeprefix("(b) ") for p in panels] == names
    hdl = [np.concatenate([y for label, _x, y in p["lines"] if label.startswith("HDL")]) for p in panels]
    assert not np.array_equal(hdl[0], hdl[1])
    # the text report names both, each with its mismatches
    assert all(f"{n} (0 mismatches)" in run.out for n in names)


def test_temporary_design_is_not_reported_as_a_path(designs, tmp_path, capsys, monkeypatch):
    """A model simulated without --build is generated into a temporary directory, gone when sim
    returns: neither the text nor the JSON names it.  What is simulated is beside the point here
    (every bench runs in the tests above): the benches are stood in for."""
    from flann.commands import sim as sim_command

    def bench(design, build_dir, **_):
        return SimResult.from_summary(bench_summary(design, 256, 0, None, {}, True), None, design.spec)

    monkeypatch.setattr(sim_command, "simulate", bench)
    model = str(designs["model"])
    summary = tmp_path / "s.json"     # the text and the JSON of one run
    assert main(["sim", model, "--input-bits", str(BITS), "--summary-json", str(summary)]) == 0
    assert json.loads(summary.read_text())["design"] is None
    line = next(ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("design"))
    assert "temporary" in line and "flann-sim-" not in line
    # kept with --build: the path is reported, and the design is there
    assert main(["sim", model, "--json", "--input-bits", str(BITS), "--build", str(tmp_path / "b")]) == 0
    kept = Path(json.loads(capsys.readouterr().out)["design"])
    assert kept == (tmp_path / "b" / "hdl").resolve() and (kept / "manifest.json").is_file()


@pytest.mark.parametrize("name", [n for n in SIMULATED if n not in ("fixed", "thermal")])
def test_verilator_engine_is_refused_where_it_cannot_run(designs, name, cli):
    """--engine verilator compiles the sweep driver's netlist for the one-input fixed-point and the
    thermal datapaths: another datapath is refused in one line before any simulation."""
    rc, out, err = cli(["sim", designs["dir"] / name, "--engine", "verilator"])
    assert rc == 2 and out == "" and err.startswith("error: --engine verilator") and len(err.strip().splitlines()) == 1


def test_thermal_design_every_sample_through_the_compiled_netlist(designs, tmp_path, capsys):
    """--engine verilator on a two-input design: every (voltage, temperature) code through GHDL's
    synthesised netlist under Verilator against the twin, and the VHDL itself under GHDL on a
    sample across the clamp at both ends and the middle of the temperature codes."""
    d = designs["dir"] / "thermal"
    assert main(["sim", str(d), "--engine", "verilator", "--json", "--build", str(tmp_path / "b")]) == 0
    s = json.loads(capsys.readouterr().out)
    man = json.loads((d / "manifest.json").read_text())
    temps = man["temp_clamp_codes"]
    assert s["sweep"]["engine"] == "verilator" and s["all_passed"] and s["mismatches"] == 0
    assert s["codes_tested"] == 2 ** BITS * s["temperature_codes_tested"] == 2 ** BITS * 2 ** man["temp_bits"]
    sample = s["sweep"]["vhdl_sample"]
    assert sample["bench_ok"] and sample["mismatches"] == 0 and sample["codes"] > 0
    assert s["max_err_lsb"] is not None and s["max_err_lsb"] <= man["analysis"]["pre_rounding_lsb"] + 0.5, temps


def test_throughput_is_said_to_be_at_the_nominal_clock(small_sims):
    """sim runs no timing analysis: its samples/s is at the clock the design is written for (a
    float18 design does not reach it on a Spartan-II), and both the text and the JSON say so."""
    run = small_sims("float18")
    line = next(ln for ln in run.out.splitlines() if ln.startswith("samples/s at"))
    s = run.summary
    assert s["clock_nominal"] is True and s["clock_checked_by"] == "flann synth"
    # the names outside scripts read are kept
    assert s["samples_per_s"] == s["samples_per_s_at_50mhz"] and s["clock_hz"] == 50e6
    assert line.split()[:5] == ["samples/s", "at", "50", "MHz", f"{s['samples_per_s']:.0f}"]
    assert line.endswith(" at the design's nominal clock, not a timing result (flann synth estimates the "
                         "design's Fmax)")
