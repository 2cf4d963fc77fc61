#!/usr/bin/env python3
"""The forward curve's members odd about a null: what they change, against the free units alone.

Every figure is the forward curve inverted alone (no FLANN, no hardware: the whole flow gives
the same figures, docs/golden.md), in process, with the odd members in the Akaike average
("both") and without them ("free": the same fit's free members, weighted again, which is
the curve `flann train` wrote before the odd members).

    .venv/bin/python bench/odd_members.py filament [--n 6]
    .venv/bin/python bench/odd_members.py off-centre [--draws 16]
    .venv/bin/python bench/odd_members.py e2e --seeds 3,7,11 [--n 20]          # needs ../shared/checks
    .venv/bin/python bench/odd_members.py draws --seed 7 --index 1 [--draws 16]  # needs ../shared/checks
    .venv/bin/python bench/odd_members.py flow --seeds 202,404 [--n 30] [--sweeps 2] [--steps M] [--each]
    .venv/bin/python bench/odd_members.py units --seeds 111,222 [--n 30] [--sweeps 2] [--caps 6,8,10]
    .venv/bin/python bench/odd_members.py weights --seeds 111,222 [--n 30] [--sweeps 2]
    .venv/bin/python bench/odd_members.py oracles --seeds 111,222,333 [--n 30] [--sweeps 2]
    .venv/bin/python bench/odd_members.py spare --seeds 5150,7272,8181 [--n 30] [--sweeps 2]
    .venv/bin/python bench/odd_members.py noise-free --seeds 111,222,333 [--n 30] [--sweeps 2] [--each]

filament: random geometries of the independent forward model (`flann.physics.filament`),
161 positions x 2 over 85 % of the monotone range, noise 2e-4 of the span; the inverse's max
error against the noise-free curve.  off-centre: an arctan with a 2 % gain step on 0..20 mm,
the null at 10, 6 and 3 mm, 150 positions x 2, 1 mV.  e2e: the shared check's sensors
(`draw`, `recordings`, `oracle_reference`), held-out max error / the oracle's, median,
geometric mean and worst per seed.  draws: one of those sensors recorded again with new noise
draws (generator seed 99).  flow: the whole flow instead of the curve alone, in process
(`flann train` through `flann.cli.main`, the written model on the held-out points as
`flann eval` clamps them), on both cores: the figures `e2e_sensors.py` prints, without
`flann gen`; against other code with PYTHONPATH=<worktree>/gen.  units: the curve alone on
the check's sensors with the units capped at each of ``--caps`` (no growth past the cap), and
whether six units miss the readings (the growth's test, as `flann train` makes it).
weights: the same members weighted by other rules than Akaike's (AICc, Bayes', 3 per
parameter, the best member alone, the fewest parameters the repeats accept).  oracles: how far apart two fits that both know the
check's formula land: the check's oracle (least squares) against the same formula fitted with
a soft-L1 loss (as good under Gaussian noise, a different estimator), held-out max error of
the second / the first: the spread the metric has when nothing is wrong with either fit.
spare: the check's formula with one or two generic terms to spare (a linear, then also a
cubic term in the position), least squares, over the check's oracle: how far a fit that
knows the form lands once it has room to follow the noise, which any fit that does not know
the form has more of.
noise-free: the curve fitted to the readings and to the noise-free curve at the same
positions, each over the oracle on the readings: how much of the error is bias, how much noise.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import io
import sys
import tempfile
import warnings
from multiprocessing import Pool
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from flann.cli import main as flann
from flann.commands.predict import predict_clamped
from flann.golden import sigmoids
from flann.golden.forward import noise_floor_v
from flann.golden.inverse import invert
from flann.golden.model import load_model
from flann.physics import filament
from flann.recordings import converter_step

E2E = Path(__file__).resolve().parents[2] / "shared" / "checks" / "e2e_sensors.py"


def free_only(fw: sigmoids.SigmoidForward, x, v) -> sigmoids.SigmoidForward:
    """The same fit's free members weighted again: the curve without the odd members (the
    module's own averaging, reached into on purpose: no public switch is worth adding)."""
    free = [m for m in fw.members if m.shape is sigmoids._Free]
    return sigmoids._averaged(free, scaled(fw, np.asarray(x, float), np.asarray(v, float)),
                              (fw.x_lo, fw.x_hi, fw.v_mid, fw.v_half))


