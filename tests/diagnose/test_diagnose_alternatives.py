"""Equally good explanations, the measurement that separates them, parameters the recordings do
not determine, and figures that cannot be computed (never printed as nan)."""

import json
import math
import re
import warnings
from dataclasses import replace

import numpy as np
import pytest

from flann.cli import main
from flann.diagnose import diagnose
from flann.diagnose.confound import bic_spread, separations
from flann.diagnose.demo import CASES, simulate_case
from flann.diagnose.report import format_text, to_json
from flann.diagnose.select import Fit
from flann.physics import filament as F
from flann.recordings import Recordings


def _diag(rec):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(rec)


@pytest.mark.parametrize("sets, words", [
    ([("zero_shift",), ("secondary_imbalance",)], "both secondary amplitudes"),
    ([("null_offset",), ("zero_shift",)], "both secondary amplitudes"),
    ([("null_offset", "backlash"), ("secondary_imbalance", "backlash")],
     "both secondary amplitudes"),
    ([("quadrature_null",), ("null_offset",)], "quadrature channel"),
    ([("thermal_drift",), ("null_offset",)], "constant temperature"),
])
def test_each_confounded_pair_has_its_measurement(sets, words):
    (sep,) = separations(sets)
    assert words in sep.measurement and sep.why
    # the pair is the effects the two sets do not share
    differ = set(sets[0]) ^ set(sets[1])
    assert {sep.a, sep.b} == differ


def test_no_measurement_when_decided_and_one_per_pair():
    assert separations([("zero_shift",)]) == ()
    three = separations([("null_offset",), ("zero_shift",), ("secondary_imbalance",)])
    assert [{s.a, s.b} for s in three] == [{"null_offset", "zero_shift"},
                                           {"null_offset", "secondary_imbalance"}]
    # a set inside another: the extra effect alone
    (sep,) = separations([("backlash", "null_offset"), ("backlash",)])
    assert sep.a == "null_offset" and sep.b is None and sep.measurement


def _fit(resid):
    r = np.asarray(resid, float)
    return Fit((), [], np.zeros(0), np.zeros(0), r, np.arange(r.size))


def test_bic_spread_follows_the_noise_of_a_difference():
    """A set that misses by delta at every reading lies sum(delta^2)/sigma^2 behind, give or
    take 2 sqrt of that over noise draws; a difference at five readings is not spread."""
    rng = np.random.default_rng(1)
    r = rng.normal(0, 1, 2000)
    se, readings = bic_spread(_fit(r), _fit(r + 0.1))
    expected = 2 * math.sqrt(2000 * 0.1 ** 2)
    assert 0.8 * expected < se < 1.25 * expected and readings > 300
    bump = r.copy()
    bump[:5] += 5.0
    assert bic_spread(_fit(r), _fit(bump))[1] < 10


def _filament_rectified(q_v: float, seed: int) -> Recordings:
    rng = np.random.default_rng(77)
    m = F.random_geometry(rng)
    h = F.monotonic_half_range(m) * 0.9
    m = replace(F.scaled_to(m, 5.0, h), rectified=True)
    m = m.with_effects(quadrature={"quadrature_v": q_v}) if q_v else m
    return F.simulate_recording(m, (-h, h), 2 * h / 299, 0.004, seed=seed)


def test_quadrature_null_at_a_v_tip_is_named():
    """A 40 mV quadrature null on a rectified output (4 mV noise, 600 points): the shape term
    chosen without it fills the tip in; with the null in place it needs no terms."""
    dg = _diag(_filament_rectified(0.04, 3000))
    assert dg.named == ["quadrature_null"], format_text(dg)
    q = dg.effects[0].params["quadrature_v"]
    assert abs(q["value"] - 0.04) < max(3 * q["stderr"], 0.004)
    # the shape term alone, an offset, or the offset beside the null may draw the same tip;
    # the quadrature channel tells the null from either of the first two
    sets = sorted(sorted(a.named) for a in dg.alternatives)
    assert sets == [[], ["null_offset"], ["null_offset", "quadrature_null"]], format_text(dg)
    assert next(a for a in dg.alternatives if a.named == []).note
    # the null and the offset together: one split of what either explains alone, not a value
    both = next(a for a in dg.alternatives if len(a.named) == 2)
    assert all(p.get("determined") is False and "share" in p["why"]
               for e in both.effects for p in e.params.values())
    assert "not determined" in format_text(dg)
    assert any("quadrature channel" in s.measurement for s in dg.separate_by)
    # another sensor of the same build, whose noise puts the offset 8 BIC behind the null
    # (the first: 11): the same explanations
    other = _diag(_filament_rectified(0.04, 3006))
    assert sorted(sorted(e) for e in other.explanations) == sorted(
        sorted(e) for e in dg.explanations), format_text(other)
    # and the same sensor without it: nothing named
    assert _diag(_filament_rectified(0.0, 3001)).named == []


def test_rails_figures_are_not_computable_not_nan():
    rec = simulate_case(next(c for c in CASES if c.name.startswith("control: paper")),
                        seed=11, points=600)
    top = 0.8 * float(np.max(rec.voltage_v))
    v = np.clip(rec.voltage_v, -np.inf, top)
    dg = _diag(Recordings(rec.displacement_mm, v, rec.direction, rec.time_s,
                          rec.temperature_c))
    assert "adc_clipping" in dg.named
    text = format_text(dg)
    assert not re.search(r"\bnan\b", text, re.I)
    assert "not computable" in text
    e = next(e for e in to_json(dg)["effects"] if e["name"] == "adc_clipping")
    assert e["delta_bic"] is None and "rails" in e["not_computable"]


def test_undetermined_geometry_has_no_value(tmp_path):
    """Twelve points cannot fix four lengths: a fitted length whose uncertainty exceeds it
    is reported as not determined, in the text and in the JSON."""
    out = tmp_path / "d.json"
    assert main(["diagnose", "data/paper_table1.csv", "--json", str(out), "--quiet"]) == 0
    params = json.loads(out.read_text())["baseline"]["params"]
    undetermined = [k for k, p in params.items() if p.get("determined") is False]
    assert undetermined
    for k, p in params.items():
        if p.get("determined") is False:
            assert p["value"] is None and p["stderr"] > abs(p["fitted_value"]), (k, p)
        elif p["stderr"] is not None and k != "origin_mm":
            assert p["stderr"] <= abs(p["value"]), (k, p)


def test_undetermined_in_text(capsys):
    assert main(["diagnose", "data/paper_table1.csv", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "not determined by these recordings" in out
    assert not re.search(r"\bnan\b", out, re.I)
