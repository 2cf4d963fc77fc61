"""Reporting a :class:`~flann.diagnose.core.Diagnosis`: JSON, text and the residual plot."""

from __future__ import annotations

import math

import numpy as np

from ..fileio import atomic_save_figure
from .data import running_mean, window_size


def _num(v: float) -> float:
    v = float(v)
    return v if math.isfinite(v) else None  # JSON has no inf/nan


def to_json(dg) -> dict:
    """The issue's JSON, keys exactly as specified (params as {"value", "stderr", "unit"}),
    and "reduced" when a long recording was diagnosed on means of its readings."""
    out = {
        "baseline": {"rms_v": _num(dg.baseline_rms), "params": _params(dg.baseline_params),
                     "ideal_rms_v": _num(dg.ideal_rms),
                     "shape_term": _clean(dg.shape_description),
                     "noise_method": dg.noise_method,
                     "noise_by_region": _clean(dg.noise_regions)},
        "noise_v": _num(dg.noise_v),
        "regions": [{"from_mm": _num(r["from_mm"]), "to_mm": _num(r["to_mm"]),
                     "direction": r["direction"], "peak_residual_v": _num(r["peak_residual_v"])}
                    for r in dg.regions],
        "outliers": [{"row": int(o["row"]), "displacement_mm": _num(o["displacement_mm"]),
                      "residual_v": _num(o["residual_v"])} for o in dg.outliers],
        "effects": [_effect(e) for e in dg.effects],
        # other sets of effects that explain the recordings as well as "effects" (the
        # choice), ranked, and the measurements that would tell them apart
        "alternatives": [{"effects": [{"name": e.name, "explanation": e.explanation,
                                       "params": _params(e.params)} for e in a.effects],
                          "delta_bic": _num(a.delta_bic), "rms_v": _num(a.rms_v),
                          "differs_most_at_mm": _num(a.differs_most_at_mm),
                          "difference_v": _num(a.difference_v),
                          **({"note": a.note} if a.note else {})} for a in dg.alternatives],
        "separate_by": [{"effects": [x for x in (s.a, s.b) if x], "measurement": s.measurement,
                         "why": s.why} for s in dg.separate_by],
        "final": {"rms_v": _num(dg.final_rms)},
        "improvement": _num(dg.baseline_rms / dg.final_rms) if dg.final_rms > 0 else None,
    }
    if dg.reduced:
        out["reduced"] = dict(dg.reduced)
    return out


def _effect(e) -> dict:
    out = {"name": e.name, "explanation": e.explanation, "params": _params(e.params),
           "rms_v_after": _num(e.rms_v_after), "delta_bic": _num(e.delta_bic),
           "cv_t": _num(e.cv_t)}
    if e.evidence_note:
        out["not_computable"] = e.evidence_note
    return out


def _params(params: dict) -> dict:
    """Parameters as JSON: one the recordings do not determine has no value, only its fit."""
    out = {}
    for k, p in params.items():
        if p.get("determined", True):
            out[k] = _clean(p)
        else:
            out[k] = {"value": None, "fitted_value": _num(p["value"]), "stderr": _num(p["stderr"]),
                      "unit": p["unit"], "determined": False}
            if p.get("why"):
                out[k]["why"] = p["why"]
    return out


def _clean(obj):
    """JSON-safe copy (no inf/nan)."""
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_clean(v) for v in obj]
    if isinstance(obj, float):
        return _num(obj)
    return obj


def _fmt_param(name: str, p: dict) -> str:
    unit = f" {p['unit']}" if p.get("unit") else ""
    se = p.get("stderr")
    if isinstance(p.get("value"), str):
        return f"{name} = {p['value']}"
    if p.get("why"):
        return (f"{name} not determined by these recordings ({p['why']}; fitted "
                f"{p['value']:.3g}{unit})")
    if not p.get("determined", True):
        return (f"{name} not determined by these recordings (its uncertainty ±{se:.2g}{unit} "
                f"exceeds the fitted {p['value']:.3g}{unit})")
    if se is None or not math.isfinite(se):
        return f"{name} = {p['value']:.6g}{unit}"
    return f"{name} = {p['value']:.6g} ± {se:.2g}{unit}"


