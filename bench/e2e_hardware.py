"""Hardware accuracy on sensors drawn from a closed-form family: train -> gen -> eval --design.

Each sensor is a saturating S-curve written here (not the project's physics): random stroke,
sensitivity, roll-off sharpness, asymmetric gain, sign, origin (null in the middle, or the
travel starting at 0), step count, noise and ADC width.  Its forward+reverse recordings go
through the tool's defaults exactly as a user runs them::

    flann train REC.csv -o model.json
    flann gen model.json -o hdl --input-bits B --input-lsb-v LSB
    flann eval model.json HELDOUT.csv --design hdl --json

and the row is the *hardware's* held-out max error (the design's bit-true twin on the held-out
voltages as ADC codes; held-out points are noise-free and quantised), the physical limit (half
an ADC LSB over the sensor's true local slope, worst over the stroke) and their ratio, next to
the float model's ratio and a smoothing spline x(v) (scipy, GCV) fitted to the same recordings.
``noise/LSB`` is the recording noise in ADC codes: where it is large the ratio is set by the
noise, not the converter.

    .venv/bin/python bench/e2e_hardware.py [--n 20] [--seed 21]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from flann.cli import main as flann
from flann.hardware.accuracy import physical_limit_mm


def s_curve(x, p):
    """Saturating S-curve: slope 1 at the null, roll-off to +-1, asymmetric gain, in volts."""
    u = (x - p["null_mm"]) / p["width_mm"]
    shape = u / (1 + np.abs(u) ** p["sharp"]) ** (1 / p["sharp"])
    return p["sign"] * p["amp_v"] * np.where(u >= 0, 1 + p["asym"], 1 - p["asym"]) * shape + p["offset_v"]


def draw(rng) -> dict:
    stroke = float(rng.choice([2.0, 5.0, 10.0, 25.0, 50.0, 100.0]))   # half travel, mm
    from_zero = bool(rng.integers(0, 2))
    return dict(stroke_mm=stroke, from_zero=from_zero, null_mm=stroke if from_zero else 0.0,
                width_mm=stroke * rng.uniform(0.45, 0.9), sharp=rng.uniform(1.5, 4.0),
                amp_v=rng.uniform(0.5, 8.0), asym=rng.uniform(-0.04, 0.04),
                sign=float(rng.choice([1, -1])), offset_v=rng.uniform(-0.01, 0.01),
                noise_v=rng.uniform(0.0002, 0.003), bits=int(rng.choice([12, 14, 16])),
                steps=int(rng.integers(60, 400)))


def recordings(p, rng):
    lo, hi = (0.0, 2 * p["stroke_mm"]) if p["from_zero"] else (-p["stroke_mm"], p["stroke_mm"])
    x = np.linspace(lo, hi, p["steps"])
    xs = np.concatenate([x, x[::-1]])
    direction = np.concatenate([np.ones_like(x), -np.ones_like(x)])
    vmax = float(np.max(np.abs(s_curve(np.array([lo, hi]), p)))) * 1.05
    lsb = float(f"{2 * vmax / 2 ** p['bits']:.9g}")
    v = np.round((s_curve(xs, p) + rng.normal(0, p["noise_v"], xs.size)) / lsb) * lsb
    xt = np.sort(rng.uniform(lo, hi, 2000))
    vt = np.round(s_curve(xt, p) / lsb) * lsb
    return (xs, v, direction), (xt, vt), lsb, true_limit_mm(p, lo, hi, lsb)


class TrueInverse:
    """The sensor's true x(v) (its curve inverted on a fine grid), as a model for
    :func:`physical_limit_mm`: the limit is the sensor's, not the trained model's.  Its range
    is the stroke's; the grid reaches past it, where a code's bin at the stroke's end does."""

    def __init__(self, p, lo, hi, points=20001):
        pad = 0.05 * (hi - lo)
        x = np.linspace(lo - pad, hi + pad, points)
        v = s_curve(x, p)
        order = np.argsort(v)   # the curve falls with x when its sign is negative
        self.v, self.x = v[order], x[order]
        self.voltage_range_v = tuple(sorted(float(e) for e in s_curve(np.array([lo, hi]), p)))

    def predict(self, voltage_v):
        return np.interp(voltage_v, self.v, self.x)


def true_limit_mm(p, lo, hi, lsb) -> float:
    """The physical limit (flann eval's rule) on the true curve, worst over the stroke."""
    inv = TrueInverse(p, lo, hi)
    return float(np.max(physical_limit_mm(inv, s_curve(np.linspace(lo, hi, 20001), p), lsb)))


