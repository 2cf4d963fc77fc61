"""flann gen of a two-input model: the thermal datapath's directory (VHDL compiling under GHDL
--std=93c, each order the fixed datapath's entities under its own prefix, a flat in_temp port),
its manifest read back through the registry, the option checks, and the twin protocol."""

from __future__ import annotations

import json
import re
import shutil
import subprocess

import numpy as np
import pytest

from flann.golden.thermal_train import fit_thermal
from flann.hardware.fixed.render import ENTITIES
from flann.hardware.registry import DATAPATHS, read_design
from flann.hardware.thermal.twin import FlannThermalTop
from flann.verify.datapaths import simulate
from flann.verify.shards import cores
from flann.hardware.thermal.verify import THERMAL_MAX_SAMPLES, temperature_codes as thermal_temperature_codes
from flann.hardware.design import from_directory

from test_thermal_twin import sensor_v



@pytest.fixture(scope="module")
def design(tmp_path_factory, flann):
    d = tmp_path_factory.mktemp("thermal")
    x, t = np.tile(np.linspace(-10, 10, 41), 3), np.repeat([-20.0, 25.0, 80.0], 41)
    model = d / "m.json"
    model.write_text(fit_thermal(sensor_v(x, t), t, x, (5, 3), norm="range").to_json())
    r = flann("gen", model, "-o", d / "hdl", "--input-bits", 8, "--temp-bits", 5, "--temp-lsb-c", 6)
    assert r.returncode == 0, r.stderr
    return {"dir": d / "hdl", "model": model, "out": r.stdout}


def test_directory_and_manifest(design):
    man, dp = read_design(design["dir"])
    assert dp is DATAPATHS["thermal"] and man["top"] == "flann_thermal_top" == dp.top
    assert man["temp_bits"] == 5 and man["temp_lsb_c"] == 6.0 and man["input_bits"] == 8
    assert man["temp_clamp_codes"] == [-3, 13]          # -20 / 6 rounded up, 80 / 6 rounded down
    assert "(thermal, top flann_thermal_top)" in design["out"]
    files = man["files"]
    assert files[-1] == "flann_thermal_top.vhd"
    orders = len(man["spec"]["orders"])
    # every order is the fixed datapath's set of entities, renamed; nothing else
    names = {re.match(r"flann_t(\d+)_(\w+)\.vhd$", f).groups() for f in files[:-1]}
    assert names == {(str(j), e.short) for j in range(orders) for e in ENTITIES}
    for f in files[:-1]:
        text = (design["dir"] / f).read_text()
        declared = re.findall(r"^entity (\w+) is", text, re.M)
        assert len(declared) == 1 and declared[0] == f[:-4]
        assert not re.search(r"\bflann_(norm|expansion|multiplier|adder|seq|top)\b", text)
    top = (design["dir"] / "flann_thermal_top.vhd").read_text()
    assert re.search(r"in_temp\s+: in\s+std_logic_vector\(4 downto 0\)", top)
    assert top.count("entity work.flann_t") == orders


@pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl not installed")
def test_vhdl_compiles_under_ghdl_93c(design, tmp_path):
    man = json.loads((design["dir"] / "manifest.json").read_text())
    r = subprocess.run(["ghdl", "-a", "--std=93c", f"--workdir={tmp_path}",
                        *[str(design["dir"] / f) for f in man["files"]]], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    r = subprocess.run(["ghdl", "-e", "--std=93c", f"--workdir={tmp_path}", "-o", str(tmp_path / "top"),
                        "flann_thermal_top"], capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr


def test_regenerating_gives_identical_bytes(design, tmp_path, flann):
    r = flann("gen", design["model"], "-o", tmp_path / "again", "--input-bits", 8, "--temp-bits", 5,
              "--temp-lsb-c", 6)
    assert r.returncode == 0, r.stderr
    for f in design["dir"].iterdir():
        assert (tmp_path / "again" / f.name).read_bytes() == f.read_bytes(), f.name


def test_rebuilt_twin_follows_the_protocol(design):
    d = from_directory(design["dir"])
    twin = d.twin()
    assert twin.entity == "flann_thermal_top" and twin.latency == d.manifest["latency_cycles"] > 0
    codes = twin.all_codes()
    assert codes[0] == -128 and codes[-1] == 127
    rec = twin.process(codes, d.spec.temp_hi)
    assert rec.out_data.shape == rec.out_sat.shape == codes.shape
    e = twin.error_vs_float()
    assert e["temperature_codes"] == 32 and e["codes"] == 256 and 0 < e["max_err_lsb"] <= 1.0
    # the float model, computed here, at one code: the twin within one output LSB
    m, s = d.spec.model, d.spec
    ref = m.predict(np.array([50 * s.input_lsb_v]), np.array([4 * s.temp_lsb_c]))[0]
    assert abs(twin.process([50], 4).out_data[0] * s.output_lsb_mm - ref) <= s.output_lsb_mm


def test_sweep_covers_every_temperature_code_or_a_stated_set_with_both_ends(design):
    spec = from_directory(design["dir"]).spec
    temps, every = thermal_temperature_codes(spec)
    assert every and temps == list(range(-16, 16))
    wide = type("S", (), dict(temp_code_min=-2048, temp_code_max=2047, temp_lo=-320, temp_hi=1280,
                              code_min=-32768, code_max=32767))()
    temps, every = thermal_temperature_codes(wide)
    assert not every and 4096 * 65536 > THERMAL_MAX_SAMPLES
    assert {-2048, 2047, -320, 1280} <= set(temps) and len(temps) == 17


@pytest.mark.sim
@pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl not installed")
def test_an_order_of_near_zero_weights_agrees_with_its_twin(tmp_path, flann):
    """An order whose weights are all far below an output LSB (order 2 here is about 3.5e-6 v_n):
    its fixed datapath once wrapped in the linear accumulator and lost the adder's rounding half,
    so the VHDL disagreed with the twin. Every voltage code at every temperature code."""
    x, t = np.tile(np.linspace(-10, 10, 41), 3), np.repeat([-20.0, 25.0, 80.0], 41)
    m = fit_thermal(sensor_v(x, t), t, x, (5, 3, 1), norm="range")
    assert max(abs(w) for w in (*m.weights[2], m.bias[2])) < 1e-4
    (tmp_path / "m.json").write_text(m.to_json())
    r = flann("gen", tmp_path / "m.json", "-o", tmp_path / "d", "--input-bits", 8, "--temp-bits", 3,
              "--temp-lsb-c", 30)
    assert r.returncode == 0, r.stderr
    r = flann("sim", tmp_path / "d", "--json", "--build", tmp_path / "b")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["codes_tested"] == 256 * 8 and out["mismatches"] == 0


@pytest.mark.sim
@pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl not installed")
def test_an_eighteen_bit_input_agrees_with_its_twin(design, tmp_path, flann):
    """An ADC wider than the order datapaths (18 bits: their grid is 4 codes, the low bits go
    through the interpolation fraction): HDL and twin bit for bit over the codes around the top
    of the calibrated range (the steepest slope, and clamped codes beyond it), the stated temperature codes."""
    r = flann("gen", design["model"], "-o", tmp_path / "d", "--input-bits", 18, "--temp-bits", 3,
              "--temp-lsb-c", 30)
    assert r.returncode == 0, r.stderr
    d = from_directory(tmp_path / "d")
    assert d.spec.fine_bits == -2
    hi = d.spec.clamp_hi
    out = simulate(d, tmp_path / "b", codes=(hi - 150, hi + 50))
    temps, _ = thermal_temperature_codes(d.spec)
    assert {d.spec.temp_code_min, d.spec.temp_code_max} <= set(temps)
    assert out.summary["mismatches"] == 0 and out.summary["codes_tested"] == 201 * len(temps), out.summary


def test_eval_design_gives_the_hardware_figures_per_temperature(design, tmp_path, flann):
    """flann eval --design of a two-input design: the twin at the recordings' codes, by temperature
    and the drift figure; the codes computed here (nearest code of each reading) give the same
    max error per temperature."""
    x = np.tile(np.linspace(-9.5, 9.5, 77), 3)
    t = np.repeat([-10.0, 40.0, 65.0], 77)
    v = sensor_v(x, t)
    rec = tmp_path / "held.csv"
    rec.write_text("displacement_mm,voltage_v,temperature_c\n"
                   + "".join(f"{a:.17g},{b:.17g},{c:g}\n" for a, b, c in zip(x, v, t)))
    r = flann("eval", design["model"], rec, "--design", design["dir"], "--json")
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    hw = res["hardware"]
    assert "by_temperature" not in res and set(res["drift_ppm_fs_per_c"]) == {"raw", "float", "hardware"}
    assert res["drift_ppm_fs_per_c"]["hardware"] > 0
    assert [row["temperature_c"] for row in hw["by_temperature"]] == [-10.0, 40.0, 65.0]
    assert hw["temp_bits"] == 5 and hw["temp_lsb_c"] == 6.0
    d = from_directory(design["dir"])
    s = d.spec
    codes = np.clip(np.floor(v / s.input_lsb_v + 0.5), s.code_min, s.code_max).astype(np.int64)
    tcodes = np.floor(t / 6.0 + 0.5).astype(np.int64)
    err = d.twin().process(codes, tcodes).out_data * s.output_lsb_mm - x
    for k, row in enumerate(hw["by_temperature"]):
        assert row["max_error_mm"] == pytest.approx(np.abs(err[77 * k:77 * (k + 1)]).max(), abs=1e-12)
        assert row["points"] == 77
    r = flann("eval", design["model"], rec, "--design", design["dir"])
    assert r.returncode == 0 and "5-bit temperature x 6 degC" in r.stdout and ", hardware " in r.stdout
    # another two-input model than the design's, and a one-input model: one line each
    other = tmp_path / "other.json"
    xc, tc = np.tile(np.linspace(-10, 10, 41), 3), np.repeat([-20.0, 25.0, 80.0], 41)
    other.write_text(fit_thermal(sensor_v(xc, tc), tc, xc, (3, 1), norm="range").to_json())
    r = flann("eval", other, rec, "--design", design["dir"])
    assert r.returncode == 2 and "generated from another model" in r.stderr and len(r.stderr.splitlines()) == 1


def test_trace_design_splits_the_error_into_its_stages(design, tmp_path, flann):
    """flann trace DIR of a two-input design: the stages add up to the whole error, which is the
    twin against the float model at the same codes, and each stage stays within its bound from
    the spec's error analysis."""
    r = flann("trace", design["dir"], "--json", "--plot", tmp_path / "t.png")
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["format"] == "thermal" and (tmp_path / "t.png").stat().st_size > 0
    assert res["identity_residual_mm"] < 1e-9
    s = from_directory(design["dir"]).spec
    temps = res["temperature_codes"]
    assert temps[0] == s.temp_lo and temps[-1] == s.temp_hi
    c = np.arange(s.clamp_lo, s.clamp_hi + 1)
    worst = max(np.abs(FlannThermalTop(s).process(c, tau).out_data * s.output_lsb_mm - s.float_reference(c, tau)).max()
                for tau in temps)
    assert res["total"]["max_mm"] == pytest.approx(worst, abs=1e-12) and worst <= s.output_lsb_mm
    for name, st in res["stages"].items():
        assert st["max_mm"] <= st["bound_mm"] * (1 + 1e-9) + 1e-15, name
    r = flann("trace", design["dir"])
    assert r.returncode == 0 and "dominant stage" in r.stdout


@pytest.mark.parametrize("args,word", [
    (("--temp-bits", 1), "--temp-bits"),
    (("--temp-bits", 17), "--temp-bits"),
    (("--temp-lsb-c", -1), "--temp-lsb-c"),
    (("--temp-bits", 5, "--temp-lsb-c", 1), "not the calibrated -20..80 degC"),
    (("--format", "float18"), "fixed point only"),
])
def test_bad_options_are_one_line(design, tmp_path, args, word, flann):
    out = tmp_path / "bad"
    r = flann("gen", design["model"], "-o", out, "--input-bits", 8, *args)
    assert r.returncode == 2 and r.stderr.startswith("error: ") and len(r.stderr.splitlines()) == 1, r.stderr
    assert word in r.stderr and not out.exists()


def test_synth_reads_a_two_level_hierarchy_stat():
    """Yosys 0.23 writes hierarchy text lines into `stat -json` for a top of tops."""
    from flann.eda import _stat_json

    text = ('{\n   "modules": {\n   },\n       flann_t0_adder                1\n       flann_t1_seq   1\n'
            '      "design": {\n         "num_cells_by_type": {\n            "LUT4": 12\n         }\n      }\n}\n')
    assert json.loads(_stat_json(text))["design"]["num_cells_by_type"] == {"LUT4": 12}


@pytest.mark.sim
@pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl not installed")
def test_the_sweep_runs_in_shards_of_temperature_codes_and_a_fault_in_one_fails_the_whole(design, tmp_path):
    """25 voltage codes at every temperature code through shards of whole temperature codes, one
    per core, progress to the last sample; then the same design with its upper temperature clamp one code
    low: only the last shard's codes differ from the twin, and the joined result fails."""
    seen, codes = [], (-12, 12)        # the steep middle of the 8-bit range, at every temperature code
    n = (codes[1] - codes[0] + 1) * 32
    out = simulate(from_directory(design["dir"]), tmp_path / "b", codes=codes,
                   progress=lambda label: (lambda done, total, secs: seen.append((label, done, total))))
    s = out.summary
    assert s["all_passed"] and s["mismatches"] == 0 and s["codes_tested"] == n, s
    assert s["sweep"]["shards"] == min(cores(), 32)
    assert seen[-1] == ("sweep", n, n)
    assert out.curve is not None
    bad = tmp_path / "bad"
    shutil.copytree(design["dir"], bad)
    top = bad / "flann_thermal_top.vhd"
    hi = from_directory(design["dir"]).spec.temp_code_max
    text = top.read_text()
    line = next(ln for ln in text.splitlines() if "constant temp_hi_c" in ln)
    assert line.endswith('"01101";')                          # 13, the fixture's upper clamp code
    top.write_text(text.replace(line, line.replace('"01101"', '"01100"')))
    s = simulate(from_directory(bad), tmp_path / "b2", codes=codes).summary
    assert not s["all_passed"] and s["codes_tested"] == n
    assert 0 < s["mismatches"] <= n // 32 * (hi - 12), s
