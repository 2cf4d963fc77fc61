"""A two-input design never reports a displacement beyond the calibrated range unflagged.

The input clamp is one rectangle (calibrated voltages x calibrated temperatures), but the
sensor's span shrinks with temperature: at the hot end the top of the voltage range is a
reading the sensor never gives, and the model, a polynomial in t_n, extrapolates there far
beyond the stroke.  The design saturates its output at the calibrated displacement range
widened by 1 % of its span (``flann.golden.thermal.OUTPUT_MARGIN``), rounded outward to the output LSB, and
raises ``out_sat`` there; the twin does the same, and the float reference is saturated alike.
The sensor is the outside reviewer's (an erf S-curve, asymmetric, its gain falling
0.04 %/degC), calibrated at -20/25/70 degC over +-25 mm; an 8-bit input and a 4-bit x 10 degC
temperature code (the calibrated -20..70 degC are codes -2..7).
"""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from math import erf

import numpy as np
import pytest

from flann.golden.thermal_train import fit_thermal
from flann.hardware.thermal.spec import derive_thermal_spec
from flann.hardware.thermal.twin import FlannThermalTop
from flann.verify.datapaths import simulate
from flann.hardware.design import from_directory

FLANN = [sys.executable, "-m", "flann.cli"]
STROKE_MM = (-25.0, 25.0)
MARGIN_MM = 0.01 * (STROKE_MM[1] - STROKE_MM[0])      # 1 % of the calibrated span
GEN = dict(input_bits=8, input_lsb_v=5.0 / 256, temp_bits=4, temp_lsb_c=10.0)

_erf = np.vectorize(erf)


def sensor_v(x, temp):
    """The reviewer's invented sensor (mkrec.py), noise-free: V at x mm and temp degC."""
    dt = np.asarray(temp, dtype=float) - 25.0
    u = np.asarray(x, dtype=float) - (1.3 + 0.004 * dt)
    return 1.9 * (1 - 0.0004 * dt) * _erf(u / 11.0) + 0.012 * (u / 10) ** 3 - 0.0004 * u ** 2 + 0.045


@pytest.fixture(scope="module")
def model():
    xs = np.arange(STROKE_MM[0], STROKE_MM[1] + 1e-9, 0.5)
    x, t = np.tile(xs, 3), np.repeat([-20.0, 25.0, 70.0], xs.size)
    return fit_thermal(sensor_v(x, t), t, x, (9, 5, 3), norm="half")


@pytest.fixture(scope="module")
def spec(model):
    return derive_thermal_spec(model, **GEN)


def _limits(q: float) -> tuple[float, float]:
    """The calibrated range + the margin, rounded outward to the output LSB (mm), computed here."""
    return (math.floor((STROKE_MM[0] - MARGIN_MM) / q + 1e-9) * q,
            math.ceil((STROKE_MM[1] + MARGIN_MM) / q - 1e-9) * q)


def _every_code(spec):
    c, t = np.meshgrid(np.arange(spec.code_min, spec.code_max + 1), np.arange(spec.temp_code_min, spec.temp_code_max + 1))
    return c.ravel(), t.ravel()


def test_the_model_extrapolates_beyond_the_stroke_at_a_calibrated_corner(model, spec):
    """The premise: inside the input clamp's rectangle the float model leaves the stroke by
    more than the margin (at the top voltage code and the hot end: about 27.9 mm)."""
    assert tuple(model.displacement_range_mm) == STROKE_MM
    c, t = _every_code(spec)
    c, t = np.clip(c, spec.clamp_lo, spec.clamp_hi), np.clip(t, spec.temp_lo, spec.temp_hi)
    x = model.predict(c * spec.input_lsb_v, t * spec.temp_lsb_c)
    assert x.max() > STROKE_MM[1] + MARGIN_MM + 1.0 and x.min() < STROKE_MM[0] - MARGIN_MM - 1.0