def _mv(v: float) -> str:
    return f"{v * 1e3:.3g} mV"


def _set(names) -> str:
    return "{" + (" + ".join(names) or "nothing") + "}"


def _evidence(e) -> str:
    """delta BIC and cross-validation t, or why they are not computable (never "nan")."""
    if math.isfinite(e.delta_bic) and math.isfinite(e.cv_t):
        return f"delta BIC {e.delta_bic:.1f}, cross-validation t = {e.cv_t:.1f}"
    why = e.evidence_note or "no fit to compare with"
    if math.isfinite(e.delta_bic):
        return f"delta BIC {e.delta_bic:.1f}, cross-validation t not computable ({why})"
    return f"delta BIC and cross-validation t {why}"


def format_text(dg) -> str:
    lines = [f"{dg.source}: {dg.n_used} of {dg.n} points, {dg.passes_text}"]
    for note in dg.notes:
        lines.append(f"note: {note}")
    lines.append(f"calibrated ideal simulation ({dg.calibration_text}): RMS residual "
                 f"{_mv(dg.baseline_rms)}")
    lines.append("  " + "; ".join(_fmt_param(k, v) for k, v in dg.baseline_params.items()))
    sd = dg.shape_description
    if sd:
        lines.append(f"shape of this sensor (smooth, odd term; not an effect): {sd['description']}; "
                     f"with the named effects switched off the fitted curve differs from the "
                     f"calibrated ideal simulation by {_mv(sd['rms_v'])} RMS, up to "
                     f"{_mv(sd['peak_v'])} (beyond a change of gain); ideal simulation alone "
                     f"leaves {_mv(dg.ideal_rms)}")
    lines.append(f"noise: {_mv(dg.noise_v)} (1 sigma), {dg.noise_method}")
    if dg.noise_regions:
        lines.append("  by region: " + "; ".join(
            f"{r['from_mm']:.3g}..{r['to_mm']:.3g} mm {_mv(r['noise_v'])}" for r in dg.noise_regions))
    if dg.outliers:
        lines.append(f"isolated outliers ({len(dg.outliers)}, measurement glitches, left out of "
                     "the fits):")
        for o in dg.outliers:
            times = (f" ({abs(o['residual_v']) / dg.noise_v:.0f} x noise)" if dg.noise_v > 0
                     else "")
            lines.append(f"  row {o['row']} at {o['displacement_mm']:g} mm: {_mv(o['residual_v'])} "
                         f"off the curve{times}")
    if dg.regions:
        lines.append("where the ideal simulation and the recordings differ beyond the noise:")
        for r in dg.regions:
            lines.append(f"  {r['from_mm']:g} .. {r['to_mm']:g} mm, direction {r['direction']}: "
                         f"residual up to {_mv(r['peak_residual_v'])}")
        if dg.time_spans:
            unit = "s" if dg.time_unit == "s" else "rows"
            spans = ", ".join(f"{a:g}..{b:g} {unit}" for a, b, _ in dg.time_spans)
            lines.append(f"  in recording time: {spans}")
    if dg.alternatives:
        lines.append(f"not decided: {len(dg.alternatives) + 1} explanations fit these recordings "
                     f"equally well (BIC within {dg.alternatives_margin:.3g} of the best, or "
                     "within what another recording of the same sensor may move it by), "
                     "ranked:")
        lines.append(f"  1. {_set(dg.named)}: the choice" + (", below" if dg.named else ""))
        for i, a in enumerate(dg.alternatives, 2):
            lines.append(f"  {i}. {_set(a.named)}: delta BIC {a.delta_bic:+.1f} against the "
                         f"choice, RMS {_mv(a.rms_v)}; its curve differs from the choice's by at "
                         f"most {_mv(a.difference_v)} (at {a.differs_most_at_mm:.3g} mm)"
                         + (f"; {a.note}" if a.note else ""))
            for e in a.effects:
                lines.append(f"     {e.name}: " + "; ".join(_fmt_param(k, v)
                                                         for k, v in e.params.items()))
        lines.append("  to tell them apart:")
        for sp in dg.separate_by:
            pair = f"{sp.a} or {sp.b}" if sp.b else sp.a
            lines.append(f"    {pair}: {sp.measurement}" + (f" ({sp.why})" if sp.why else ""))
    if not dg.effects and not dg.alternatives and not dg.regions:
        lines.append(f"nothing missing: the residual ({_mv(dg.final_rms)} RMS) is noise; "
                     "no effect of the catalogue earns its keep")
    elif not dg.effects and not dg.alternatives:
        lines.append("no effect of the catalogue explains the mismatch located above: it is "
                     "physics the catalogue lacks, or a shape the simulated geometry cannot take")
    if dg.effects:
        lines.append("physics missing from the ideal simulation (most important first)" +
                     (", if the choice is right:" if dg.alternatives else ":"))
        prev = dg.baseline_rms
        for i, e in enumerate(dg.effects, 1):
            lines.append(f"  {i}. {e.name}: {e.explanation}")
            lines.append("     " + "; ".join(_fmt_param(k, v) for k, v in e.params.items()))
            lines.append(f"     RMS {_mv(prev)} -> {_mv(e.rms_v_after)}, " + _evidence(e))
            if e.alternatives:
                lines.append(f"     fits these recordings equally well (BIC within 2): "
                             f"{', '.join(e.alternatives)}; named the simplest")
            prev = e.rms_v_after
        # a model that meets every reading exactly has no finite improvement factor
        better = (f"improvement x{dg.baseline_rms / dg.final_rms:.3g}" if dg.final_rms > 0
                  else "every reading reproduced exactly")
        lines.append(f"final RMS {_mv(dg.final_rms)} (noise {_mv(dg.noise_v)}), {better}")
    if dg.trials and dg.trials[-1]:
        last = [t for t in dg.trials[-1] if not t.accepted]
        if last:
            lines.append("  closest candidates not earning their keep (delta BIC must be < -10 and "
                         "cross-validation t > 2): " + ", ".join(
                             f"{t.name} " + (f"{t.delta_bic:+.1f}" if math.isfinite(t.delta_bic)
                                             else "(delta BIC not computable: too few points "
                                             "for its parameters, or its fit failed)")
                             + (f" (CV t {t.cv_t:.1f})"
                                                               if t.cv_t is not None else "")
                             + (f" ({t.note})" if t.note else "")
                             for t in last[:3]))
    if dg.untestable:
        lines.append("not testable on these recordings: " + "; ".join(
            f"{k} ({v})" for k, v in dg.untestable.items()))
    return "\n".join(lines) + "\n"


