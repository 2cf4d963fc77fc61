"""`flann train --terms auto` fits the FLANN to the inverse of a forward curve v(x)
(flann.golden.inverse, flann.golden.sigmoids), judged against sensors written here (not sums
of tanh units) and the direct fit of x(v)."""

import json
from dataclasses import replace

import numpy as np
import pytest
from scipy.special import erf

from flann.cli import main as flann
from flann.golden import inverse
from flann.golden.inverse import (DENSE_TEACHER_TOL, SPARSE_POSITIONS, Forward, fit_to_forward, forward_curve,
                                  inverse_fit, spline_curve)
from flann.golden.model import load_model
from flann.golden.sigmoids import MAX_UNITS, SPREADS, Units, _Free, _Odd, fit_forward, refit
from flann.golden.train import AUTO_NORMS, fit_auto
from flann.hardware.fixed.cost import fixed_point_cost
from flann.physics import filament


def sensor(x):
    """A saturating sensor of this test's own: arctan roll-off, a slight even term; the ends of
    +-20 mm fall to a seventeenth of the slope at the null."""
    return 2.0 * np.arctan(x / 5.0) + 0.02 * (x / 20.0) ** 2 + 0.002


LSB = 2 * 3.2 / 2 ** 14


def recording(path, positions, seed, sweeps=1, noise=3e-4):
    rng = np.random.default_rng(seed)
    one = np.linspace(-20, 20, positions)
    x = np.concatenate([one if k % 2 == 0 else one[::-1] for k in range(sweeps)])
    v = np.round((sensor(x) + rng.normal(0, noise, x.size)) / LSB) * LSB
    d = np.repeat([1 if k % 2 == 0 else -1 for k in range(sweeps)], positions) if sweeps > 1 else None
    rows = ["displacement_mm,voltage_v" + (",direction" if d is not None else "")]
    for i in range(x.size):
        rows.append(f"{x[i]:.9g},{v[i]:.9g}" + (f",{d[i]:+d}" if d is not None else ""))
    path.write_text("\n".join(rows) + "\n")
    return x, v


