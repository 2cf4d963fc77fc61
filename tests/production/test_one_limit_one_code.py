"""One physical limit and one converter rule: the production certificate and ``flann eval
--design`` must report the same limit for the same model and converter, and a voltage half
way between two codes must get the same code in every path (eval, calibrate, trace)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flann.analysis.trace import run_trace
from flann.cli import main
from flann.golden.model import load_model
from flann.golden.metrics import DEFAULT_BAND_PCT_FS, DEFAULT_TOL_PCT_FS, full_scale_mm
from flann.hardware.accuracy import (adc_codes, design_adc, design_spec, hardware_accuracy, physical_limit_mm,
                                     temperature_codes)
from flann.hardware.family.render import load_design
from flann.hardware.registry import FAMILY_THERMAL, datapath, read_design
from flann.numeric.fixed import nearest_codes
from flann.golden.family import ridge_ladder
from flann.production.calibrate import check_sensor
from flann.production.spec import ProductionSpec
from flann.production.thermal import check_sensor_thermal
from flann.production.verdict import judge
from flann.recordings import Recordings, read_recordings, write_recordings

SPAN_MM, W_MM, SHARP = 10.0, 7.0, 2.5
ADC_LSB_V = 2 * 3.6 / 2 ** 14
TEMPS = (-20.0, 25.0, 80.0)


def volts(x, amp, temp=25.0, gain_tc=0.0, null_tc=0.0):
    """A saturating S-curve (not the project's physics), its gain and null moving with temperature."""
    u = x / W_MM
    dt = temp - 25.0
    return amp * (1 + gain_tc * dt) * u / (1 + np.abs(u) ** SHARP) ** (1 / SHARP) + null_tc * dt


def sweep(seed, amp, temps=(25.0,), gain_tc=0.0, null_tc=0.0, steps=120):
    x = np.linspace(-SPAN_MM, SPAN_MM, steps)
    xs = np.concatenate([np.concatenate([x, x[::-1]]) for _ in temps])
    d = np.tile(np.concatenate([np.ones(steps), -np.ones(steps)]), len(temps))
    ts = np.repeat(np.asarray(temps, dtype=float), 2 * steps)
    noise = np.random.default_rng(seed).normal(0, 0.3e-3, xs.size)
    v = np.round((volts(xs, amp, ts, gain_tc, null_tc) + noise) / ADC_LSB_V) * ADC_LSB_V
    return Recordings(displacement_mm=xs, voltage_v=v, direction=d,
                      temperature_c=ts if len(temps) > 1 else None)


def eval_hardware(capsys, model_path, rec_path, design) -> tuple[dict, dict]:
    """``flann eval --design --json``'s hardware block, and its per-point arrays (the same call
    as the command's)."""
    capsys.readouterr()
    assert main(["eval", str(model_path), str(rec_path), "--design", str(design), "--json"]) == 0
    hw = json.loads(capsys.readouterr().out)["hardware"]
    rec = read_recordings(rec_path)
    pts = hardware_accuracy(design_spec(model_path, design), rec, tol=DEFAULT_TOL_PCT_FS, band=DEFAULT_BAND_PCT_FS,
                            fs_mm=full_scale_mm(rec.displacement_mm), adc=design_adc(design))["_points"]
    return hw, pts


@pytest.fixture(scope="module")
def family(tmp_path_factory):
    d = tmp_path_factory.mktemp("one_limit")
    paths = [d / "a.csv", d / "b.csv", d / "c.csv"]
    for k, (p, amp) in enumerate(zip(paths, (3.0, 3.1, 2.95))):
        write_recordings(p, sweep(k, amp))
    # a coarse converter: the copies of the limit differed most where the LSB is large
    assert main(["gen", "--family", str(paths[0]), str(paths[1]), "-o", str(d / "design"),
                 "--input-bits", "9"]) == 0
    return {"dir": d, "paths": paths, "design": d / "design"}


def test_certificate_limit_is_evals_limit(family, capsys):
    """c.csv did not size the design: calibrate's check and eval --design on the calibrated
    model see the same codes, the same hardware error and the same limit."""
    fam = load_design(family["design"])
    rec_path = family["paths"][2]
    chk = check_sensor(read_recordings(rec_path), fam)   # what calibrate reads
    model_path = family["dir"] / "c_model.json"
    model_path.write_text(chk["model"].to_json())
    hw, pts = eval_hardware(capsys, model_path, rec_path, family["design"])
    assert hw["adc_lsb_v"] == fam.spec.input_lsb_v   # the same converter
    assert hw["physical_limit_mm"]["max"] == pytest.approx(float(np.max(chk["limit_mm"])), rel=1e-12)
    assert hw["max_error_mm"] == pytest.approx(float(np.max(np.abs(chk["hw_err_mm"]))), rel=1e-12)
    np.testing.assert_allclose(pts["limit"], chk["limit_mm"], rtol=1e-12)
    np.testing.assert_allclose(pts["hardware"], chk["hw_err_mm"], rtol=0, atol=1e-12)
    # one full scale: the verdict's % FS over the whole stroke is eval's
    verdict = judge(ProductionSpec(max_error_mm=1.0), read_recordings(rec_path).displacement_mm,
                    chk["hw_err_mm"], None, ())
    assert verdict.max_error_pct_fs == pytest.approx(hw["max_error_pct_fs"], rel=1e-12)


def test_limit_is_half_a_code_bin_and_clips_to_the_trained_range(family):
    """Half an LSB over the slope, from the model itself: at a reading inside the range the
    half-width of its code's bin, and beyond the range the value at the range's end."""
    fam = load_design(family["design"])
    model = check_sensor(read_recordings(family["paths"][2]), fam)["model"]
    lsb = fam.spec.input_lsb_v
    vlo, vhi = sorted(model.voltage_range_v)
    inside = np.array([0.0, 0.5 * vhi, 0.9 * vlo])
    want = 0.5 * np.abs(model.predict(inside + lsb / 2) - model.predict(inside - lsb / 2))
    np.testing.assert_allclose(physical_limit_mm(model, inside, lsb), want, rtol=1e-12)
    beyond = physical_limit_mm(model, [vhi + 0.3, vlo - 0.3], lsb)
    np.testing.assert_allclose(beyond, physical_limit_mm(model, [vhi, vlo], lsb), rtol=1e-12)
    # the limit shrinks with the LSB as an LSB over a slope does
    np.testing.assert_allclose(physical_limit_mm(model, inside, lsb / 4) * 4, want, rtol=1e-3)


def test_the_limit_at_an_end_takes_no_slope_from_beyond_the_trained_range(family):
    """At the ends the bin is the one that ends there: a model's continuation past its range is
    pinned by no data (a FLANN's can be flat where the sensor is not), so a model that differs
    from another only beyond the range has the same limit everywhere."""
    fam = load_design(family["design"])
    model = check_sensor(read_recordings(family["paths"][2]), fam)["model"]
    lsb = fam.spec.input_lsb_v
    vlo, vhi = sorted(model.voltage_range_v)

    class WildBeyond:
        voltage_range_v = model.voltage_range_v

        @staticmethod
        def predict(v):
            v = np.asarray(v, dtype=float)
            return model.predict(v) + 1e3 * (np.maximum(v - vhi, 0) + np.minimum(v - vlo, 0))

    ends = np.array([vhi, vhi - lsb / 4, vlo, vlo + lsb / 4, vhi + 1.0])
    np.testing.assert_allclose(physical_limit_mm(WildBeyond, ends, lsb), physical_limit_mm(model, ends, lsb),
                               rtol=1e-12)
    at_top = 0.5 * abs(model.predict(vhi) - model.predict(vhi - lsb))
    assert physical_limit_mm(model, [vhi], lsb)[0] == pytest.approx(at_top, rel=1e-12)


@pytest.fixture(scope="module")
def thermal_family(tmp_path_factory):
    d = tmp_path_factory.mktemp("one_limit_thermal")
    params = ((3.0, -2.0e-4, 40e-6), (3.1, -1.2e-4, -25e-6), (2.9, -2.6e-4, 10e-6))
    paths = []
    for k, (amp, gtc, ntc) in enumerate(params):
        paths.append(d / f"t{k}.csv")
        write_recordings(paths[-1], sweep(k, amp, TEMPS, gtc, ntc, steps=80))
    assert main(["gen", "--family", *map(str, paths), "-o", str(d / "design"), "--input-bits", "8",
                 "--temp-bits", "8", "--temp-lsb-c", "1", "--terms", "15"]) == 0
    return {"dir": d, "paths": paths, "design": d / "design", "params": params}


def test_thermal_certificate_limit_is_evals_limit(thermal_family, capsys):
    man, dp = read_design(thermal_family["design"])
    assert dp is FAMILY_THERMAL
    spec, _ = dp.rebuild(dp.model_path(thermal_family["design"], man), man, thermal_family["design"])
    rec_path = thermal_family["paths"][1]
    chk = check_sensor_thermal(read_recordings(rec_path), spec, ridge_ladder(spec.fam.ridge))
    model_path = thermal_family["dir"] / "t1_model.json"
    model_path.write_text(chk["model"].to_json())
    hw, pts = eval_hardware(capsys, model_path, rec_path, thermal_family["design"])
    assert hw["physical_limit_mm"]["max"] == pytest.approx(float(np.max(chk["limit_mm"])), rel=1e-12)
    assert hw["max_error_mm"] == pytest.approx(float(np.max(np.abs(chk["hw_err_mm"]))), rel=1e-12)
    np.testing.assert_allclose(pts["limit"], chk["limit_mm"], rtol=1e-12)
    np.testing.assert_allclose(pts["hardware"], chk["hw_err_mm"], rtol=0, atol=1e-12)


def test_a_tie_rounds_up_in_every_path(default_model_json):
    """Voltages exactly half way between two codes (an LSB of 2^-8 V makes the ties exact):
    the next code up in eval's converter and in trace --at."""
    model = load_model(default_model_json)
    lsb = 2.0 ** -8
    spec = datapath("fixed").derive(model, input_bits=12, input_lsb_v=lsb)
    tr = run_trace(model, "fixed", input_bits=12, input_lsb_v=lsb)
    below = np.array([-301, -2, -1, 0, 1, 2, 7, 300])
    ties = (below + 0.5) * lsb
    want = (below + 1).tolist()
    assert adc_codes(spec, ties).tolist() == want
    assert [r["code"] for r in tr.at_voltages(ties)] == want
    assert nearest_codes([-0.5, 0.5, 1.5, 2.5], 1.0, -8, 7).tolist() == [0, 1, 2, 3]
    # saturated at the converter's ends, not wrapped
    assert nearest_codes([-100.0, 100.0], 1.0, -8, 7).tolist() == [-8, 7]


def test_a_temperature_tie_rounds_up(thermal_family):
    """The temperature converter's rule is the voltage converter's (1 degC codes here)."""
    man, dp = read_design(thermal_family["design"])
    spec, _ = dp.rebuild(dp.model_path(thermal_family["design"], man), man, thermal_family["design"])
    lsb = spec.temp_lsb_c
    assert temperature_codes(spec, [20.5 * lsb, -3.5 * lsb, 1e6]).tolist() == [21, -3, spec.temp_code_max]