def spline_max_error(v, x, vt, xt) -> float:
    """The lookup-table alternative: a smoothing spline x(v) (GCV) on the same recordings."""
    from scipy.interpolate import make_smoothing_spline  # lazy: only this yardstick needs it

    order = np.argsort(v)
    vu, inv = np.unique(v[order], return_inverse=True)
    xu = np.bincount(inv, weights=x[order]) / np.bincount(inv)
    f = make_smoothing_spline(vu, xu)
    return float(np.max(np.abs(f(np.clip(vt, vu[0], vu[-1])) - xt)))


def write_csv(path: Path, cols: dict) -> Path:
    rows = zip(*cols.values())
    path.write_text(",".join(cols) + "\n" + "".join(",".join(f"{c:.9g}" for c in r) + "\n" for r in rows))
    return path


def cli(*argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = flann([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def one_sensor(p, rng, tmp: Path) -> dict:
    (xs, v, d), (xt, vt), lsb, limit = recordings(p, rng)
    rec = write_csv(tmp / "rec.csv", {"displacement_mm": xs, "voltage_v": v, "direction": d})
    held = write_csv(tmp / "held.csv", {"displacement_mm": xt, "voltage_v": vt})
    model, hdl = tmp / "model.json", tmp / "hdl"
    row = {"limit_mm": limit, "noise_lsb": p["noise_v"] / lsb, "spline_mm": spline_max_error(v, xs, vt, xt)}
    for step, argv in (("train", ("train", rec, "-o", model)),
                       ("gen", ("gen", model, "-o", hdl, "--input-bits", p["bits"], "--input-lsb-v", f"{lsb:.9g}")),
                       ("eval", ("eval", model, held, "--design", hdl, "--json"))):
        rc, out, err = cli(*argv)
        if rc != 0:
            return {**row, "failed": f"{step}: {(err.strip().splitlines() or ['?'])[-1][:90]}"}
    res = json.loads(out)
    terms = json.loads(model.read_text())["terms"]
    return {**row, "failed": "", "hw_mm": res["hardware"]["max_error_mm"],
            "float_mm": res["compensated"]["max_error_mm"], "terms": terms,
            "output_lsb_mm": res["hardware"]["output_lsb_mm"]}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20, help="sensors (default %(default)s)")
    ap.add_argument("--seed", type=int, default=21, help="family seed (default %(default)s)")
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    tty = sys.stderr.isatty()
    print(f"{'#':>2} {'stroke':>6} {'bits':>4} {'origin':>6} {'noise/LSB':>9} {'terms':>5} {'hw max mm':>10} "
          f"{'limit mm':>9} {'hw ratio':>8} {'float ratio':>11} {'spline ratio':>12}")
    rows, t0 = [], time.perf_counter()
    for i in range(a.n):
        p = draw(rng)
        with tempfile.TemporaryDirectory(prefix="e2e_hw_") as tmp:
            r = one_sensor(p, rng, Path(tmp))
        rows.append(r)
        head = (f"{i:>2} {p['stroke_mm']:>6g} {p['bits']:>4} {'0..2L' if p['from_zero'] else '+-L':>6} "
                f"{r['noise_lsb']:>9.2f}")
        if r["failed"]:
            print(f"{head}  FAILED {r['failed']}")
        else:
            lim = r["limit_mm"]
            print(f"{head} {r['terms']:>5} {r['hw_mm']:>10.4g} {lim:>9.3g} {r['hw_mm'] / lim:>8.2f} "
                  f"{r['float_mm'] / lim:>11.2f} {r['spline_mm'] / lim:>12.2f}")
        if tty:
            print(f"\r{i + 1}/{a.n} sensors, {time.perf_counter() - t0:.0f} s", end="", file=sys.stderr, flush=True)
    if tty:
        print(file=sys.stderr)
    ok = [r for r in rows if not r["failed"]]
    if ok:
        hw = np.array([r["hw_mm"] / r["limit_mm"] for r in ok])
        fl = np.array([r["float_mm"] / r["limit_mm"] for r in ok])
        sp = np.array([r["spline_mm"] / r["limit_mm"] for r in ok])
        print(f"hardware max error / physical limit: median {np.median(hw):.2f}, worst {hw.max():.2f} "
              f"(float model: median {np.median(fl):.2f}, worst {fl.max():.2f})")
        print(f"hardware max error <= the smoothing spline's on {int(np.sum(hw <= sp))}/{len(ok)} sensors "
              f"(spline ratio: median {np.median(sp):.2f}, worst {sp.max():.2f})")
    print(f"{len(ok)}/{a.n} sensors went through train -> gen -> eval --design "
          f"({time.perf_counter() - t0:.0f} s)")
    return 0 if len(ok) == a.n else 1


if __name__ == "__main__":
    sys.exit(main())