def _plot_alternatives(ax, dg, x, d, keep) -> None:
    """Each alternative's fitted curve minus the choice's: where a recording could tell them
    apart, against the noise of one reading and of a running mean."""
    first = keep & (d == d[0]) if d is not None else keep    # one pass: the curves repeat
    o = np.flatnonzero(first)
    o = o[np.argsort(x[o], kind="stable")]
    for a, diff in zip(dg.alternatives, dg.plot.alternative_diffs):
        ax.plot(x[o], diff[o] * 1e3, "-", lw=1.6,
                label=f"{_set(a.named)} minus {_set(dg.named)} (delta BIC {a.delta_bic:+.1f})")
    w = window_size(o.size)
    for k, ls in ((2, "--"), (2 / math.sqrt(w), ":")):
        for sgn in (-1, 1):
            ax.axhline(sgn * k * dg.noise_v * 1e3, color="0.5", lw=0.7, ls=ls)
    ax.axhline(0, color="0.3", lw=0.7)
    top = max([float(np.max(np.abs(df[o]))) for df in dg.plot.alternative_diffs]
              + [2 * dg.noise_v / math.sqrt(w)])
    ax.set_ylim(-1.6 * top * 1e3, 1.6 * top * 1e3)
    ax.set_title(f"alternatives minus the choice (dotted: ±2 noise of a mean of {w} readings; "
                 "dashed: of one)", fontsize=10)
    ax.set_ylabel("difference (mV)")
    ax.legend(fontsize=8, loc="best")


