"""The seed paper reproduced: Table 2, Fig. 5, and what the paper did not show.

Table 2 ("% of linearity range" for 11, 25, 51, 61 functional expansions) is recomputed
with the paper's own method: raw volts into the expansion (offset 0, scale 1), the bias
and every weight starting at 1, LMS in table order.  The paper gives neither the learning
rate nor the number of epochs; :data:`DEFAULT_ETA` and :data:`DEFAULT_EPOCHS` are our
choice (docs/golden.md shows how the 11/25-term rows move with them).

Beyond the paper: leave-one-out error of each row's model (same method, each of the 13
points held out in turn), the 51-term model between the 13 points (a dense voltage sweep
compared with a monotone interpolant of the table), and the tool's own default
(``--terms auto``) on dense data from a physics-like S-curve (:func:`s_curve`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import FlannError
from ..fileio import atomic_save_figure
from .metrics import (DEFAULT_BAND_PCT_FS, DEFAULT_TOL_PCT_FS, error_report, full_scale_mm,
                      linearity_pct, raw_line, raw_linearity_pct)
from .model import FlannModel
from ..recordings import Recordings
from .inverse import fit_default
from .train import design_matrix, fit_lms, fit_lstsq, lms_epochs, lms_leave_one_out

# The paper's Table 1 (also in data/paper_table1.csv, checked equal by the tests).
TABLE1_DISPLACEMENT_MM = np.arange(-30.0, 30.0 + 1, 5.0)
TABLE1_VOLTAGE_V = np.array([-5.185, -5.017, -4.717, -4.039, -2.896, -1.494, 0.001,
                             1.462, 1.810, 3.962, 4.799, 5.225, 5.276])
# The paper's Table 2 and its raw-sensor figure.
PAPER_TABLE2 = {11: 38.46, 25: 84.62, 51: 100.00, 61: 100.00}
PAPER_RAW_PCT = 15.38
DEFAULT_ETA = 0.02
DEFAULT_EPOCHS = 3000
SWEEP_POINTS = 2001


def table1() -> Recordings:
    return Recordings(displacement_mm=TABLE1_DISPLACEMENT_MM.copy(),
                      voltage_v=TABLE1_VOLTAGE_V.copy(), source="paper Table 1")


def paper_model(rec: Recordings, terms: int, eta: float = DEFAULT_ETA,
                epochs: int = DEFAULT_EPOCHS, offset_scale=(0.0, 1.0)) -> FlannModel:
    """One Table 2 row's model: LMS on raw volts as the paper did it."""
    return fit_lms(rec.voltage_v, rec.displacement_mm, terms, eta=eta, epochs=epochs,
                   offset_scale=offset_scale, training={"normalisation": "none (raw volts)"})


def loo_errors(rec: Recordings, terms: int, eta: float = DEFAULT_ETA,
               epochs: int = DEFAULT_EPOCHS, offset_scale=(0.0, 1.0)) -> np.ndarray:
    """Leave-one-out error (mm) at every point, same method as :func:`paper_model`."""
    off, scale = offset_scale
    S = design_matrix((rec.voltage_v - off) / scale, terms)
    return lms_leave_one_out(S, rec.displacement_mm, eta, epochs) - rec.displacement_mm


def lstsq_loo_errors(rec: Recordings, terms: int, norm: str = "range",
                     ridge: float = 0.0) -> np.ndarray:
    """Leave-one-out error (mm) of ``flann train --terms N --method lstsq`` (normalisation
    recomputed from the remaining points, as training on them would)."""
    err = np.empty(len(rec))
    for i in range(len(rec)):
        keep = np.arange(len(rec)) != i
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = fit_lstsq(rec.voltage_v[keep], rec.displacement_mm[keep], terms, norm=norm,
                          ridge=ridge)
        err[i] = m.predict(rec.voltage_v[i:i + 1])[0] - rec.displacement_mm[i]
    return err