def inverse_max(curve, lo: float, hi: float, xt, vt) -> float:
    return float(np.max(np.abs(invert(curve, lo, hi, vt, points=40001) - xt)))


def both_and_free(x, v, lo, hi, xt, vt) -> tuple[float, float, float]:
    fw = sigmoids.fit_forward(x, v)
    return (inverse_max(fw, lo, hi, xt, vt), inverse_max(free_only(fw, x, v), lo, hi, xt, vt),
            fw.describe()["odd_about_null"]["weight"])


def run_filament(a) -> None:
    for seed in range(a.n):
        rng = np.random.default_rng(seed)
        m = filament.random_geometry(rng)
        half = filament.monotonic_half_range(m)
        x = np.repeat(np.linspace(-half, half, 161), 2)
        clean = filament.output_v(m, x)
        v = clean + rng.normal(0, 2e-4 * np.ptp(clean), x.size)
        xt = np.linspace(-half, half, 3001)
        both, free, w = both_and_free(x, v, -half, half, xt, filament.output_v(m, xt))
        print(f"geometry {seed}: half range {half:.2f} mm, odd weight {w:.2f}, inverse max error "
              f"both {both:.4g} mm, free {free:.4g} mm", flush=True)


def run_off_centre(a) -> None:
    for null in (10.0, 6.0, 3.0):
        def truth(x, null=null):
            return (1 + 0.02 * np.sign(x - null)) * 2 * np.arctan((x - null) / 6.0)
        r = []
        for k in range(a.draws):
            rng = np.random.default_rng(100 + k)
            x = np.repeat(np.linspace(0, 20, 150), 2)
            xt = np.linspace(0, 20, 3001)
            r.append(both_and_free(x, truth(x) + rng.normal(0, 1e-3, x.size), 0, 20, xt, truth(xt)))
        r = np.array(r)
        q = r[:, 0] / r[:, 1]
        print(f"null at {null:g} mm: geometric mean both / free {np.exp(np.mean(np.log(q))):.3f}, "
              f"better by > 5 % {int(np.sum(q < 0.95))}, worse {int(np.sum(q > 1.05))} of {a.draws}; "
              f"median odd weight {np.median(r[:, 2]):.2f}", flush=True)


def e2e_module():
    if not E2E.is_file():
        sys.exit(f"error: {E2E} not found (the shared check sits beside the project)")
    spec = importlib.util.spec_from_file_location("e2e_sensors", E2E)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def check_sensor(seed: int, index: int, sweeps: int, steps: int = 0):
    """(the check, parameters, recordings (x, v, direction), held-out points (x, v)) of sensor
    ``index`` of ``seed``: the check's own draws, ``steps`` positions a sweep when not 0."""
    e2e = e2e_module()
    rng = np.random.default_rng(seed)
    for _ in range(index + 1):
        p = e2e.draw(rng)
        if steps:
            p["steps"] = steps
        recorded, held, _lsb, _limit = e2e.recordings(p, rng, sweeps)
    return e2e, p, recorded, held


def per_seed(a, work, *extra):
    """(seed, ``work``'s results for the seed's ``a.n`` sensors) per seed of ``a.seeds``, on
    both cores; each job is (seed, index, sweeps, *extra)."""
    with Pool(2) as pool:
        for seed in (int(s) for s in a.seeds.split(",")):
            yield seed, pool.map(work, [(seed, i, a.sweeps, *extra) for i in range(a.n)], chunksize=1)


def ratios(e2e, p, rng) -> tuple[float, float]:
    (xs, v, _d), (xt, vt), _lsb, _limit = e2e.recordings(p, rng, 2)
    oracle = e2e.oracle_reference(p, xs, v, xt, vt)
    both, free, _w = both_and_free(xs, v, xs.min(), xs.max(), xt, vt)
    return both / oracle, free / oracle


def summary(label: str, r: np.ndarray) -> str:
    return (f"{label}: median {np.median(r):.2f}, geometric mean {np.exp(np.mean(np.log(r))):.3f}, "
            f"worst {r.max():.2f}")


def run_e2e(a) -> None:
    e2e = e2e_module()
    for seed in (int(s) for s in a.seeds.split(",")):
        rng = np.random.default_rng(seed)
        r = np.array([ratios(e2e, e2e.draw(rng), rng) for _ in range(a.n)])
        print(f"seed {seed}, {a.n} sensors, held-out max error / oracle: "
              f"{summary('both', r[:, 0])}; {summary('free', r[:, 1])}", flush=True)


