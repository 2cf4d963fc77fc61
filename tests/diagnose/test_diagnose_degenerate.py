"""Recordings with no curve to diagnose (a step between two flat levels) are refused in one
line, and the report survives a model that meets every reading exactly."""

import dataclasses
import math

import numpy as np
import pytest

from flann.cli import main
from flann.diagnose import diagnose
from flann.diagnose.pipeline import EffectReport
from flann.diagnose.report import format_text, to_json
from flann.golden.paper import table1


def _csv(path, x, y):
    path.write_text("displacement_mm,voltage_v\n" + "".join(f"{a:g},{b:g}\n" for a, b in zip(x, y)))
    return str(path)


# a saturated recording: -1 mV, one 0 at the null, +1 mV (the rails leave one reading)
SATURATED = (np.arange(-30, 31), 0.001 * np.sign(np.arange(-30, 31)))
# a hard step: every reading on one of two levels
STEP = (np.arange(-10, 11), [0.5 if i >= 0 else -0.5 for i in range(-10, 11)])


@pytest.mark.parametrize("xy", [SATURATED, STEP], ids=["saturated", "step"])
@pytest.mark.parametrize("extra", [[], ["--quiet"], ["--json", "OUT"], ["--plot", "OUT.png"]])
def test_a_step_is_refused_in_one_line_and_writes_nothing(tmp_path, capsys, xy, extra):
    path = _csv(tmp_path / "r.csv", *xy)
    extra = [str(tmp_path / e) if e.startswith("OUT") else e for e in extra]
    assert main(["diagnose", path, *extra]) == 2
    cap = capsys.readouterr()
    err = cap.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: "), err
    assert "flat levels" in err[0] and "between the rails" in err[0]
    assert cap.out == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv"]


def test_a_ramp_between_rails_is_still_diagnosed(tmp_path, capsys):
    x = np.arange(-30, 31)
    path = _csv(tmp_path / "r.csv", x, np.clip(0.1 * x, -0.45, 0.45))
    assert main(["diagnose", path, "--quiet"]) == 0
    assert "adc_clipping" in capsys.readouterr().out


def test_report_of_an_exact_fit():
    dg = diagnose(table1())
    effect = EffectReport("null_offset", "a constant offset.", {}, 0.0, -20.0, 5.0)
    exact = dataclasses.replace(dg, effects=[effect], final_rms=0.0, noise_v=0.0,
                                outliers=[{"row": 8, "displacement_mm": 10.0, "residual_v": -1.0}])
    text = format_text(exact)
    assert "every reading reproduced exactly" in text
    assert "row 8 at 10 mm" in text
    assert to_json(exact)["improvement"] is None and math.isinf(exact.improvement)


def test_no_json_or_plot_when_the_report_fails(tmp_path, capsys, monkeypatch):
    import flann.commands.diagnose as cmd
    from flann.errors import FlannError

    def fail(dg):
        raise FlannError("report failed")

    monkeypatch.setattr(cmd, "format_text", fail)
    out, png = tmp_path / "d.json", tmp_path / "d.png"
    assert main(["diagnose", "data/paper_table1.csv", "--json", str(out), "--plot", str(png),
                 "--quiet"]) == 2
    assert "report failed" in capsys.readouterr().err
    assert not out.exists() and not png.exists()