def _strictly_increasing(x: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(voltages, displacements) for an interpolant x(v): repeated positions (more sweeps,
    dwells) are averaged per position, and positions that still read the same voltage (a
    flat stretch, a converter's grid) share one point at their mean displacement."""
    x = np.asarray(x, float)
    v = np.asarray(v, float)
    xu, inv = np.unique(x, return_inverse=True)
    vu = np.bincount(inv, weights=v) / np.bincount(inv)
    v_pts, inv = np.unique(vu, return_inverse=True)
    x_pts = np.bincount(inv, weights=xu) / np.bincount(inv)
    return v_pts, x_pts


def between_points(model: FlannModel, rec: Recordings, n: int = SWEEP_POINTS) -> dict:
    """The model on a dense sweep of v between the recorded voltages.

    Compared with the monotone (PCHIP) interpolant of the recorded points: a plausible
    sensor between the points, not the truth (which the table does not contain).
    """
    from scipy.interpolate import PchipInterpolator

    v_pts, x_pts = _strictly_increasing(rec.displacement_mm, rec.voltage_v)
    v = np.linspace(v_pts[0], v_pts[-1], n)
    y = model.predict(v)
    ref = PchipInterpolator(v_pts, x_pts)(v)
    dy = np.diff(y)
    fs = full_scale_mm(rec.displacement_mm)
    dev = np.abs(y - ref)
    return {
        "sweep_points": n,
        "max_dev_from_pchip_mm": float(dev.max()),
        "max_dev_from_pchip_pct_fs": float(100 * dev.max() / fs),
        "at_voltage_v": float(v[int(np.argmax(dev))]),
        "sweep_fraction_within_tol_of_pchip": float(np.mean(dev <= DEFAULT_TOL_PCT_FS / 100 * fs)),
        "output_range_mm": [float(y.min()), float(y.max())],
        "decreasing_fraction": float(np.mean(dy < 0)),
        "v": v, "y": y, "ref": ref,
    }


def reproduce(rec: Recordings | None = None, eta: float = DEFAULT_ETA,
              epochs: int = DEFAULT_EPOCHS, tol_pct_fs: float = DEFAULT_TOL_PCT_FS,
              offset_scale=(0.0, 1.0)) -> tuple[dict, dict]:
    """(json_dict, details). json_dict has exactly the keys ``flann paper --json`` prints."""
    rec = table1() if rec is None else rec
    x = rec.displacement_mm
    fs = full_scale_mm(x)
    rows, details = [], {"models": {}, "loo": {}, "fs_mm": fs}
    for terms, paper_pct in PAPER_TABLE2.items():
        model = paper_model(rec, terms, eta, epochs, offset_scale)
        loo = loo_errors(rec, terms, eta, epochs, offset_scale)
        details["models"][terms] = model
        details["loo"][terms] = loo
        rows.append({
            "terms": terms,
            "linearity_pct": round(linearity_pct(model.predict(rec.voltage_v), x, tol_pct_fs, fs), 2),
            "paper_pct": paper_pct,
            "loo_max_error_mm": float(np.max(np.abs(loo))),
        })
    out = {
        "raw_linearity_pct": round(raw_linearity_pct(rec.voltage_v, x, tol_pct_fs, fs), 2),
        "tolerance_pct_fs": float(tol_pct_fs),
        "rows": rows,
    }
    return out, details


# -- physics-like dense data -----------------------------------------------------------
def s_curve(displacement_mm, noise_v: float = 0.0, seed: int = 0) -> np.ndarray:
    """A differential-transformer-like S-curve (V) shaped after Table 1.

    ``v = 5.6 tanh(x / 17 mm) + 0.0004 V/mm * x * |x| / 30 mm + 1 mV`` -- saturating
    symmetric response (the core's ends approaching the secondaries), a small asymmetry
    and a null offset -- plus Gaussian noise of ``noise_v`` (seeded: deterministic).
    Not the physics simulator (gen/flann/physics/): a stand-in for demos and tests.
    """
    x = np.asarray(displacement_mm, dtype=float)
    v = 5.6 * np.tanh(x / 17.0) + 0.0004 * x * np.abs(x) / 30.0 + 0.001
    if noise_v:
        v = v + np.random.default_rng(seed).normal(0.0, noise_v, x.size)
    return v


@dataclass(frozen=True)
class DefaultFit:
    """``flann train --terms auto``'s model of a recording, what it is, and its held-out error."""

    model: FlannModel
    label: str          # "51 terms, normalisation 0.85, ridge 0, fitted to the forward curve's inverse"
    loo_text: str       # its leave-one-out error, and of what


def default_fit(rec: Recordings, cost) -> DefaultFit:
    """The model ``flann train --terms auto`` writes for ``rec`` (:func:`fit_default`), with
    the held-out error of what chose it, as its training record states it: the forward
    curve's (the FLANN follows that curve within its teacher tolerance) at the interior
    positions left out in turn, or over the direct fit's folds; else the direct fit's LOO."""
    x, v = rec.displacement_mm, rec.voltage_v
    model, choice, from_curve = fit_default(x, v, cost)
    t = model.training
    if from_curve:
        label = (f"{model.terms} terms, normalisation {t['normalisation']}, ridge {t['ridge']:g}, "
                 "fitted to the forward curve's inverse")
        heldout = t["forward_model"].get("heldout")
        loo_text = (f"its forward curve's LOO max {t['cv_heldout_max_error_mm']:.3g} mm (interior positions)"
                    if "leave_one_out" in t else
                    f"its forward curve's held-out max {heldout['max_error_mm']:.3g} mm "
                    f"({heldout['folds']} folds of positions)" if heldout else
                    "its forward curve (no held-out figure: a fold left no monotone curve)")
    else:
        label = f"{choice.terms} terms, normalisation {choice.norm}, ridge {choice.ridge:g}, the direct fit x(v)"
        loo = lstsq_loo_errors(rec, choice.terms, choice.norm, choice.ridge)
        loo_text = f"LOO max {np.max(np.abs(loo)):.3g} mm"
    return DefaultFit(model, label, loo_text)


def dense_demo(noise_v: float = 0.5e-3, band_pct_fs: float = DEFAULT_BAND_PCT_FS, cost=None) -> dict:
    """The tool's default (``--terms auto``; ``cost`` as ``flann train`` gives it) on a dense
    physics-like sweep.

    Training: 601 points, 0.1 mm steps over +-30 mm, noise seed 1.  Test: 600 points
    between the training points (0.05 mm offset), noise seed 2 -- never seen in training.
    """
    x_train = np.linspace(-30.0, 30.0, 601)
    x_test = x_train[:-1] + 0.05
    v_train = s_curve(x_train, noise_v, seed=1)
    v_test = s_curve(x_test, noise_v, seed=2)
    fit = default_fit(Recordings(displacement_mm=x_train, voltage_v=v_train), cost)
    model = fit.model
    fs = full_scale_mm(x_train)
    after = error_report(model.predict(v_test), x_test, band_pct_fs=band_pct_fs, fs_mm=fs)
    a, b = np.polyfit(v_train, x_train, 1)   # the raw sensor's line, from the training sweep
    before = error_report(a * v_test + b, x_test, band_pct_fs=band_pct_fs, fs_mm=fs)
    return {"noise_v": noise_v, "band_pct_fs": band_pct_fs, "fs_mm": fs,
            "terms": model.terms, "normalisation": model.training["normalisation"],
            "ridge": model.training["ridge"], "label": fit.label, "before": before, "after": after}


# -- Fig. 5 ----------------------------------------------------------------------------
def plot_fig5(outdir, rec: Recordings, details: dict) -> list[str]:
    """``fig5.png``: the paper's Fig. 5 panel for panel (3 x 3, (a)-(i)), and
    ``between_points_51.png``: the 51-term model between the table's points (beyond it)."""
    import matplotlib  # loaded only to plot
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    outdir = Path(outdir)
    v, x = rec.voltage_v, rec.displacement_mm
    models = details["models"]
    sweep = between_points(models[51], rec)
    fig, axes = plt.subplots(3, 3, figsize=(13, 11))
    (a, b, c), (d, e, f), (g, h, i) = axes

    slope, icpt = raw_line(v, x)
    a.plot(x, v, "o-", label="Table 1")
    a.plot(x, (x - icpt) / slope, "--", label="least-squares line")
    a.set(xlabel="displacement (mm)", ylabel="LVDT output (V)", title="(a) LVDT (nonlinear)")
    a.legend()

    b.plot(sweep["v"], sweep["y"], "-", lw=0.6, label="51 terms, dense sweep")
    b.plot(v, models[51].predict(v), "o", label="at Table 1 voltages")
    b.set(xlabel="LVDT output (V)", ylabel="FLANN output (mm)",
          title="(b) FLANN (inverse model), 51 terms")
    b.legend()

    for ax, terms, title in ((c, 51, "(c) overall response (51)"), (d, 25, "(d) FE: 25"),
                             (e, 51, "(e) FE: 51"), (f, 61, "(f) FE: 61")):
        ax.plot(x, x, "k--", lw=0.8, label="ideal y = x")
        ax.plot(x, models[terms].predict(v), "o-", label=f"LVDT + FLANN, {terms} terms")
        ax.set(xlabel="displacement (mm)", ylabel="compensated output (mm)", title=title)
        ax.legend()

    for ax, terms, tag in ((g, 25, "g"), (h, 51, "h"), (i, 61, "i")):
        mse = models[terms].training["mse_per_epoch"]
        ax.semilogy(np.arange(1, len(mse) + 1), mse)
        ax.set(xlabel="epoch", ylabel="MSE (mm$^2$)", title=f"({tag}) CR: {terms}")
    for ax in axes.flat:
        ax.grid(True)
    fig.tight_layout()
    atomic_save_figure(fig, outdir / "fig5.png", dpi=80)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(sweep["v"], sweep["y"] - sweep["ref"], lw=0.8, label="51 terms (paper LMS)")
    ax.plot(v, np.zeros_like(v), "ko", ms=3, label="Table 1 voltages")
    ax.set(xlabel="LVDT output (V)", ylabel="model - PCHIP of table (mm)",
           title="51-term model between the 13 points (beyond the paper)")
    ax.legend()
    ax.grid(True)
    fig.tight_layout()
    atomic_save_figure(fig, outdir / "between_points_51.png", dpi=80)
    plt.close(fig)
    return ["fig5.png", "between_points_51.png"]


def sensitivity(rec: Recordings | None = None, etas=(0.005, 0.01, 0.02, 0.03),
                epochs_list=(100, 300, 1000, 3000, 10000),
                tol_pct_fs: float = DEFAULT_TOL_PCT_FS, terms_list=(11, 25, 51, 61)) -> dict:
    """% of linearity range for every (terms, eta, epochs): how much the unknown LMS
    settings move Table 2.  Epochs are run incrementally (one LMS run per (terms, eta))."""
    rec = table1() if rec is None else rec
    v, x = rec.voltage_v, rec.displacement_mm
    fs = full_scale_mm(x)
    out = {}
    for terms in terms_list:
        S = design_matrix(v, terms)
        for eta in etas:
            w, done = None, 0
            for ep in sorted(epochs_list):
                try:
                    w, _ = lms_epochs(S, x, eta, ep - done, w0=w)
                    out[(terms, eta, ep)] = round(linearity_pct(S @ w, x, tol_pct_fs, fs), 2)
                except FlannError:
                    out[(terms, eta, ep)] = None  # diverged
                    break
                done = ep
    return out
