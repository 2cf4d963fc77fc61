"""`flann diagnose wave.csv`: waveforms tell apart what a DC curve confounds.

Each waveform is simulated by `flann simulate --waveforms` from the seed paper's LVDT with one
effect switched on in its sensor file (sizes and truths written here, not read from the code),
4 mV rms noise on each secondary, nine positions over +-20 mm forward and back, 3 ms dwells.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
PAPER = REPO / "data" / "sensors" / "paper_lvdt.toml"

# case -> (sensor [effects] text, extra simulate options, the effects diagnose must name)
CASES = {
    "clean": ("", [], set()),
    "imbalance": ("[effects.secondary_imbalance]\nimbalance_fraction = 0.02\n", [], {"secondary_imbalance"}),
    "zero_shift": ("[effects.zero_shift]\nshift_mm = 0.5\n", [], {"zero_shift"}),
    "quadrature": ("[effects.quadrature_null]\nquadrature_v = 0.05\n", [], {"quadrature_null"}),
    # loaded secondaries turn the secondaries' phase against the excitation
    "phase": ("[effects.secondary_loading]\nload_ohm = 10000\n", [], {"phase_shift"}),
    "drift": ("", ["--excitation-drift-pct", "10"], {"excitation_drift"}),
}


def _sensor_text(effects: str) -> str:
    text = PAPER.read_text()
    head = text.split("[effects", 1)[0]
    return head + "\n" + effects


@pytest.fixture(scope="module")
def waves(tmp_path_factory, flann):
    """case -> (waveform CSV, diagnose --json object, its stdout report)."""
    root = tmp_path_factory.mktemp("waves")
    out = {}
    for name, (effects, extra, _want) in CASES.items():
        toml = root / f"{name}.toml"
        toml.write_text(_sensor_text(effects))
        wave = root / f"{name}.csv"
        r = flann("simulate", toml, "--waveforms", "-o", wave, "--from-mm", "-20", "--to-mm", "20",
                  "--step-mm", "5", "--trajectory", "steps:0.003", "--noise-v", "0.004", *extra)
        assert r.returncode == 0, r.stderr
        js = root / f"{name}.json"
        r = flann("diagnose", wave, "--sensor", toml, "--json", js)
        assert r.returncode == 0, r.stderr
        text = flann("diagnose", wave, "--sensor", toml)
        assert text.returncode == 0, text.stderr
        out[name] = (wave, json.loads(js.read_text()), text.stdout)
    return out


def _named(obj) -> set[str]:
    return {e["name"] for e in obj["effects"]}


@pytest.mark.parametrize("case", list(CASES))
def test_each_effect_is_named_alone(waves, case):
    _wave, obj, _text = waves[case]
    assert obj["kind"] == "waveform"
    assert _named(obj) == CASES[case][2]


@pytest.mark.parametrize("case", [c for c in CASES if c != "clean"])
def test_each_effect_carries_its_evidence(waves, case):
    obj = waves[case][1]
    (effect,) = obj["effects"]
    assert effect["evidence"], "an effect is named with the figure that found it"
    for ev in effect["evidence"]:
        assert ev["found"] and abs(ev["value"]) > ev["threshold"] > 0


def test_imbalance_moves_the_crossing_but_is_not_a_shift(waves):
    """The confound of the DC curve: an imbalance moves the point where A = B off zero, by more
    than a shift the waveform fit would detect, yet the fit gives it to the imbalance."""
    obj = waves["imbalance"][1]
    shift = next(e for e in obj["evidence"] if e["effect"] == "zero_shift")
    assert abs(obj["null_mm"]) > shift["threshold"]
    e = obj["effects"][0]["params"]["imbalance_fraction"]
    assert e["value"] == pytest.approx(0.02, rel=0.05)


def test_figures_agree_with_the_concealed_sizes(waves):
    shift = waves["zero_shift"][1]["effects"][0]["params"]["shift_mm"]["value"]
    assert shift == pytest.approx(0.5, rel=0.1)
    quad = waves["quadrature"][1]["effects"][0]["params"]["quadrature_v"]["value"]
    assert quad == pytest.approx(0.05, rel=0.05)
    drift = waves["drift"][1]["effects"][0]["params"]["drift_pct"]["value"]
    assert drift == pytest.approx(10.0, rel=0.02)


def test_the_ratio_cancels_the_excitation_drift(waves):
    ev = {e["figure"]: e for e in waves["drift"][1]["evidence"] if e["effect"] == "excitation_drift"}
    diff = ev["A - B change over the run"]
    ratio = ev["ratio (A - B)/(A + B) change over the run"]
    assert diff["found"] and diff["value"] == pytest.approx(10.0, rel=0.02)
    assert not ratio["found"]


def test_the_demodulator_offset_is_said_to_be_absent_from_waveforms(waves):
    obj, text = waves["clean"][1], waves["clean"][2]
    assert any(n["name"] == "null_offset" for n in obj["not_in_waveforms"])
    assert "null_offset" in text and "effects: none" in text


def test_without_excitation_the_quadrature_is_still_found_and_the_phase_is_not_computable(waves, tmp_path, flann):
    wave = waves["quadrature"][0]
    lines = wave.read_text().splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("time_s"))
    cols = lines[at].split(",")
    k = cols.index("exc_v")
    lines = lines[:at] + [",".join(c for j, c in enumerate(row.split(",")) if j != k) for row in lines[at:]]
    bare = tmp_path / "bare.csv"
    bare.write_text("\n".join(lines) + "\n")
    js = tmp_path / "bare.json"
    r = flann("diagnose", bare, "--json", js)
    assert r.returncode == 0, r.stderr
    obj = json.loads(js.read_text())
    assert _named(obj) == {"quadrature_null"}
    phase = next(e for e in obj["evidence"] if e["effect"] == "phase_shift")
    assert phase["value"] is None and phase["not_computable"]


def test_without_a_sensor_description_the_phase_is_not_judged(waves, tmp_path, flann):
    js = tmp_path / "phase.json"
    r = flann("diagnose", waves["phase"][0], "--json", js)
    assert r.returncode == 0, r.stderr
    obj = json.loads(js.read_text())
    assert _named(obj) == set()
    phase = next(e for e in obj["evidence"] if e["effect"] == "phase_shift")
    assert phase["value"] is None and "--sensor" in phase["not_computable"]


def test_plot_is_written(waves, tmp_path, flann):
    png = tmp_path / "q.png"
    r = flann("diagnose", waves["quadrature"][0], "--plot", png, "--quiet")
    assert r.returncode == 0, r.stderr
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_a_waveform_without_dwells_is_one_line_exit_2(tmp_path, flann):
    wave = tmp_path / "ramp.csv"
    r = flann("simulate", PAPER, "--waveforms", "-o", wave, "--trajectory", "ramp:0.01")
    assert r.returncode == 0, r.stderr
    js = tmp_path / "ramp.json"
    r = flann("diagnose", wave, "--json", js)
    assert r.returncode == 2
    assert r.stderr.startswith("error: ") and len(r.stderr.strip().splitlines()) == 1
    assert not js.exists()