def plot(dg, path) -> None:
    """Residuals against displacement before and after the added effects, spans shaded."""
    # lazy: matplotlib is only loaded when a plot is asked for
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    arr = dg.plot
    panels = 3 if dg.alternatives else 2
    fig, axes = plt.subplots(panels, 1, figsize=(8, 3.25 * panels), sharex=True)
    x, d = arr.x, arr.direction
    keep = ~arr.outlier_mask
    title_after = ("after " + " + ".join(e.name for e in dg.effects)) if dg.effects \
        else "no effect added (nothing missing)"
    for ax, r, title in ((axes[0], arr.resid_before, "ideal simulation, calibrated"),
                         (axes[1], arr.resid_after, title_after)):
        for reg in dg.regions:
            color = {"+": "tab:red", "-": "tab:blue", "both": "tab:purple"}[reg["direction"]]
            ax.axvspan(reg["from_mm"], reg["to_mm"], color=color, alpha=0.12, lw=0)
        ms = 2.5 if x.size > 300 else 5
        if d is not None:
            for sign, color, label in ((1, "tab:red", "moving +"), (-1, "tab:blue", "moving -")):
                m = keep & (d == sign)
                if m.any():
                    ax.plot(x[m], r[m] * 1e3, ".", ms=ms, color=color, label=label)
        else:
            ax.plot(x[keep], r[keep] * 1e3, ".", ms=ms, color="k", label="points")
        # running means make a pattern below the per-point noise visible
        groups = ([(d == sign) & keep for sign in (1, -1)] if d is not None else [keep])
        for m, color in zip(groups, ("darkred", "navy") if d is not None else ("k",)):
            if m.sum() >= 5:
                o = np.flatnonzero(m)
                o = o[np.argsort(x[o], kind="stable")]
                rm, _ = running_mean(r[o], window_size(o.size))
                ax.plot(x[o], rm * 1e3, "-", color=color, lw=1.6)
        inl = r[keep] * 1e3
        lim = max(float(np.max(np.abs(inl))) if inl.size else 1.0, 3 * dg.noise_v * 1e3) * 1.25
        ax.set_ylim(-lim, lim)
        if arr.outlier_mask.any():
            # outliers drawn at the edge of the axis, their value written next to them
            ro = np.clip(r[~keep] * 1e3, -0.95 * lim, 0.95 * lim)
            ax.plot(x[~keep], ro, "x", color="tab:orange", ms=8, label="outlier (value noted)")
            for xo, yo, v in zip(x[~keep], ro, r[~keep]):
                ax.annotate(f"{v * 1e3:.0f} mV", (xo, yo), textcoords="offset points",
                            xytext=(5, -10 if yo < 0 else 4), fontsize=7, color="tab:orange")
        for k in (-2, 2):
            ax.axhline(k * dg.noise_v * 1e3, color="0.5", lw=0.7, ls="--")
        ax.axhline(0, color="0.3", lw=0.7)
        rms = math.sqrt(np.mean(r[keep] ** 2))
        ax.set_title(f"{title}: RMS {rms * 1e3:.3g} mV", fontsize=10)
        ax.set_ylabel("residual (mV)")
        ax.legend(fontsize=8, loc="best")
    if dg.alternatives:
        _plot_alternatives(axes[2], dg, x, d, keep)
    axes[-1].set_xlabel("displacement (mm)")
    fig.suptitle(f"flann diagnose: {dg.source} (shaded: located mismatch, dashed: ±2 noise)",
                 fontsize=10)
    fig.tight_layout()
    try:
        atomic_save_figure(fig, path)
    finally:
        plt.close(fig)