def held_out_max_mm(model):
    xt = np.linspace(-20, 20, 2001)
    lo, hi = sorted(model.voltage_range_v)
    return float(np.max(np.abs(model.predict(np.clip(sensor(xt), lo, hi)) - xt)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_thirteen_positions_fit_the_inverse_of_the_forward_curve(tmp_path, seed):
    rec, out = tmp_path / "rec.csv", tmp_path / "m.json"
    x, v = recording(rec, 13, seed)
    assert flann(["train", str(rec), "-o", str(out)]) == 0
    model = load_model(out)
    t = model.training
    assert t["forward_spline"] in ("cubic", "pchip")
    assert t["leave_one_out"]["positions"] == 11
    assert t["cv_heldout_rms_error_mm"] == pytest.approx(t["leave_one_out"]["rms_error_mm"])
    # against the direct fit of x(v) on the same readings (auto's own choice): the ends of
    # the stroke, where x(v) is steep, are where the direct fit swings between 13 points
    direct, _ = fit_auto(v, x)
    assert held_out_max_mm(model) < 0.25 * held_out_max_mm(direct)
    assert held_out_max_mm(model) < 0.05      # of a 40 mm stroke, noise 0.3 mV


def test_many_positions_fit_the_inverse_of_the_forward_curve(tmp_path):
    """Two noisy sweeps of 120 positions: the direct fit of x(v) has the noise in its
    regressor and is pulled flat at the ends; the forward curve's inverse is not."""
    ratios = []
    for seed in (3, 4, 5):
        rec, out = tmp_path / f"rec{seed}.csv", tmp_path / f"m{seed}.json"
        x, v = recording(rec, 120, seed, sweeps=2, noise=2e-3)
        assert flann(["train", str(rec), "-o", str(out)]) == 0
        model = load_model(out)
        t = model.training
        assert t["selected_by"].startswith("120 positions: the FLANN fitted to the inverse")
        assert t["forward_model"]["kind"].startswith("tanh units")
        assert t["direct"]["cv_heldout_max_error_mm"] > t["teacher_max_deviation_mm"]
        direct, _ = fit_auto(v, x)
        ratios.append(held_out_max_mm(model) / held_out_max_mm(direct))
    assert max(ratios) < 0.9 and np.mean(ratios) < 0.75


def test_the_curve_is_cross_validated_on_the_direct_fits_folds(tmp_path):
    """The written model's own held-out figure, next to the direct fit's on the same folds
    (whole positions held out, the ends never): the procedure is no worse than the direct fit
    on the same readings, and refitting it on all of them reproduces the curve."""
    rec, out = tmp_path / "rec.csv", tmp_path / "m.json"
    x, v = recording(rec, 120, 6, sweeps=2, noise=1e-3)
    assert flann(["train", str(rec), "-o", str(out)]) == 0
    t = load_model(out).training
    own, direct = t["forward_model"]["heldout"], t["direct"]
    assert own["folds"] == t["cv_folds"] and own["points"] == 2 * 118   # ends never held out
    assert own["rms_error_mm"] <= direct["cv_heldout_rms_error_mm"]
    assert own["max_error_mm"] >= own["rms_error_mm"] > 0
    # the held-out readings carry their noise: at the null (slope 0.4 V/mm) 1 mV is 2.5 um
    assert own["rms_error_mm"] < 0.03
    fw = fit_forward(x, v)
    xs = np.linspace(-20, 20, 401)
    # a fit stops once its residual stops falling, not at the optimum: refined from there a
    # narrow unit moves a few evaluations further, by a thousandth of the readings' noise
    assert np.max(np.abs(refit(fw, x, v)(xs) - fw(xs))) < 1e-5


def test_repeats_at_few_positions_are_averaged_into_the_curve(tmp_path):
    rec, out = tmp_path / "rec.csv", tmp_path / "m.json"
    recording(rec, 13, 4, sweeps=4)
    assert flann(["train", str(rec), "-o", str(out)]) == 0
    model = load_model(out)
    assert model.training["positions_used"] == 13
    assert held_out_max_mm(model) < 0.05


@pytest.fixture(scope="module")
def arctan_fit():
    """Two noisy readings at each of 81 positions of the arctan sensor, and their forward
    curve, fitted once for the tests that look at it."""
    rng = np.random.default_rng(7)
    x = np.repeat(np.linspace(-20, 20, 81), 2)
    v = sensor(x) + rng.normal(0, 1e-3, x.size)
    return x, v, fit_forward(x, v)


def test_the_forward_curve_follows_a_shape_outside_its_family(arctan_fit):
    """arctan is no finite sum of tanh units: the average follows it within the noise."""
    x, v, fw = arctan_fit
    assert fw is not None
    assert fw.weights.sum() == pytest.approx(1.0)
    fine = np.linspace(-20, 20, 4001)
    assert np.all(np.diff(fw(fine)) > 0)
    assert np.max(np.abs(fw(fine) - sensor(fine))) < 1.5e-3
    again = fit_forward(x, v)       # deterministic: same starts, same fit (a fit of its own)
    assert np.array_equal(again(fine), fw(fine))


def knee(x):
    """A roll-off of this test's own with a knee sharper than six tanh units follow: the slope
    falls from 2.1 to 0.3 within a twentieth of the stroke (soft-plus corners at +-0.6)."""
    def corner(z):
        return np.logaddexp(0.0, 25.0 * z) / 25.0
    return 2.0 * (x - corner(x - 0.6) + corner(-x - 0.6)) + 0.1 * x ** 3


def knee_readings(sweeps: int):
    rng = np.random.default_rng(5)
    one = np.linspace(-1.0, 1.0, 201)
    x = np.concatenate([one if k % 2 == 0 else one[::-1] for k in range(sweeps)])
    return x, knee(x) + rng.normal(0, 2e-4, x.size)


def inverse_max_error(fw, truth) -> float:
    g = np.linspace(*fw.stroke, 4001)
    return float(np.max(np.abs(inverse.invert(fw, *fw.stroke, truth(g), points=g.size) - g)))


def test_a_knee_six_units_miss_grows_more_units_from_the_repeats():
    """Four sweeps: the position means are known to a quarter of the noise, and six units
    miss them at the knees by far more; more units are grown, and follow the knee."""
    x, v = knee_readings(4)
    grown, capped = fit_forward(x, v), fit_forward(x, v, more_units=MAX_UNITS)
    assert capped.describe()["largest_units"] == MAX_UNITS
    assert grown.describe()["largest_units"] > MAX_UNITS
    # measured 0.00066 against 0.0049 (of a stroke of 2)
    assert inverse_max_error(grown, knee) < inverse_max_error(capped, knee) / 3


def test_no_units_past_six_without_repeats_to_judge_the_misfit_by():
    x, v = knee_readings(1)
    assert fit_forward(x, v).describe()["largest_units"] == MAX_UNITS


def test_repeats_on_one_converter_code_are_no_misfit(tmp_path):
    """Noise far below the converter's step: the two sweeps mostly read the same code, so
    the readings scatter about their position means by nearly nothing, and what the curve
    leaves is the quantisation.  `flann train` takes the step from the readings' grid as the
    smallest scatter, and grows no units past six; without the step the quantisation reads
    as a misfit."""
    rec, out = tmp_path / "rec.csv", tmp_path / "m.json"
    x, v = recording(rec, 81, 8, sweeps=2, noise=2e-5)
    assert flann(["train", str(rec), "-o", str(out)]) == 0
    assert load_model(out).training["forward_model"]["largest_units"] <= MAX_UNITS
    assert fit_forward(x, v).describe()["largest_units"] > MAX_UNITS


def test_near_equal_local_optima_are_members_of_the_average(arctan_fit):
    """Which of near-equal optima the solver reaches turns on rounding: every one within 5 %
    of its K's best residual is a member, none further, and no optimum twice."""
    fw = arctan_fit[2]
    groups: dict = {}
    for m in fw.members:
        groups.setdefault((m.shape, m.units, m.linear), []).append(m.sse)
    assert any(len(sse) > 1 for sse in groups.values())
    for sse in groups.values():
        assert max(sse) <= 1.05 * min(sse)
        assert len(set(np.round(np.array(sse) / min(sse), 9))) == len(sse)


MEMBER_KINDS = ([(_Free, np.array([0.1, np.log(0.5), -0.4, np.log(0.2)])),
                 (_Odd, np.array([0.07, 0.05, np.log(0.6), np.log(0.2)]))]
                + [(shape, np.array([0.07, 0.05, np.log(0.6)])) for shape in SPREADS])


@pytest.mark.parametrize("shape, nl", MEMBER_KINDS,
                         ids=lambda k: getattr(k, "unit", getattr(k, "name", ""))[:12] + str(getattr(k, "derivatives", "")))
@pytest.mark.parametrize("linear", [False, True])
def test_each_members_derivative_is_its_curves(shape, nl, linear):
    """The analytic derivative in the nonlinear parameters the solver's Jacobian is built
    from, against central differences of the curve (off the null, where the gain steps)."""
    x = np.linspace(-1, 1, 200)
    beta = np.random.default_rng(1).normal(size=shape.basis(nl, x, linear).shape[1])
    numeric = []
    for k in range(nl.size):
        step = np.zeros(nl.size)
        step[k] = 1e-6
        numeric.append((Units(nl + step, beta, linear, 0.0, shape)(x)
                        - Units(nl - step, beta, linear, 0.0, shape)(x)) / 2e-6)
    got = shape.derivative(nl, x, linear, beta)
    assert np.max(np.abs(got - np.column_stack(numeric))) < 1e-6 * np.max(np.abs(got))


def langevin_sensor(x):
    """A magnetisation-like curve of this test's own, coth(z) - 1/z, odd about 1 mm with 2 %
    more gain above it: its tail is algebraic, no tanh's, so one width does not carry it."""
    z = (x - 1.0) / 3.0
    small = np.abs(z) < 1e-6
    safe = np.where(small, 1.0, z)
    return (1 + 0.02 * np.sign(z)) * 2.0 * np.where(small, z / 3, 1 / np.tanh(safe) - 1 / safe)


@pytest.fixture(scope="module")
def langevin_fit():
    """The forward curve of one noisy recording of :func:`langevin_sensor`, fitted once."""
    rng = np.random.default_rng(0)
    x = np.repeat(np.linspace(-15, 17, 150), 2)
    return fit_forward(x, langevin_sensor(x) + rng.normal(0, 1e-3, x.size))


def test_a_spread_of_widths_is_carried_by_the_spread_members(langevin_fit):
    fw = langevin_fit
    spread = sum(w for m, w in zip(fw.members, fw.weights) if m.shape in SPREADS)
    assert spread > 0.1
    odd = fw.describe()["odd_about_null"]
    assert odd["weight"] > 0.9                      # the spread members count as odd ones
    assert odd["null_mm"] == pytest.approx(1.0, abs=0.02)
    assert inverse_max_mm(fw, langevin_sensor, -15, 17) < 0.012


def test_an_algebraic_tail_is_carried_by_the_algebraic_members(langevin_fit):
    """coth z - 1/z falls off as 1/z: the algebraic units take most of the weight, and the
    inverse is closer than with tanh units alone (0.0092 mm measured without them)."""
    fw = langevin_fit
    algebraic = sum(w for m, w in zip(fw.members, fw.weights)
                    if m.shape in SPREADS and m.shape.unit == "algebraic")
    assert algebraic > 0.4
    assert inverse_max_mm(fw, langevin_sensor, -15, 17) < 0.0085


def odd_sensor(x):
    """A differential sensor of this test's own: arctan about a null at 3 mm, 3 % more gain
    above the null than below it (slopes 1.0619:1), a small offset."""
    z = x - 3.0
    return (1 + 0.03 * np.sign(z)) * 1.5 * np.arctan(z / 4.0) + 0.004


def inverse_max_mm(fw, truth, lo, hi):
    fine = np.linspace(lo, hi, 4001)
    g = np.linspace(lo, hi, 40001)
    v = fw(g)
    order = np.argsort(v)
    return float(np.max(np.abs(np.interp(truth(fine), v[order], g[order]) - fine)))


@pytest.mark.parametrize("seed", [0, 1, 3])
def test_a_sensor_odd_about_its_null_is_carried_by_the_odd_members(seed):
    """The stroke (-15..20 mm) is not centred on the null: the odd members find the null and
    the gain step, and each end of the stroke borrows the other half's readings.  The free
    units alone were 0.017-0.025 mm off the truth's inverse on these draws."""
    rng = np.random.default_rng(seed)
    x = np.repeat(np.linspace(-15, 20, 150), 2)
    fw = fit_forward(x, odd_sensor(x) + rng.normal(0, 1e-3, x.size))
    odd = fw.describe()["odd_about_null"]
    assert odd["weight"] > 0.9
    assert odd["null_mm"] == pytest.approx(3.0, abs=0.05)
    assert odd["slope_above_over_below"] == pytest.approx(1.03 / 0.97, abs=0.01)
    assert inverse_max_mm(fw, odd_sensor, -15, 20) < 0.015


def test_the_filament_lvdt_is_odd_about_its_null():
    """The independent forward model (a coil geometry, not the physics simulator's sensor
    file): the odd members carry most of the weight, and the inverse is closer to the
    truth than the free units alone got (0.0072 mm on this draw)."""
    rng = np.random.default_rng(0)
    m = filament.random_geometry(rng)
    half = filament.monotonic_half_range(m)
    x = np.repeat(np.linspace(-half, half, 161), 2)
    clean = filament.output_v(m, x)
    fw = fit_forward(x, clean + rng.normal(0, 2e-4 * np.ptp(clean), x.size))
    assert fw.describe()["odd_about_null"]["weight"] > 0.5
    assert inverse_max_mm(fw, lambda z: filament.output_v(m, z), -half, half) < 0.006


def test_a_sensor_with_an_even_part_gives_the_odd_members_no_weight():
    """A bow (0.15 V at the ends) that no gain step makes odd: the free units carry it."""
    def bowed(x):
        return 2.0 * np.arctan(x / 5.0) + 0.15 * (x / 20.0) ** 2
    rng = np.random.default_rng(2)
    x = np.repeat(np.linspace(-20, 20, 150), 2)
    fw = fit_forward(x, bowed(x) + rng.normal(0, 1e-3, x.size))
    assert fw.describe()["odd_about_null"]["weight"] < 0.01
    assert inverse_max_mm(fw, bowed, -20, 20) < 0.05


def test_train_says_where_the_null_is(tmp_path, capsys):
    rng = np.random.default_rng(4)
    x = np.repeat(np.linspace(-15, 20, 120), 2)
    v = odd_sensor(x) + rng.normal(0, 1e-3, x.size)
    rec, out = tmp_path / "rec.csv", tmp_path / "m.json"
    rec.write_text("displacement_mm,voltage_v\n" + "".join(f"{a:.9g},{b:.9g}\n" for a, b in zip(x, v)))
    assert flann(["train", str(rec), "-o", str(out)]) == 0
    odd = load_model(out).training["forward_model"]["odd_about_null"]
    said = [ln for ln in capsys.readouterr().err.splitlines() if "odd about a null" in ln]
    assert len(said) == 1 and f"{odd['null_mm']:.4g} mm" in said[0]
    assert odd["null_mm"] == pytest.approx(3.0, abs=0.1)


def test_no_forward_curve_from_too_few_or_flat_positions():
    x = np.linspace(-20, 20, 5)
    assert fit_forward(x, sensor(x)) is None                   # fewer than 6 positions
    assert fit_forward(np.linspace(-20, 20, 30), np.zeros(30)) is None
    assert forward_curve(x, sensor(x)).kind in ("cubic", "pchip")   # few positions: the spline
    many = np.linspace(-20, 20, SPARSE_POSITIONS)
    assert "tanh" in forward_curve(many, sensor(many)).describe()["kind"]


def test_no_monotone_spline_through_the_positions_is_none():
    x = np.linspace(-20, 20, 9)
    v = sensor(x)
    v[-2], v[-1] = v[-1], v[-2]          # the last two positions read in the wrong order
    assert spline_curve(x, v) is None
    assert spline_curve(x[:4], sensor(x[:4])) is None      # too few positions
    assert spline_curve(x, sensor(x)) is not None


@pytest.fixture(scope="module")
def thirteen_noise_free():
    """13 noise-free positions of the arctan sensor and the spline curve through them, fitted
    once: its check by leaving each position out refits the trend twelve times (~20 s)."""
    x = np.linspace(-20, 20, 13)
    return x, sensor(x), spline_curve(x, sensor(x))


def test_no_candidate_that_builds_falls_back_to_the_direct_fit(thirteen_noise_free, monkeypatch):
    x, v, curve = thirteen_noise_free
    real = inverse.forward_curve

    def forward_curve(xs, vs, step_v=0.0):   # these readings' curve is the one fitted above
        same = np.array_equal(xs, x) and np.array_equal(vs, v) and step_v == 0.0
        return curve if same else real(xs, vs, step_v)
    monkeypatch.setattr(inverse, "forward_curve", forward_curve)
    _, choice = fit_auto(v, x)
    never = inverse_fit(x, v, choice, lambda m: {"buildable": False, "why": "test", "cost": np.inf}, {})
    assert never is None
    built = inverse_fit(x, v, choice, lambda m: {"buildable": True, "why": "", "cost": float(m.terms),
                                                 "luts": 0, "brams": 0, "weight_bits": 16,
                                                 "term_bits": 16, "output_lsb_mm": 1e-3}, {})
    assert built is not None and "forward_model" in built.training


def test_a_curve_the_flann_cannot_follow_keeps_the_direct_fit(monkeypatch):
    """With many positions the direct fit stays when the FLANN's best buildable deviation
    from the curve's inverse exceeds the direct fit's own held-out max error."""
    real, fitted = inverse.forward_curve, {}

    def forward_curve(xs, vs, step_v=0.0):   # both inverse_fit calls below: one fit (deterministic)
        key = (np.asarray(xs, float).tobytes(), np.asarray(vs, float).tobytes(), step_v)
        if key not in fitted:
            fitted[key] = real(xs, vs, step_v)
        return fitted[key]
    monkeypatch.setattr(inverse, "forward_curve", forward_curve)
    x = np.repeat(np.linspace(-20, 20, SPARSE_POSITIONS + 10), 2)
    v = sensor(x)
    _, choice = fit_auto(v, x)
    tight = replace(choice, max_mm=1e-9)
    ok = {"buildable": True, "why": "", "cost": 1.0, "luts": 0, "brams": 0, "weight_bits": 16,
          "term_bits": 16, "output_lsb_mm": 1e-3}
    assert inverse_fit(x, v, tight, lambda m: ok, {}) is None
    assert inverse_fit(x, v, choice, lambda m: ok, {}) is not None


class ErfCurve:
    """A noise-free forward curve of this test's own rolling off strongly: erf, the ends of
    +-4 mm at a twentieth of the slope at the null."""
    stroke = (-4.0, 4.0)

    def __call__(self, x):
        return 3.0 * erf(np.asarray(x) / 2.31)


def test_a_strong_roll_off_is_followed_with_a_margin_normalisation(monkeypatch):
    """At 16 bits the candidates that follow the steep ends of the inverse best ('half', small
    ridge) bound |hardware - float| above one output LSB; v_n in [-0.85, 0.85] builds closer
    (measured 0.0087 mm against 0.038 mm with 'range' and 'half' alone)."""
    def cost(m):
        return fixed_point_cost(m, (16, 2 * 3.2 / 2 ** 16))
    _, info = fit_to_forward(ErfCurve(), cost, {}, DENSE_TEACHER_TOL)
    monkeypatch.setattr(inverse, "TEACHER_NORMS", AUTO_NORMS)
    _, without = fit_to_forward(ErfCurve(), cost, {}, DENSE_TEACHER_TOL)
    assert info["normalisation"] == "0.85"
    assert info["teacher_max_deviation_mm"] < 0.5 * without["teacher_max_deviation_mm"]


def test_the_paper_table_trains_through_the_forward_curve(tmp_path):
    out = tmp_path / "m.json"
    assert flann(["train", "data/paper_table1.csv", "-o", str(out)]) == 0
    t = json.loads(out.read_text())["training"]
    assert t["positions_used"] == 13 and "forward_model" in t


def test_a_straight_sensor_is_mostly_the_straight_line():
    rng = np.random.default_rng(11)
    x = np.repeat(np.linspace(0, 10, 150), 2)
    fw = fit_forward(x, 0.2 * x + rng.normal(0, 1e-3, x.size))
    assert fw.describe()["heaviest_units"] == 0
    fine = np.linspace(0, 10, 1001)
    assert np.max(np.abs(fw(fine) - 0.2 * fine)) < 1e-3


def test_few_positions_take_the_spline_on_a_trend_when_it_leaves_out_better(thirteen_noise_free):
    """13 noise-free positions of the arctan sensor: a cubic through what a 2-unit trend
    leaves bends less between them than a cubic through the readings themselves."""
    _x, _v, fw = thirteen_noise_free
    assert fw.trend is not None
    plain = Forward(fw.positions, fw.mean_v, fw.kind)
    fine = np.linspace(-20, 20, 4001)
    assert np.max(np.abs(fw(fine) - sensor(fine))) < 0.5 * np.max(np.abs(plain(fine) - sensor(fine)))


def test_a_straight_sensor_keeps_the_cheap_direct_fit(tmp_path):
    """No curvature beyond the noise: the direct fit (a few terms), not 61 terms following
    the curved members' wiggles."""
    rng = np.random.default_rng(5)
    x = np.linspace(0, 10, 300)
    rec, out = tmp_path / "line.csv", tmp_path / "m.json"
    rec.write_text("displacement_mm,voltage_v\n" + "".join(
        f"{a:.9g},{b:.9g}\n" for a, b in zip(x, 0.2 * x + rng.normal(0, 1e-3, x.size))))
    assert flann(["train", str(rec), "-o", str(out)]) == 0
    model = load_model(out)
    assert "forward_model" not in model.training and model.terms <= 3
    assert fit_forward(x, 0.2 * x).straight and not fit_forward(x, np.arctan(x - 5)).straight
