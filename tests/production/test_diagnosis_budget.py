"""The diagnosis on a budget: what calibrate hands it, and that it still names a real effect."""

from __future__ import annotations

import numpy as np
import pytest

from flann.cli import main
from flann.physics.sensor import default_sensor, format_sensor
from flann.physics.simulate import simulate_recordings
from flann.production.calibrate import diagnosis_sample
from flann.recordings import Recordings, write_recordings

STEP_MM = 2 * 28 / 999  # forward + reverse over the paper LVDT's stroke: ~2,000 points


@pytest.fixture(scope="module")
def sweep():
    return simulate_recordings(default_sensor().replace(effects={}), step_mm=STEP_MM, noise_v=0.2e-3, seed=3)


def test_bins_stay_inside_one_pass(sweep):
    small, basis = diagnosis_sample(sweep, 250)
    assert 200 <= len(small) <= 250 and "means of the" in basis
    # a bin that spanned the turn would average the two directions: not +-1, not monotonic
    assert set(np.unique(small.direction)) == {-1.0, 1.0}
    for d in (-1.0, 1.0):
        x = small.displacement_mm[small.direction == d]
        assert np.all(np.diff(x) * d > 0)
    assert small.displacement_mm.min() >= sweep.displacement_mm.min()
    assert small.displacement_mm.max() <= sweep.displacement_mm.max()
    # a bin mean has less noise: the voltage still follows the raw sweep at the bin's position
    fwd = sweep.direction == 1
    raw = np.interp(small.displacement_mm, sweep.displacement_mm[fwd], sweep.voltage_v[fwd])
    assert np.max(np.abs(small.voltage_v - raw)[small.direction == 1]) < 1e-3


def test_no_budget_and_unordered_rows(sweep):
    assert diagnosis_sample(sweep, 0)[0] is sweep
    assert diagnosis_sample(sweep, len(sweep))[0] is sweep
    order = np.random.default_rng(1).permutation(len(sweep))
    shuffled = Recordings(displacement_mm=sweep.displacement_mm[order], voltage_v=sweep.voltage_v[order])
    small, basis = diagnosis_sample(shuffled, 100)
    assert len(small) == 100 and "evenly sampled" in basis
    assert np.isin(small.voltage_v, shuffled.voltage_v).all()  # real rows, not means


def test_budget_still_names_backlash(tmp_path):
    """A sensor with 50 um of backlash (physics simulator), calibrated with the default budget:
    the certificate names the effect and says what the diagnosis saw."""
    s = default_sensor().replace(effects={"backlash": {"deadband_mm": 0.05}})
    rec = simulate_recordings(s, step_mm=STEP_MM, noise_v=0.2e-3, seed=4)
    p = tmp_path / "lash.csv"
    write_recordings(p, rec)
    toml = tmp_path / "nominal.toml"
    toml.write_text(format_sensor(default_sensor().replace(effects={})))
    assert main(["gen", "--family", str(p), "-o", str(tmp_path / "design")]) == 0
    assert main(["calibrate", str(p), "-o", str(tmp_path / "out"), "--design", str(tmp_path / "design"),
                 "--sensor", str(toml), "-j", "1"]) == 0
    html = (tmp_path / "out" / "lash" / "certificate.html").read_text()
    assert "<li>backlash: " in html
    assert f"means of the {len(rec)} readings" in html


def test_many_short_sweeps_stay_within_the_budget():
    """50,000 rows of 60-row sweeps gave 1,667 whole-sweep means (one per pass, about 4 distinct
    displacements): the budget held neither the count nor the curve."""
    x = np.linspace(-25.0, 25.0, 60)
    one = np.concatenate([x, x[::-1]])
    xs = np.tile(one, 417)[:50_000]
    d = np.tile(np.r_[np.ones(60), -np.ones(60)], 417)[:50_000]
    rec = Recordings(xs, 0.2 * xs, direction=d, source="short.csv")
    small, basis = diagnosis_sample(rec, 250)
    assert len(small) <= 2 * 250 and "means of the 50000 readings" in basis   # about the budget
    assert np.unique(np.round(small.displacement_mm, 6)).size >= 20
