"""``flann sim --plot``: what the HDL produced against its reference, for every datapath.

A curve (what each bench entry of :mod:`flann.verify.datapaths` returns) is drawn as panel (a)
per group of series (HDL and reference over the input voltage; a two-input design: one curve
per shown temperature code, a family: one per weight image) and one panel (b) of differences
(HDL - reference) over every sample simulated, with the design's stated bound when it has one.
Every line drawn carries a legend label.
"""

from __future__ import annotations

import numpy as np

from ..fileio import atomic_save_figure

GOLDEN = "golden model (float64)"
TWIN = "bit-true twin"
# temperature codes drawn in panel (a) of a two-input design (panel (b) holds every code)
SHOWN_TEMPS = 5
DIFF_COLORS = ("C3", "C0", "C2", "C1", "C4", "C5", "C6", "C8", "C9")


def series(label: str, codes, hdl, ref) -> dict:
    return {"label": label, "codes": np.asarray(codes), "hdl": np.asarray(hdl, dtype=float),
            "ref": np.asarray(ref, dtype=float)}


def curve(panels: list[dict], *, ref: str, simulator: str, unit_mm: bool = False, bound: dict | None = None,
          diff: list[dict] | None = None, diff_label: str = "") -> dict:
    """``panels``: [{"title", "series": [series(...)]}]; values in output LSBs (``unit_mm``: in mm).
    ``diff``: panel (b)'s series ({"label", "codes", "diff", optional "ls"}), default HDL - reference of every
    series (labelled ``diff_label``, else the series' own label, else "HDL - reference");
    ``bound``: {"value", "label"} in the same unit, drawn at +-value."""
    word = "golden" if ref == GOLDEN else "twin"   # the difference panel's short name of the reference
    if diff is None:
        diff = [{"label": diff_label or s["label"] or f"HDL - {word}", "codes": s["codes"],
                 "diff": s["hdl"] - s["ref"]} for p in panels for s in p["series"]]
    return {"panels": panels, "ref": ref, "ref_word": word, "simulator": simulator, "unit_mm": unit_mm,
            "bound": bound, "diff": diff}


def shown_temperature_codes(temps, n: int = SHOWN_TEMPS) -> list[int]:
    """At most ``n`` of the simulated temperature codes, both ends included, evenly spaced."""
    temps = sorted(set(int(t) for t in temps))
    if len(temps) <= n:
        return temps
    return sorted({temps[int(round(k))] for k in np.linspace(0, len(temps) - 1, n)})


def two_input(groups: list[dict], temps, temp_lsb_c: float, *, ref: str, simulator: str,
              bound: dict | None = None, calibrated: tuple[int, int] | None = None) -> dict:
    """A two-input sweep's curve: ``groups`` [{"name", "codes", "temps", "hdl", "ref", "valid"}]
    (one per weight image, or one), arrays over every (voltage code, temperature code) simulated,
    in output LSBs; ``valid`` marks the samples whose difference counts (output clipping of a
    reference beyond the output range is not an error).  Panel (a) per group at the shown
    temperature codes (within ``calibrated``, the codes the design does not clamp, when given);
    panel (b) per group: at each voltage code the largest and smallest difference over every
    temperature code simulated."""
    inside = [t for t in temps if calibrated is None or calibrated[0] <= t <= calibrated[1]]
    shown = shown_temperature_codes(inside or temps)
    n = len(set(int(t) for t in temps))
    panels, diff = [], []
    for g in groups:
        ss = []
        for t in shown:
            k = g["temps"] == t
            ss.append(series(f"{t * temp_lsb_c:g} degC (code {t})", g["codes"][k], g["hdl"][k], g["ref"][k]))
        panels.append({"title": g["name"], "series": ss})
        d = g["hdl"] - g["ref"]
        codes, at = np.unique(g["codes"], return_inverse=True)
        hi = np.full(codes.size, -np.inf)
        lo = np.full(codes.size, np.inf)
        np.maximum.at(hi, at[g["valid"]], d[g["valid"]])
        np.minimum.at(lo, at[g["valid"]], d[g["valid"]])
        # a voltage code whose every sample is clipped has no difference to draw
        hi[~np.isfinite(hi)] = np.nan
        lo[~np.isfinite(lo)] = np.nan
        who = f" ({g['name']})" if len(groups) > 1 else ""
        diff.append({"label": f"largest over {n} temperature codes{who}", "codes": codes, "diff": hi})
        diff.append({"label": f"smallest over {n} temperature codes{who}", "codes": codes, "diff": lo,
                     "ls": "--"})
    return curve(panels, ref=ref, simulator=simulator, bound=bound, diff=diff)