def run_draws(a) -> None:
    e2e, p, _recorded, _held = check_sensor(a.seed, a.index, 2)
    again = np.random.default_rng(99)
    r = np.array([ratios(e2e, p, again) for _ in range(a.draws)])
    print(f"seed {a.seed} #{a.index}, {a.draws} new noise draws, held-out max error / oracle: "
          f"{summary('both', r[:, 0])}; {summary('free', r[:, 1])}")


def flow_ratio(job) -> float:
    """Held-out max error / oracle of sensor ``index`` of ``seed`` through `flann train`."""
    seed, index, sweeps, steps = job
    e2e, p, (xs, v, d), (xt, vt) = check_sensor(seed, index, sweeps, steps)
    with tempfile.TemporaryDirectory() as t:
        rec, out = Path(t) / "rec.csv", Path(t) / "model.json"
        e2e.write_csv(str(rec), (xs, v, d), ("displacement_mm", "voltage_v", "direction"))
        with warnings.catch_warnings(), contextlib.redirect_stderr(io.StringIO()):
            warnings.simplefilter("ignore")
            if flann(["train", str(rec), "-o", str(out)]) != 0:
                return float("nan")
            err = np.max(np.abs(predict_clamped(load_model(out), vt, None)[0] - xt))
    return float(err / e2e.oracle_reference(p, xs, v, xt, vt))


def run_flow(a) -> None:
    for seed, got in per_seed(a, flow_ratio, a.steps):
        r = np.array(got)
        if a.each:
            print(f"seed {seed}: " + " ".join(f"#{i} {x:.2f}" for i, x in enumerate(r)), flush=True)
        print(f"seed {seed}, {a.n} sensors, {a.sweeps} sweep(s), the whole flow, held-out max error / "
              f"oracle: {summary('flann', r[~np.isnan(r)])}; not through: {int(np.isnan(r).sum())}",
              flush=True)


def scaled(fw: sigmoids.SigmoidForward, x, v):
    """The readings averaged per position, in ``fw``'s normalised x and v."""
    return sigmoids._scaled(x, v, fw.x_lo, fw.x_hi, fw.v_mid, fw.v_half)


def train_floor(fw: sigmoids.SigmoidForward, v) -> float:
    """The floor `flann train` gives the misfit test (the readings' converter step), in
    ``fw``'s normalised v."""
    return noise_floor_v(v, converter_step(v)) / fw.v_half


def units_ratios(job) -> tuple[bool, list[float]]:
    seed, index, sweeps, caps = job
    warnings.filterwarnings("ignore")
    e2e, p, (xs, v, _d), (xt, vt) = check_sensor(seed, index, sweeps)
    oracle = e2e.oracle_reference(p, xs, v, xt, vt)
    six = sigmoids.fit_forward(xs, v, more_units=sigmoids.MAX_UNITS)
    misfit = sigmoids._misfit(list(six.members), scaled(six, xs, v), train_floor(six, v))
    return misfit, [inverse_max(sigmoids.fit_forward(xs, v, max_units=k, more_units=k), xs.min(), xs.max(),
                                xt, vt) / oracle for k in caps]


def run_units(a) -> None:
    caps = [int(k) for k in a.caps.split(",")]
    for seed, got in per_seed(a, units_ratios, caps):
        r = np.array([g[1] for g in got])
        print(f"seed {seed}, {a.n} sensors, {a.sweeps} sweep(s), the curve alone, held-out max error / oracle: "
              + "; ".join(summary(f"K <= {k}", r[:, j]) for j, k in enumerate(caps))
              + f"; six units miss the readings on {sum(g[0] for g in got)}", flush=True)


WEIGHT_RULES = ("Akaike", "AICc", "Bayes", "3 per parameter", "best alone",
                "smallest accepted (p > 0.05)", "smallest accepted (p > 0.01)", "accepted, up to 2 more (p > 0.05)")


def accepted(fw: sigmoids.SigmoidForward, d, floor: float, p_min: float) -> np.ndarray:
    """Which members the repeats accept: the misfit test's p-value above ``p_min``."""
    return np.array([(p := sigmoids._misfit_p(u, d, floor)) is not None and p > p_min for u in fw.members])


