"""Every command on every datapath's design directory: it works, or refuses in one line naming why;
and a tampered manifest is refused in one line naming the field (exit 2), whatever the command."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

from pathlib import Path

import pytest

from flann.implement.synth import lint_vhdl
from flann.verify.runner import simulator_name, throughput

REPO = Path(__file__).resolve().parents[2]
BITS = "8"


@pytest.fixture(scope="module")
def designs(small_designs):
    """Small designs (4-5 terms, 8-bit input) of every datapath flann gen writes
    (``small_designs``), the seed architecture, a design flann did not write, and held-out
    recordings of the two-input sensor."""
    d, held = small_designs["dir"], small_designs["held_thermal"]
    return {"dir": d, "model": small_designs["model"], "rec": small_designs["rec"],
            # the family's initial image is its first member, the sensor the held-out recording is of
            "eval": {"thermal": (small_designs["thermal"], held),
                     "family_thermal": (d / "family_thermal" / "init_model.json", held)}}


def one_line_refusal(r) -> None:
    """Exit 2, one `error:` line, the last on stderr (progress lines such as synth's may precede it)."""
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    errors = [ln for ln in lines if ln.startswith("error: ")]
    assert r.returncode == 2 and len(errors) == 1 and lines[-1] == errors[0], r.stderr
    assert "Traceback" not in r.stderr


# command -> argument list for a design directory (the designs keep their model)
COMMANDS = {
    "sim": lambda d, fx: ("sim", d),
    "trace": lambda d, fx: ("trace", d),
    "eval": lambda d, fx: ("eval", *fx["eval"].get(d.name, (fx["model"], fx["rec"])), "--design", d),
    "ise": lambda d, fx: ("ise", d, "-o", fx["dir"] / f"ise_{d.name}"),
    # lint on; the mapped netlist checked where a bench drives it; the synthesis ise's timing check
    # then takes from the cache (abc -fast for the seed: its parallel multipliers are wide)
    "synth": lambda d, fx: ("synth", d, *(("--abc", "fast") if d.name == "seed" else ())),
    # one lane: the fixed design's two multiplier styles; the float18 design's one (it has no --mult)
    "explore": lambda d, fx: ("explore", d, "--lanes", 1, "--widths", "budget", "--no-seed"),
}
# (datapath, command) that refuse, with a word the one line must hold
REFUSED = {("family", "explore"): "members",
           **{("seed", c): "comparison design" for c in ("sim", "trace", "eval", "explore", "ise")},
           ("thermal", "explore"): "two-input",
           ("family_thermal", "explore"): "members",
           **{("conditioner", c): "written from a spec" for c in ("trace", "eval", "explore", "ise")},
           # 5 parallel constant multipliers of the seed's wide words: more LUT4 than the largest part
           ("seed", "synth"): "does not fit"}


@pytest.mark.sim
@pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl not installed")
@pytest.mark.parametrize("datapath", ["fixed", "float18", "family", "seed", "thermal", "family_thermal",
                                      "conditioner"])
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_command_on_datapath(designs, datapath, command, small_sims, small_synths, flann):
    why = REFUSED.get((datapath, command))
    if command == "sim" and not why:
        # each design's one simulation of the run (tests/verify/test_sim_cli.py looks at its outputs)
        run = small_sims(datapath)
        assert run.rc == 0 and run.summary["all_passed"], run.err
        return
    if command == "synth" and not why:
        # each design's one synthesis of the run (tests/verify/test_netlist_split.py looks at its report)
        r = subprocess.CompletedProcess(["flann", "synth"], *small_synths(datapath)[:3])
    else:
        if command == "ise" and not why:
            small_synths(datapath)   # ise's timing check then takes that synthesis from the cache
        r = flann(*COMMANDS[command](designs["dir"] / datapath, designs))
    if why:
        one_line_refusal(r)
        assert why in r.stderr
    else:
        assert r.returncode == 0, r.stderr
    if command == "synth" and not why and datapath != "conditioner":   # every top flann gen writes has a netlist sweep
        assert "0 mismatches with the twin: passed" in r.stdout, r.stdout
    if command == "ise" and not why:
        # the README's wiring step names the ports the datapath adds to the common interface
        extra = (json.loads((designs["dir"] / datapath / "manifest.json").read_text()).get("cfg_port") or {})
        readme = (designs["dir"] / f"ise_{datapath}" / "README.txt").read_text()
        for name in extra.get("ports", {}):
            assert name in readme.split("This design adds", 1)[-1].split("\n", 1)[0], (name, readme)


@pytest.mark.sim
@pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl not installed")
def test_explore_float18_dir_explores_its_own_widths(designs, flann):
    """A float18 design explores the float18 design (its term widths), not the fixed rows; the
    budget row is the design in the directory (its cycles and its trace's error)."""
    d = designs["dir"] / "float18"
    r = flann("explore", d, "--widths", "budget,narrow", "--no-seed", "--json")
    assert r.returncode == 0, r.stderr
    rows = json.loads(r.stdout)
    assert [(x["lanes"], x["mult_style"], x["widths"]) for x in rows] == [(1, "float18", "budget"),
                                                                           (1, "float18", "narrow")]
    man = json.loads((d / "manifest.json").read_text())
    tr = json.loads(flann("trace", d, "--json").stdout)
    assert rows[0]["cycles_per_sample"] == man["cycles_per_sample"]
    assert rows[0]["max_err_mm"] == pytest.approx(tr["total"]["max_mm"], rel=1e-9)
    assert all(x["luts"] and x["fits"] is not None for x in rows)
    for args, word in ((("--mult", "lut"), "multiplier style"), (("--lanes", "1,2"), "one lane")):
        one_line_refusal(r := flann("explore", d, *args, "--no-seed"))
        assert word in r.stderr


def test_eval_family_thermal_design_by_temperature(designs, flann):
    """eval --design of a family design with temperature: the hardware judged at held-out
    temperatures (10 and 65 degC, between and beside the calibration ones) like a thermal design,
    on the design's initial image, and within one output LSB of the float model at the same codes."""
    d = designs["dir"] / "family_thermal"
    model, held = designs["eval"]["family_thermal"]
    r = flann("eval", model, held, "--design", d, "--json")
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    hw, man = res["hardware"], json.loads((d / "manifest.json").read_text())
    assert [b["temperature_c"] for b in hw["by_temperature"]] == [10.0, 65.0]
    assert sum(b["points"] for b in hw["by_temperature"]) == res["points"] == 78
    assert hw["max_error_mm"] == pytest.approx(max(b["max_error_mm"] for b in hw["by_temperature"]))
    assert set(res["drift_ppm_fs_per_c"]) == {"raw", "float", "hardware"}
    assert all(v is not None and v >= 0 for v in res["drift_ppm_fs_per_c"].values())
    assert (hw["temp_bits"], hw["temp_lsb_c"]) == (4, 12.0)
    assert "initial image" in hw["weight_image"] and man["images"][0]["hex"] in hw["weight_image"]
    # the datapath's own error, at the codes the design saw: the error analysis' bound (1 LSB)
    assert hw["max_abs_hardware_minus_float_at_codes_mm"] <= man["output_lsb_mm"] * man["analysis"]["bound_lsb"]
    # a one-input model is not what the design computes
    one_line_refusal(r := flann("eval", designs["model"], held, "--design", d))
    assert "one-input model" in r.stderr


def test_ise_refuses_a_part_too_small(designs, flann):
    r = flann("ise", designs["dir"] / "fixed", "--device", "xc2s15-vq100-5", "-o", designs["dir"] / "ise_small")
    one_line_refusal(r)
    assert "smallest Spartan-II that fits: xc2s" in r.stderr
    assert not (designs["dir"] / "ise_small").exists()
    r = flann("ise", designs["dir"] / "fixed", "--device", "xc2s15-vq100-5", "--force", "-o",
              designs["dir"] / "ise_small")
    # written, and said once why the part will not hold it
    assert r.returncode == 0 and (designs["dir"] / "ise_small").is_dir(), r.stderr
    said = [ln for ln in r.stderr.splitlines() if ln.startswith(("warning:", "error:"))]
    assert len(said) == 1 and said[0].startswith("warning:") and "does not fit xc2s15-vq100-5" in said[0]
    assert "written anyway (--force)" in said[0]


def test_ise_refuses_a_part_the_synthesized_design_does_not_fit(designs, flann):
    """A datapath with no estimate before synthesis (family_thermal): the timing check's netlist decides."""
    out = designs["dir"] / "ise_ft_small"
    r = flann("ise", designs["dir"] / "family_thermal", "--device", "xc2s15-vq100-5", "-o", out)
    one_line_refusal(r)
    assert "does not fit xc2s15-vq100-5" in r.stderr and "synthesized" in r.stderr
    assert not out.exists()


def test_gen_says_it_replaces_a_design(designs, tmp_path, flann):
    out = tmp_path / "d"
    assert flann("gen", designs["model"], "-o", out, "--input-bits", BITS).returncode == 0
    r = flann("gen", designs["model"], "-o", out, "--input-bits", BITS, "--format", "float18")
    assert r.returncode == 0 and "replaced the flann design" in r.stderr
    assert sorted(p.name for p in out.iterdir()) == sorted(
        json.loads((out / "manifest.json").read_text())["files"] + ["manifest.json", "model.json"])


def _drop(path):
    def edit(m):
        *parents, last = path.split(".")
        for p in parents:
            m = m[p]
        del m[last]
    return edit


def _set(path, value):
    def edit(m):
        *parents, last = path.split(".")
        for p in parents:
            m = m[p]
        m[last] = value
    return edit


# (datapath, edit, the field the one line must name)
TAMPERED = [
    ("family", _drop("family.widths.weight_bits"), "family.widths.weight_bits"),
    ("family", _set("family.widths.weight_bits", "22"), "family.widths.weight_bits"),
    ("family", _set("family.members", 5), "family.members"),
    ("fixed", _set("spec", "x"), "'spec'"),
    ("plain", _set("spec", "x"), "'spec'"),
    ("plain", _set("input_bits", "12"), "input_bits"),
    ("fixed", _set("input_bits", True), "input_bits"),
    ("float18", _drop("output.frac_bits"), "output.frac_bits"),
    ("fixed", _set("datapath", "quantum"), "datapath"),
    ("thermal", _drop("spec.temp_bits"), "spec.temp_bits"),
    ("thermal", _set("temp_lsb_c", "0.5"), "temp_lsb_c"),
    ("family_thermal", _drop("spec.temperature"), "spec.temperature"),
]
TAMPER_COMMANDS = {
    "sim": lambda d, fx: ("sim", d),
    "trace": lambda d, fx: ("trace", d),
    "eval": lambda d, fx: ("eval", *fx["eval"].get(d.name, (fx["model"], fx["rec"])), "--design", d),
    "synth": lambda d, fx: ("synth", d, "--no-netlist-check"),
    "ise": lambda d, fx: ("ise", d, "-o", d.parent / f"ise_{d.name}"),
}


@pytest.mark.parametrize("command", sorted(TAMPER_COMMANDS))
@pytest.mark.parametrize("datapath,edit,field", TAMPERED, ids=[f"{t[0]}-{t[2]}-{k}" for k, t in enumerate(TAMPERED)])
def test_tampered_manifest(designs, tmp_path, command, datapath, edit, field, flann):
    d = tmp_path / datapath
    shutil.copytree(designs["dir"] / datapath, d)
    man = json.loads((d / "manifest.json").read_text())
    edit(man)
    (d / "manifest.json").write_text(json.dumps(man))
    r = flann(*TAMPER_COMMANDS[command](d, designs))
    one_line_refusal(r)
    assert field in r.stderr


@pytest.mark.skipif(shutil.which("vsg") is None and not (Path(sys.executable).parent / "vsg").exists(),
                    reason="vsg not installed")
@pytest.mark.parametrize("datapath", ["fixed", "float18", "family", "thermal", "family_thermal"])
def test_generated_vhdl_passes_vsg(designs, datapath):
    files = sorted((designs["dir"] / datapath).glob("*.vhd"))
    assert files and lint_vhdl(files, start=REPO) == []


def test_plot_legend_and_throughput_name_what_ran():
    assert simulator_name({"engine": "verilator"}).startswith("Verilator")
    assert simulator_name({"engine": "ghdl", "backend": "ghdl-llvm"}) == "GHDL, llvm"
    t = throughput(100, clock_hz=25e6)
    assert t == {"clock_hz": 25e6, "samples_per_s": 250000.0, "samples_per_s_at_50mhz": 250000.0}