def plot(c: dict, man: dict, path) -> None:
    """Draw curve ``c`` as PNG; ``man``: the design's manifest (input LSB, output LSB, clamp codes)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lsb_v = man["input_lsb_v"]
    q = 1.0 if c["unit_mm"] else man["output_lsb_mm"]
    panels = c["panels"]
    fig, axes = plt.subplots(len(panels) + 1, 1, figsize=(7, 3 + 3 * len(panels)), sharex=True, squeeze=False)
    axes = axes[:, 0]
    for n, (ax, p) in enumerate(zip(axes, panels)):
        many = len(p["series"]) > 1
        colors = plt.cm.viridis(np.linspace(0, 0.9, len(p["series"]))) if many else ["C0"]
        # every series' reference as one line (NaN between series): one artist, one label
        gap = [np.nan]
        ax.plot(np.concatenate([np.r_[s["codes"] * lsb_v, gap] for s in p["series"]]),
                np.concatenate([np.r_[s["ref"] * q, gap] for s in p["series"]]),
                lw=2.5, color="0.75", label=c["ref"], zorder=1)
        for s, col in zip(p["series"], colors):
            label = f"HDL, {s['label']}" if many else f"HDL ({c['simulator']})"
            ax.plot(s["codes"] * lsb_v, s["hdl"] * q, lw=0.8, color=col, label=label, zorder=2)
        if man.get("clamp_codes"):
            lo, hi = man["clamp_codes"]
            ax.axvspan(lo * lsb_v, hi * lsb_v, color="C2", alpha=0.06, label="trained range")
        ax.set_ylabel("displacement (mm)")
        ax.legend(loc="best", fontsize=7)
        what = f"HDL ({c['simulator']}) vs {c['ref']}" if many else f"HDL vs {c['ref']}"
        ax.set_title(f"({chr(ord('a') + n)}) {p['title'] + ': ' if p.get('title') else ''}{what}", fontsize=9)
    ax = axes[-1]
    k = -1
    for d in c["diff"]:
        # a dashed series is the lower envelope of the solid one before it: one colour for both
        k += 0 if d.get("ls") else 1
        ax.plot(d["codes"] * lsb_v, d["diff"], lw=0.7, color=DIFF_COLORS[k % len(DIFF_COLORS)],
                ls=d.get("ls", "-"), label=d["label"])
    if c["bound"]:
        b = c["bound"]["value"]
        # +bound and -bound as one line (x in axes coordinates): one artist, one label
        ax.plot([0, 1, np.nan, 0, 1], [b, b, np.nan, -b, -b], transform=ax.get_yaxis_transform(),
                ls=":", color="k", label=c["bound"]["label"])
    ax.legend(loc="best", fontsize=7)
    unit = "mm" if c["unit_mm"] else "output LSB"
    ax.set_ylabel(f"HDL - {c['ref_word']} ({unit})")
    ax.set_xlabel("input (V)")
    title = f"({chr(ord('a') + len(panels))}) difference"
    if not c["unit_mm"]:
        title += f" (1 LSB = {q} mm)"
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    try:
        atomic_save_figure(fig, path, dpi=120)
    finally:
        plt.close(fig)


__all__ = ["plot", "curve", "series", "two_input", "shown_temperature_codes", "GOLDEN", "TWIN"]