def test_no_output_beyond_the_calibrated_range_without_out_sat(spec):
    """Every (voltage code, temperature code): an output beyond the calibrated displacement
    range + margin never comes without out_sat; outputs stop at the limits; the twin stays
    within 1 LSB of the float reference (saturated alike), and inside the calibration and the
    limits nothing is flagged."""
    q = spec.output_lsb_mm
    lo, hi = _limits(q)
    c, t = _every_code(spec)
    top = FlannThermalTop(spec)
    out, sat = top.process(c, t)
    mm = out * q
    assert mm.max() <= hi + 1e-9 and mm.min() >= lo - 1e-9, (mm.min(), mm.max())
    beyond = (mm > STROKE_MM[1] + MARGIN_MM + 1e-9) | (mm < STROKE_MM[0] - MARGIN_MM - 1e-9)
    assert not (beyond & ~sat).any()
    # where the float model is beyond a limit, the output is that limit and says so
    x = spec.float_model(c, t)
    over, under = x > hi + q, x < lo - q
    assert over.any() and under.any()
    assert (sat[over] & np.isclose(mm[over], hi)).all()
    assert (sat[under] & np.isclose(mm[under], lo)).all()
    assert spec.output_limits_mm == pytest.approx((lo, hi))
    # the float reference saturates as the hardware does: the error bound holds everywhere
    assert np.abs(out - spec.float_reference(c, t) / q).max() <= 1.0
    assert top.error_vs_float()["max_err_lsb"] <= 1.0
    inside = ((c >= spec.clamp_lo) & (c <= spec.clamp_hi) & (t >= spec.temp_lo) & (t <= spec.temp_hi)
              & (x < hi - q) & (x > lo + q))
    assert inside.sum() > 1000 and not sat[inside].any()


@pytest.mark.sim
@pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl not installed")
def test_the_vhdl_saturates_at_the_limits_as_its_twin(model, tmp_path):
    """flann gen of the design, then GHDL over the top of the voltage range (the calibrated codes
    where the hot end extrapolates, and the clamped codes beyond) at every temperature code:
    0 mismatches against the twin, and no output beyond the limits without out_sat."""
    (tmp_path / "m.json").write_text(model.to_json())
    r = subprocess.run([*FLANN, "gen", str(tmp_path / "m.json"), "-o", str(tmp_path / "d"), "--input-bits", "8",
                        "--input-lsb-v", str(GEN["input_lsb_v"]), "--temp-bits", "4", "--temp-lsb-c", "10"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    d = from_directory(tmp_path / "d")
    man = json.loads((tmp_path / "d" / "manifest.json").read_text())
    q = d.spec.output_lsb_mm
    lo, hi = _limits(q)
    window = (d.spec.clamp_hi - 10, d.spec.code_max)
    res = simulate(d, tmp_path / "b", codes=window)
    s = res.summary
    temps = d.spec.temp_code_max - d.spec.temp_code_min + 1
    assert s["mismatches"] == 0 and s["all_passed"], s
    assert s["codes_tested"] == (window[1] - window[0] + 1) * temps, s
    rows = np.loadtxt(tmp_path / "b" / "thermal_sweep.txt", dtype=np.int64, ndmin=2)
    c, t, out, sat = rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3].astype(bool)
    mm = out * q
    beyond = (mm > STROKE_MM[1] + MARGIN_MM + 1e-9) | (mm < STROKE_MM[0] - MARGIN_MM - 1e-9)
    assert not (beyond & ~sat).any()
    # the window holds calibrated codes the output limit saturates (not only clamped inputs)
    calibrated = (c <= d.spec.clamp_hi) & (t >= d.spec.temp_lo) & (t <= d.spec.temp_hi)
    assert (calibrated & sat & np.isclose(mm, hi)).any()
    assert man["spec"]["output_limit_codes"] == [round(lo / q), round(hi / q)]


def test_predict_holds_the_same_pair_at_the_limits_and_says_so(model, tmp_path):
    """flann predict at a (voltage, temperature) pair inside both calibrated ranges that the
    sensor never gives: the displacement held at the limit, clamped = 1, one warning line;
    a reading the sensor gives is left alone."""
    (tmp_path / "m.json").write_text(model.to_json())
    vhi = math.floor(max(model.voltage_range_v) * 1e6) / 1e6      # inside the range as written
    (tmp_path / "q.csv").write_text("voltage_v,temperature_c\n"
                                    f"{vhi:.6f},70\n{float(sensor_v(10.0, 70.0)):.6f},70\n")
    r = subprocess.run([*FLANN, "predict", str(tmp_path / "m.json"), str(tmp_path / "q.csv"), "-o",
                        str(tmp_path / "p.csv")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    said = [ln for ln in r.stderr.splitlines() if "beyond the calibrated" in ln]
    assert len(said) == 1 and "1 of 2 readings" in said[0], r.stderr
    rows = np.loadtxt(tmp_path / "p.csv", delimiter=",", skiprows=1, ndmin=2)
    assert rows[0, 2] == pytest.approx(STROKE_MM[1] + MARGIN_MM) and rows[0, 3] == 1
    assert abs(rows[1, 2] - 10.0) < 1.0 and rows[1, 3] == 0      # (9, 5, 3) terms: 0.26 mm off there