def weight_ratios(job) -> list[float]:
    seed, index, sweeps = job
    warnings.filterwarnings("ignore")
    e2e, p, (xs, v, _d), (xt, vt) = check_sensor(seed, index, sweeps)
    oracle = e2e.oracle_reference(p, xs, v, xt, vt)
    fw = sigmoids.fit_forward(xs, v, step_v=converter_step(v))     # as `flann train` fits it
    d = scaled(fw, xs, v)
    fit, k, m = sigmoids.criterion_terms(fw.members, d)
    sse = np.array([u.sse for u in fw.members])
    aic = fit + 2 * k
    crits = [aic, aic + 2 * k * (k + 1) / np.maximum(m - k - 1, 1), fit + np.log(m) * k,
             fit + 3 * k, alone(np.arange(k.size) == np.argmin(aic))]
    # the fewest parameters the repeats accept, alone (the closest of that size) or with the
    # accepted members up to 2 parameters more under Akaike's weights; none accepted: Akaike's
    for p_min, more in ((0.05, None), (0.01, None), (0.05, 2)):
        ok = accepted(fw, d, train_floor(fw, v), p_min)
        if not ok.any():
            crits.append(aic)
        elif more is None:
            fewest = ok & (k == k[ok].min())
            crits.append(alone(fewest & (sse == sse[fewest].min())))
        else:
            crits.append(np.where(ok & (k <= k[ok].min() + more), aic, np.inf))
    out = []
    for c in crits:
        w = np.exp(-0.5 * (c - c.min()))
        curve = sigmoids.SigmoidForward(fw.members, w / w.sum(), fw.x_lo, fw.x_hi, fw.v_mid, fw.v_half)
        out.append(inverse_max(curve, xs.min(), xs.max(), xt, vt) / oracle)
    return out


def alone(chosen: np.ndarray) -> np.ndarray:
    """A criterion that gives the ``chosen`` member all the weight."""
    return np.where(chosen, 0.0, np.inf)


def run_weights(a) -> None:
    for seed, got in per_seed(a, weight_ratios):
        r = np.array(got)
        print(f"seed {seed}, {a.n} sensors, {a.sweeps} sweep(s), the curve alone, held-out max error / oracle: "
              + "; ".join(summary(rule, r[:, j]) for j, rule in enumerate(WEIGHT_RULES)), flush=True)


def robust_oracle(e2e, p, xs, v, xt, vt) -> float:
    """The check's oracle fitted with a soft-L1 loss in noise units instead of least squares."""
    def curve(th, x):
        return e2e.s_curve(x, {**p, **dict(zip(e2e.ORACLE_KEYS, th))})
    th0 = np.array([p[k] for k in e2e.ORACLE_KEYS])
    th0 = th0 * np.array([1.02, 1.02, 1.01, 1.0, 1.0, 1.0]) + np.array([0, 0, 0, 0.001, 0.0005, 0.01])
    fit = least_squares(lambda th: (curve(th, xs) - v) / p["noise_v"], th0, loss="soft_l1")
    return inverse_max(lambda x: curve(fit.x, x), xs.min(), xs.max(), xt, vt)


def oracle_ratio(job) -> float:
    seed, index, sweeps = job
    e2e, p, (xs, v, _d), (xt, vt) = check_sensor(seed, index, sweeps)
    return robust_oracle(e2e, p, xs, v, xt, vt) / e2e.oracle_reference(p, xs, v, xt, vt)


def spare_oracle(e2e, p, xs, v, xt, vt, spare: int) -> float:
    """The check's formula with ``spare`` generic terms added (z, then z^3, z the position from
    the null in spans), least squares: a fit that knows the form and has a little room to spare."""
    powers = (1, 3)[:spare]

    def curve(th, x):
        z = (x - p["null_mm"]) / p["span_mm"]
        return (e2e.s_curve(x, {**p, **dict(zip(e2e.ORACLE_KEYS, th))})
                + sum(c * z ** k for c, k in zip(th[len(e2e.ORACLE_KEYS):], powers)))
    th0 = np.array([p[k] for k in e2e.ORACLE_KEYS])
    th0 = th0 * np.array([1.02, 1.02, 1.01, 1.0, 1.0, 1.0]) + np.array([0, 0, 0, 0.001, 0.0005, 0.01])
    fit = least_squares(lambda th: curve(th, xs) - v, np.concatenate([th0, np.zeros(spare)]))
    return inverse_max(lambda x: curve(fit.x, x), xs.min(), xs.max(), xt, vt)


