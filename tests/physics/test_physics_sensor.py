"""Sensor TOML files: the defaults, round trips, and bad files -> one line, exit 2."""

import subprocess
import sys
from pathlib import Path

import pytest

from flann.cli import main
from flann.errors import SensorError
from flann.physics.sensor import (
    default_sensor, format_sensor, load_sensor, parse_sensor,
)

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "data" / "sensors" / "paper_lvdt.toml"


def test_default_is_the_paper_lvdt_file():
    s = load_sensor(PAPER)
    assert s == default_sensor()
    # what the paper gives
    assert (s.core_inner_diameter_mm, s.core_outer_diameter_mm, s.core_length_mm) == (4.4, 5.0, 60.0)
    assert (s.primary_turns, s.secondary_turns) == (1500, 3300)
    assert (s.excitation_frequency_hz, s.excitation_amplitude_vpp) == (5000.0, 10.0)
    assert s.effects == {}


@pytest.mark.parametrize("path", sorted((ROOT / "data" / "sensors").glob("*.toml")))
def test_example_files_load_and_round_trip(path):
    s = load_sensor(path)
    assert parse_sensor(format_sensor(s)) == s


def test_replace_validates_and_keeps_original():
    s = default_sensor()
    t = s.replace(secondary_gap_mm=5.0)
    assert t.secondary_gap_mm == 5.0 and s.secondary_gap_mm != 5.0
    with pytest.raises(SensorError, match="core.length_mm"):
        s.replace(core_length_mm=-1.0)
    with pytest.raises(SensorError, match="unknown field"):
        s.replace(core_lenght_mm=1.0)


def test_effects_are_read_only_and_filled_with_defaults():
    s = parse_sensor(PAPER.read_text() + "\n[effects.thermal_drift]\ncoefficient_per_c = -0.003\n")
    assert dict(s.effects["thermal_drift"]) == {"coefficient_per_c": -0.003,
                                                "reference_temperature_c": 20.0}
    with pytest.raises(TypeError):
        s.effects["thermal_drift"]["coefficient_per_c"] = 1.0


def _edit(text, old, new):
    assert old in text
    return text.replace(old, new, 1)


BASE = PAPER.read_text()
BAD = {
    "unknown_key": (_edit(BASE, "length_mm = 60.0", "length_mm = 60.0\ncolour_mm = 3.0"),
                    "unknown key core.colour_mm"),
    "missing_unit": (_edit(BASE, "length_mm = 60.0", "length = 60.0"), "core.length: key has no unit"),
    "negative_length": (_edit(BASE, "length_mm = 60.0", "length_mm = -60.0"), "core.length_mm = -60"),
    "zero_core": (_edit(BASE, "length_mm = 60.0", "length_mm = 0.0"), "core.length_mm = 0"),
    "missing_key": (_edit(BASE, "length_mm = 60.0\n", ""), "missing key core.length_mm"),
    "id_over_od": (_edit(BASE, "inner_diameter_mm = 4.4", "inner_diameter_mm = 5.5"),
                   "core.inner_diameter_mm = 5.5 must be <"),
    "core_wider_than_bore": (_edit(BASE, "outer_diameter_mm = 5.0", "outer_diameter_mm = 6.5"),
                             "must fit the bore"),
    "bad_demod": (_edit(BASE, 'kind = "phase_sensitive"', 'kind = "lock_in"'), "demodulator.kind"),
    "string_number": (_edit(BASE, "turns = 1500", 'turns = "1500"'), "primary.turns must be a number"),
    "unknown_effect": (BASE + "\n[effects.gremlins]\nsize_mm = 1.0\n", "unknown effect 'gremlins'"),
    "effect_param_range": (BASE + "\n[effects.backlash]\ndeadband_mm = -0.1\n",
                           "effects.backlash.deadband_mm = -0.1 out of range"),
    "effect_param_unit": (BASE + "\n[effects.backlash]\ndeadband = 0.1\n", "no unit suffix"),
    "effect_unknown_param": (BASE + "\n[effects.backlash]\nwidth_mm = 0.1\n", "unknown parameter"),
    "not_toml": ("this is = = not toml", "not valid TOML"),
    "missing_table": (BASE.split("[excitation]")[0], "missing table [excitation]"),
    "unknown_table": (BASE + "\n[bench]\nstep_mm = 1.0\n", "unknown table [bench]"),
    "wrong_format": (_edit(BASE, 'format = "flann-sensor/1"', 'format = "flann-sensor/9"'), "format"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_sensor_file_one_line_exit_2(case, tmp_path, capsys):
    text, fragment = BAD[case]
    path = tmp_path / f"{case}.toml"
    path.write_text(text)
    out = tmp_path / "rec.csv"
    rc = main(["simulate", str(path), "-o", str(out)])
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert "\n" not in err and err.startswith("error: ") and str(path) in err
    assert fragment in err
    assert not out.exists()


def test_missing_file_exit_2(tmp_path, capsys):
    rc = main(["simulate", str(tmp_path / "nope.toml"), "-o", str(tmp_path / "r.csv")])
    assert rc == 2 and "no such file" in capsys.readouterr().err


def test_console_script_reports_one_line(tmp_path):
    path = tmp_path / "neg.toml"
    path.write_text(BAD["negative_length"][0])
    exe = Path(sys.executable).with_name("flann")
    r = subprocess.run([str(exe), "simulate", str(path), "-o", str(tmp_path / "r.csv")],
                       capture_output=True, text=True)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr


def test_optional_core_conductivity():
    text = BASE.replace("permeability_ratio = 220.0", "permeability_ratio = 220.0\nconductivity_s_per_m = 1.7e6")
    s = parse_sensor(text)
    assert s.core_conductivity_s_per_m == 1.7e6 and default_sensor().core_conductivity_s_per_m == 0.0
    assert parse_sensor(format_sensor(s)) == s
    with pytest.raises(SensorError, match="core.conductivity_s_per_m = -1"):
        parse_sensor(text.replace("1.7e6", "-1.0"))


def test_section_given_as_value_is_refused(tmp_path, capsys):
    path = tmp_path / "flat.toml"
    path.write_text('format = "flann-sensor/1"\nstroke_mm = 30.0\ncore = 5\n')
    assert main(["simulate", str(path), "-o", str(tmp_path / "r.csv")]) == 2
    assert "core must be a table" in capsys.readouterr().err