def spare_ratios(job) -> tuple[float, float]:
    seed, index, sweeps = job
    e2e, p, (xs, v, _d), (xt, vt) = check_sensor(seed, index, sweeps)
    oracle = e2e.oracle_reference(p, xs, v, xt, vt)
    return tuple(spare_oracle(e2e, p, xs, v, xt, vt, k) / oracle for k in (1, 2))


def run_spare(a) -> None:
    for seed, got in per_seed(a, spare_ratios):
        r = np.array(got)
        print(f"seed {seed}, {a.n} sensors, {a.sweeps} sweep(s), held-out max error / the check's oracle: "
              f"{summary('the formula + a linear term', r[:, 0])}; "
              f"{summary('+ a linear and a cubic term', r[:, 1])}", flush=True)


def run_oracles(a) -> None:
    label = "the soft-L1 oracle / the check's"
    for seed, got in per_seed(a, oracle_ratio):
        r = np.array(got)
        print(f"seed {seed}, {a.n} sensors, {a.sweeps} sweep(s), held-out max error, {summary(label, r)}, "
              f"best {r.min():.2f}", flush=True)


def noise_free_ratios(job) -> tuple[float, float]:
    """(the curve fitted as `flann train` fits it, the same fitted to the noise-free curve at
    the same positions), held-out max error / the oracle's on the noisy readings: the second
    is the bias alone, the rest of the first is the noise's."""
    seed, index, sweeps = job
    e2e, p, (xs, v, _d), (xt, vt) = check_sensor(seed, index, sweeps)
    oracle = e2e.oracle_reference(p, xs, v, xt, vt)
    noisy = sigmoids.fit_forward(xs, v, step_v=converter_step(v))
    clean = sigmoids.fit_forward(xs, e2e.s_curve(xs, p))
    return tuple(inverse_max(fw, xs.min(), xs.max(), xt, vt) / oracle for fw in (noisy, clean))


def run_noise_free(a) -> None:
    for seed, got in per_seed(a, noise_free_ratios):
        r = np.array(got)
        if a.each:
            print(f"seed {seed}: " + " ".join(f"#{i} {x:.2f} ({y:.2f})" for i, (x, y) in enumerate(r)), flush=True)
        print(f"seed {seed}, {a.n} sensors, {a.sweeps} sweep(s), the curve alone, held-out max error / oracle: "
              f"{summary('noisy readings', r[:, 0])}; {summary('noise-free', r[:, 1])}", flush=True)


def seeded(sub, name: str, seeds: str) -> argparse.ArgumentParser:
    """A mode over the check's sensors: --seeds, --n a seed, --sweeps."""
    p = sub.add_parser(name)
    p.add_argument("--seeds", default=seeds)
    p.add_argument("--n", type=int, default=30)
    p.add_argument("--sweeps", type=int, default=2)
    return p


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="what", required=True)
    sub.add_parser("filament").add_argument("--n", type=int, default=6)
    sub.add_parser("off-centre").add_argument("--draws", type=int, default=16)
    e = sub.add_parser("e2e")
    e.add_argument("--seeds", default="3,7,11")
    e.add_argument("--n", type=int, default=20)
    d = sub.add_parser("draws")
    d.add_argument("--seed", type=int, default=7)
    d.add_argument("--index", type=int, default=1)
    d.add_argument("--draws", type=int, default=16)
    f = seeded(sub, "flow", "202,404")
    f.add_argument("--steps", type=int, default=0, help="positions per sweep (0: the check's draw)")
    f.add_argument("--each", action="store_true", help="also each sensor's ratio")
    seeded(sub, "units", "111,222").add_argument("--caps", default="6,8,10")
    seeded(sub, "weights", "111,222")
    seeded(sub, "oracles", "111,222,333")
    seeded(sub, "spare", "5150,7272,8181")
    seeded(sub, "noise-free", "111,222,333").add_argument("--each", action="store_true",
                                                           help="also each sensor's ratios")
    a = ap.parse_args()
    warnings.filterwarnings("ignore")   # scipy's optimiser warnings on hopeless starts
    {"filament": run_filament, "off-centre": run_off_centre, "e2e": run_e2e, "draws": run_draws,
     "flow": run_flow, "units": run_units, "weights": run_weights, "oracles": run_oracles, "spare": run_spare,
     "noise-free": run_noise_free}[a.what](a)
    return 0


if __name__ == "__main__":
    sys.exit(main())
