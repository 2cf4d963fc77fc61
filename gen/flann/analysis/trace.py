"""Stage-by-stage error of the bit-true hardware against the float64 golden model.

For every input code the hardware's output error splits *exactly* (telescoping, no
approximation) into one contribution per block and term::

    out_hw - out_golden =  sum_i  w_i (t_fixed_i - t_i)        expansion  (sin/cos table, phase)
                         + sum_i  w_i (t_hw_i - t_fixed_i)      convert    (float18 only: term -> float18)
                         + sum_i  (w_hw_i - w_i) t_hw_i         weights    (ROM constants; + bias)
                         + sum_i  (p_hw_i - w_hw_i t_hw_i)      products   (multiplier rounding)
                         + sum_k  (s_k - s_k-1 - P_k)           adder      (running-sum rounding)
                         + (lin_hw - lin)                       linear     (fixed only: serial w0 v_n + bias)
                         + (out_hw - s_last)                    output     (final rounding / saturation)

where t_i, w_i are the golden term and weight, t_fixed the expansion block's output,
t_hw, w_hw, p_hw the values the datapath carries, s_k the running sum after step k and
P_k that step's products.  ``trace()`` evaluates each piece over a sweep of input codes,
ranks stages and terms by RMS contribution, finds the input span where the dominant one
is large, and states the mechanism in one sentence with the numbers that size it.

The HDL equals the twin bit for bit (the exhaustive top-level benches check every input
code), so these are also the hardware's errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import FlannError
from ..fileio import atomic_save_figure
from ..golden.model import FlannModel, term_kind
from ..hardware.registry import FORMATS, datapath
from ..numeric.fixed import nearest_codes
from ..verify.datapaths import simulate as simulate_design
from ..hardware.design import Design
from .plugin import insight, traced
from .two_input_trace import ThermalTraceResult


STAGES = ("expansion", "convert", "weights", "products", "adder", "linear", "output")
STAGE_TEXT = {
    "expansion": "sin/cos expansion (phase + table)",
    "convert": "term conversion to float18",
    "weights": "weight/bias constants",
    "products": "multiplier rounding",
    "adder": "running-sum rounding",
    "linear": "linear term + bias (serial)",
    "output": "output rounding/saturation",
}


def term_label(i: int) -> str:
    kind, m = term_kind(i)
    if kind == "lin":
        return "v_n"
    return f"{kind}({m}πv_n)" if m > 1 else f"{kind}(πv_n)"


@dataclass
class Stages:
    """Golden and hardware values of one datapath, all in model units (terms) and mm."""

    fmt: str
    codes: np.ndarray
    volts: np.ndarray
    valid: np.ndarray            # codes inside the clamp range (others are not an error)
    term_index: list[int]        # model term index of each column
    g_terms: np.ndarray          # (n, T)
    g_weights: np.ndarray        # (T,)
    g_start: np.ndarray          # (n,)
    h_fixed_terms: np.ndarray    # (n, T) expansion block output (= h_terms for fixed)
    h_terms: np.ndarray          # (n, T)
    h_weights: np.ndarray        # (T,)
    h_products: np.ndarray       # (n, T) mm
    h_start: np.ndarray          # (n,) mm
    h_running: np.ndarray        # (n, K) mm
    step_cols: list[list[int]]   # columns added at each running-sum step
    h_out: np.ndarray            # (n,) mm
    start_stage: str             # "linear" (fixed) or "weights" (float18: bias constant)
    info: dict = field(default_factory=dict)  # sig_bits: float rounding; output_lsb_mm: a fixed output
    converts: bool = False       # a fixed -> float conversion stage sits between expansion and products

    @property
    def g_out(self) -> np.ndarray:
        return self.g_start + self.g_terms @ self.g_weights


def twin_trace(top, codes=None) -> tuple:
    """(codes, the twin's trace at them): every code when ``codes`` is None."""
    codes = top.all_codes() if codes is None else np.asarray(codes, dtype=np.int64)
    return codes, top.trace(codes)


@dataclass
class Source:
    stage: str
    term: int | None             # model term index; None for bias/start; step for adder
    label: str
    contrib: np.ndarray          # (n,) mm


# -- attribution ----------------------------------------------------------------------------
def attribute(st: Stages) -> list[Source]:
    """Exact decomposition of h_out - g_out into per-stage, per-term contributions."""
    out: list[Source] = []
    gw, hw = st.g_weights[None, :], st.h_weights[None, :]
    pieces = {
        "expansion": gw * (st.h_fixed_terms - st.g_terms),
        "convert": gw * (st.h_terms - st.h_fixed_terms),
        "weights": (hw - gw) * st.h_terms,
        "products": st.h_products - hw * st.h_terms,
    }
    for stage, arr in pieces.items():
        if stage == "convert" and not st.converts:
            continue
        for col, i in enumerate(st.term_index):
            out.append(Source(stage, i, term_label(i), arr[:, col]))
    label = "bias" if st.start_stage == "weights" else "w0·v_n + bias"
    out.append(Source(st.start_stage, None, label, st.h_start - st.g_start))
    prev = st.h_start
    for k, cols in enumerate(st.step_cols):
        cur = st.h_running[:, k]
        if cols:
            step_p = st.h_products[:, cols].sum(axis=1)
            name = term_label(st.term_index[cols[0]]) if len(cols) == 1 else f"step {k}"
            out.append(Source("adder", st.term_index[cols[0]], f"+ {name}", cur - prev - step_p))
        prev = cur
    out.append(Source("output", None, "out", st.h_out - prev))
    return out


def _rms(a: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(a)))) if a.size else 0.0


def _span(volts: np.ndarray, contrib: np.ndarray, bins: int = 16, frac: float = 0.5) -> dict:
    """Where a contribution is large: the input range is cut into ``bins`` equal bins; bins
    whose RMS is >= ``frac`` x the largest bin RMS are merged into intervals (volts)."""
    mag = np.abs(contrib)
    if not mag.size or float(mag.max()) == 0.0:
        return {"intervals_v": [], "lo_v": None, "hi_v": None, "share": 0.0, "peak_v": None}
    edges = np.linspace(volts.min(), volts.max(), bins + 1)
    idx = np.clip(np.searchsorted(edges, volts, side="right") - 1, 0, bins - 1)
    rms = np.array([_rms(contrib[idx == b]) for b in range(bins)])
    sel = rms >= frac * rms.max()
    intervals = []
    for b in range(bins):
        if sel[b]:
            lo, hi = float(volts[idx == b].min()), float(volts[idx == b].max())
            if intervals and sel[b - 1]:
                intervals[-1][1] = hi
            else:
                intervals.append([lo, hi])
    in_sel = sel[idx]
    return {"intervals_v": intervals, "lo_v": intervals[0][0], "hi_v": intervals[-1][1],
            "share": float(in_sel.mean()), "peak_v": float(volts[int(np.argmax(mag))]),
            "rms_inside_mm": _rms(contrib[in_sel]), "rms_outside_mm": _rms(contrib[~in_sel])}


def _fmt_intervals(sp: dict) -> str:
    return " and ".join(f"{lo:+.2f}..{hi:+.2f} V" for lo, hi in sp["intervals_v"]) or "nowhere"


@dataclass
class TraceResult:
    fmt: str
    n_codes: int
    total: dict
    stages: dict                 # stage -> {rms_mm, max_mm, share}
    terms: list                  # top sources: {stage, term, label, rms_mm, max_mm, span}
    dominant: dict               # {stage, term, label, span, reason}
    curves: dict = field(repr=False, default_factory=dict)   # for plotting
    volts: np.ndarray = field(repr=False, default=None)
    codes: np.ndarray = field(repr=False, default=None)
    golden_mm: np.ndarray = field(repr=False, default=None)
    hardware_mm: np.ndarray = field(repr=False, default=None)
    identity_residual_mm: float = 0.0
    input_lsb_v: float = 0.0
    hdl: dict | None = None        # set by check_hdl(): the simulated HDL's own outputs

    def plot(self, path, title: str = "") -> None:
        plot_one_input_trace(self, path, title)

    def at_voltages(self, voltages) -> list[dict]:
        """Golden, hardware and error at the (clamped) input codes nearest to ``voltages``."""
        rows = []
        pos = {int(c): k for k, c in enumerate(self.codes)}
        for v in np.asarray(voltages, dtype=float):
            # the converter's code, clamped as the hardware clamps its input
            c = int(nearest_codes(v, self.input_lsb_v, self.codes.min(), self.codes.max()))
            k = pos[c]
            rows.append({"voltage_v": float(v), "code": c, "golden_mm": float(self.golden_mm[k]),
                         "hardware_mm": float(self.hardware_mm[k]),
                         "error_mm": float(self.hardware_mm[k] - self.golden_mm[k])})
        return rows

    def to_dict(self) -> dict:
        d = {"format": self.fmt, "codes": self.n_codes, "total": self.total,
             "stages": self.stages, "top_sources": self.terms, "dominant": self.dominant,
             "identity_residual_mm": self.identity_residual_mm}
        if self.hdl is not None:
            d["hdl"] = self.hdl
        return d

    def text(self) -> str:
        t = self.total
        lines = [f"flann trace ({self.fmt}): {self.n_codes} input codes, |hardware - golden| "
                 f"max {t['max_mm']:.3g} mm (at {t['peak_v']:+.3f} V), rms {t['rms_mm']:.3g} mm",
                 "", f"{'stage':<11} {'rms mm':>10} {'max mm':>10} {'share':>7}  what"]
        for s, d in self.stages.items():
            lines.append(f"{s:<11} {d['rms_mm']:>10.3g} {d['max_mm']:>10.3g} {d['share']:>6.1%}  {STAGE_TEXT[s]}")
        lines += ["", "largest single sources (stage / term):"]
        for d in self.terms[:6]:
            sp = d["span"]
            lines.append(f"  {d['stage']:<10} {d['label']:<16} rms {d['rms_mm']:.3g} mm, max {d['max_mm']:.3g} mm, "
                         f"largest over {_fmt_intervals(sp)}" if sp["lo_v"] is not None else
                         f"  {d['stage']:<10} {d['label']:<16} 0")
        d = self.dominant
        sp = d["span"]
        lines += ["", f"dominant stage: {d['stage']} ({STAGE_TEXT[d['stage']]}, {d['stage_share']:.0%} of the "
                  f"error variance); largest term there: {d['label']}",
                  f"where: {_fmt_intervals(sp)} ({sp['share']:.0%} of codes; rms {sp['rms_inside_mm']:.3g} mm "
                  f"there vs {sp['rms_outside_mm']:.3g} mm elsewhere; peak at {sp['peak_v']:+.3f} V)",
                  f"why: {d['reason']}"]
        if self.hdl is not None:
            h = self.hdl
            err = (f"; max |HDL - golden| {h['max_err_mm']:.3g} mm over the trained range"
                   if h.get("max_err_mm") is not None else "")
            lines.append(f"HDL (GHDL, {h['top']}): {h['codes']} codes simulated, {h['mismatches']} mismatches "
                         f"vs the twin{err}")
            st = h.get("stages")
            if st:
                lines.append(f"HDL stages captured by cocotb at {st['codes']} codes: "
                             f"{st['terms']} term, {st['products']} product, {st['sums']} running-sum "
                             f"mismatches vs the twin" + ("" if not st["missing"] else f", {st['missing']} codes missing"))
        return "\n".join(lines)


def trace(st: Stages, top_n: int = 10) -> TraceResult:
    sources = attribute(st)
    ok = st.valid
    if not ok.any():
        raise FlannError("trace: no input code inside the clamp range")
    err = (st.h_out - st.g_out)[ok]
    volts = st.volts[ok]
    resid = float(np.max(np.abs(sum(s.contrib for s in sources)[ok] - err)))
    stage_tot: dict[str, np.ndarray] = {}
    for s in sources:
        stage_tot[s.stage] = stage_tot.get(s.stage, 0) + s.contrib[ok]
    var = {k: _rms(v) ** 2 for k, v in stage_tot.items()}
    vsum = sum(var.values()) or 1.0
    stages = {k: {"rms_mm": _rms(v), "max_mm": float(np.abs(v).max()), "share": var[k] / vsum}
              for k, v in sorted(stage_tot.items(), key=lambda kv: STAGES.index(kv[0]))}
    ranked = sorted(sources, key=lambda s: -_rms(s.contrib[ok]))
    terms = [{"stage": s.stage, "term": s.term, "label": s.label, "rms_mm": _rms(s.contrib[ok]),
              "max_mm": float(np.abs(s.contrib[ok]).max()), "span": _span(volts, s.contrib[ok])}
             for s in ranked[:top_n]]
    dom_stage = max(stages, key=lambda k: stages[k]["rms_mm"])
    dom = next(s for s in ranked if s.stage == dom_stage)
    dom_d = {"stage": dom_stage, "term": dom.term, "label": dom.label,
             "rms_mm": _rms(dom.contrib[ok]), "stage_share": stages[dom_stage]["share"],
             "span": _span(volts, stage_tot[dom_stage])}
    dom_d["reason"] = _reason(st, dom, ok)
    if dom_stage == "adder":
        dom_d["label"] = f"all {len(st.step_cols)} additions (largest single: {dom.label})"
    curves = {k: v for k, v in stage_tot.items()}
    curves["total"] = err
    curves[f"{dom.stage}:{dom.label}"] = dom.contrib[ok]
    e_abs = np.abs(err)
    total = {"max_mm": float(e_abs.max()), "rms_mm": _rms(err), "peak_v": float(volts[int(np.argmax(e_abs))]),
             "span": _span(volts, err)}
    return TraceResult(fmt=st.fmt, n_codes=int(ok.sum()), total=total, stages=stages, terms=terms,
                       dominant=dom_d, curves=curves, volts=volts, codes=st.codes[ok],
                       golden_mm=st.g_out[ok], hardware_mm=st.h_out[ok], identity_residual_mm=resid,
                       input_lsb_v=float(st.info["input_lsb_v"]))


def _reason(st: Stages, src: Source, ok: np.ndarray) -> str:
    """One sentence: the mechanism, with the numbers that size it."""
    info = st.info
    col = st.term_index.index(src.term) if src.term in st.term_index else None
    if src.stage == "expansion" and col is not None:
        e = float(np.abs(st.h_fixed_terms[ok, col] - st.g_terms[ok, col]).max())
        w = abs(float(st.g_weights[col]))
        A, P = info["table_addr_bits"], info["phase_bits"]
        kind, m = term_kind(src.term)
        return (f"phase/table resolution of the sin/cos expansion: the {1 << A}-entry quarter-wave table "
                f"({'with' if info['interp'] else 'without'} slope interpolation, {P}-bit phase) gives "
                f"{src.label} (harmonic {m}) an error up to {e:.2g}, which its weight |w| = {w:.3g} mm "
                f"scales to {w * e:.2g} mm.")
    if src.stage == "convert" and col is not None:
        t = float(np.abs(st.h_fixed_terms[ok, col]).max())
        w = abs(float(st.g_weights[col]))
        return (f"rounding of the expansion term to float18's {info['sig_bits']}-bit significand "
                f"(relative 2^-{info['sig_bits']} = {2.0 ** -info['sig_bits']:.2g}): {src.label} reaches "
                f"{t:.3g} and its weight |w| = {w:.3g} mm, so the rounding costs up to "
                f"{w * t * 2.0 ** -info['sig_bits']:.2g} mm.")
    if src.stage == "weights":
        if col is None:
            return (f"the bias constant is stored with {float(np.abs(src.contrib).max()):.2g} mm "
                    "quantisation error, the same at every input.")
        gw, hw = float(st.g_weights[col]), float(st.h_weights[col])
        t = float(np.abs(st.h_terms[ok, col]).max())
        return (f"quantisation of the weight of {src.label}: {gw:.6g} stored as {hw:.6g} "
                f"(relative {abs(hw - gw) / max(abs(gw), 1e-300):.2g}) times a term up to {t:.3g}.")
    if src.stage == "products" and col is not None:
        p = float(np.abs(st.h_products[ok, col]).max())
        if "sig_bits" in info:  # float products round to half an ulp of their own size
            return (f"rounding of large-argument products: |w·t| for {src.label} reaches {p:.3g} mm, "
                    f"where float18's half-ulp is {0.5 * _ulp(p, info['sig_bits']):.2g} mm.")
        return (f"each product is rounded to 2^-{info['product_frac_bits']} output LSB "
                f"({info['output_lsb_mm'] * 2.0 ** -(info['product_frac_bits'] + 1):.2g} mm per term).")
    if src.stage == "adder":
        big = float(np.abs(st.h_running[ok]).max())
        y = np.abs(st.h_out[ok])
        out = float(y.max())
        lo, hi = float(np.percentile(y, 10)), float(np.percentile(y, 90))
        n_add = len(st.step_cols)
        cancel = (f"; the partial sums reach {big:.3g} mm, {big / max(out, 1e-300):.1f}x the largest output, "
                  "so cancellation adds to it" if big > 2 * out else "")
        return (f"rounding in the float18 running sum: each of the {n_add} additions rounds to half an ulp "
                f"of the partial sum, and the ulp grows with the sum's magnitude, which follows |output| "
                f"(half-ulp {0.5 * _ulp(hi, info['sig_bits']):.2g} mm at |y| = {hi:.3g} mm, the 90th percentile, "
                f"vs {0.5 * _ulp(lo, info['sig_bits']):.2g} mm at {lo:.3g} mm, the 10th), so the error grows "
                f"towards the ends of the range where |y| is largest{cancel}.")
    if src.stage == "linear":
        return ("rounding of the serial linear term w0·v_n + bias to the accumulator's "
                f"2^-{info['product_frac_bits']} output LSB.")
    if src.stage == "output":
        if "output_lsb_mm" in info:
            return (f"final rounding to the {info['output_lsb_mm']} mm output LSB (at most "
                    f"{info['output_lsb_mm'] / 2:.3g} mm), larger than every upstream error.")
        return "saturation of the output at float18's max finite value."
    return f"{STAGE_TEXT.get(src.stage, src.stage)}."


def _ulp(x: float, sig_bits: int) -> float:
    if x <= 0:
        return 0.0
    return 2.0 ** (math.floor(math.log2(x)) - (sig_bits - 1))


# -- plot ---------------------------------------------------------------------------------
def plot_one_input_trace(result: TraceResult, path, title: str = "") -> None:
    """Error per stage vs input voltage (PNG)."""
    # matplotlib is heavy and only needed for plots: imported when one is drawn
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    v = result.volts
    order = np.argsort(v)
    fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    ax0.plot(v[order], result.curves["total"][order], lw=0.8, color="k")
    ax0.set_ylabel("hardware − golden (mm)")
    sp = result.dominant["span"]
    for n, (lo, hi) in enumerate(sp["intervals_v"]):
        ax0.axvspan(lo, hi, color="tab:red", alpha=0.08,
                    label=None if n else f"dominant: {result.dominant['stage']} / {result.dominant['label']}")
    if sp["intervals_v"]:
        ax0.legend(loc="upper left", fontsize=8)
    ax0.set_title(title or f"flann trace ({result.fmt}): error per stage")
    ax0.grid(alpha=0.3)
    # largest first, so the small contributions stay visible on top
    for s in sorted((s for s in STAGES if s in result.curves), key=lambda s: -result.stages[s]["rms_mm"]):
        if result.stages[s]["max_mm"] > 0:
            ax1.plot(v[order], result.curves[s][order], lw=0.7, label=f"{s} (rms {result.stages[s]['rms_mm']:.2g})")
    ax1.set_xlabel("input (V)")
    ax1.set_ylabel("contribution (mm)")
    ax1.legend(loc="upper left", fontsize=7, ncol=2)
    ax1.grid(alpha=0.3)
    fig.tight_layout()
    atomic_save_figure(fig, path)
    plt.close(fig)


def plot_compare(results: dict, path, points: dict | None = None, title: str = "",
                 points_label: str = "the recordings' inputs") -> None:
    """Total error (hardware - golden) of several formats on the same axes, as the seed's
    Fig. 6(b); ``points``: {fmt: at_voltages() rows} drawn as markers, named ``points_label``."""
    # matplotlib: imported when a plot is drawn (see plot_one_input_trace)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {fmt: f"C{k}" for k, fmt in enumerate(results)}
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for fmt, r in results.items():
        o = np.argsort(r.volts)
        ax.plot(r.volts[o], r.curves["total"][o], lw=0.6, color=colours.get(fmt), alpha=0.8,
                label=f"{fmt}: every input code (max {r.total['max_mm']:.3g} mm, rms {r.total['rms_mm']:.2g} mm)")
    for fmt, rows in (points or {}).items():
        ax.plot([p["voltage_v"] for p in rows], [p["error_mm"] for p in rows], "o", ms=5,
                color=colours.get(fmt), markeredgecolor="k", label=f"{fmt}: {points_label}")
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("input (V)")
    ax.set_ylabel("hardware − golden model (mm)")
    ax.set_title(title or "error between hardware and golden model")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper center")
    fig.tight_layout()
    atomic_save_figure(fig, path)
    plt.close(fig)


def check_hdl(result: TraceResult, model_path, options: dict, build_dir, stage_samples: int = 64,
              design_model=None) -> dict:
    """Simulate the generated top level over every input code (GHDL + cocotb) and compare the
    HDL's own outputs with the twin and the golden model; stores the summary in ``result.hdl``.
    ``model_path`` may be a design directory (fixed point; ``design_model`` = its model).  A
    datapath whose bench captures internal stages (``stage_capture``) also compares those at a
    spread of ``stage_samples`` codes."""
    dp = datapath(result.fmt)
    found = insight(dp)
    if found.hdl is None:
        raise FlannError(f"--hdl: the {dp.name} datapath's bench does not simulate a model's design "
                         "(generate it with flann gen -o DIR, then flann trace DIR --hdl)")
    stage_codes = (result.codes[np.linspace(0, result.codes.size - 1, stage_samples).astype(int)]
                   if found.stage_capture else ())
    codes, hdl_mm, mism, top, stages = found.hdl(model_path, options, Path(build_dir), stage_codes, design_model)
    pos = {int(c): k for k, c in enumerate(result.codes)}
    sel = np.array([int(c) in pos for c in codes])
    idx = np.array([pos[int(c)] for c in codes[sel]], dtype=np.int64)
    err = hdl_mm[sel] - result.golden_mm[idx]
    result.hdl = {"top": top, "codes": int(codes.size), "mismatches": mism,
                  "max_err_mm": float(np.abs(err).max()) if err.size else 0.0,
                  "equals_twin": bool(mism == 0), "stages": stages}
    return result.hdl


def run_trace(model: FlannModel, fmt: str = FORMATS[0], codes=None, **spec_options) -> TraceResult:
    """The stages of ``model`` in the datapath ``fmt`` (a model without a design directory)."""
    if fmt not in FORMATS:
        raise FlannError(f"--format {fmt!r}: allowed {', '.join(FORMATS)}")
    dp = datapath(fmt)
    st = insight(dp).stages(dp.derive(model, **spec_options), codes)
    st.fmt = dp.name  # check_hdl finds the datapath again by it
    return trace(st)


def trace_design(design: Design, codes=None) -> TraceResult | ThermalTraceResult:
    """The stages of a written design (any datapath with a stage model), from its own spec; a
    design with temperature has its own trace (its folder's ``analysis.py``)."""
    found = traced(design)
    if found.trace is not None:
        return found.trace(design.spec)
    return trace(found.stages(design.spec, codes))


def check_design_hdl(result: TraceResult, design: Design, build_dir) -> dict:
    """A design directory's VHDL over every input code with its datapath's bench (flann sim's)."""
    res = simulate_design(design, build_dir)
    s = res.summary
    result.hdl = {"top": design.manifest["top"], "codes": s["codes_tested"], "mismatches": s["mismatches"],
                  "max_err_mm": s["max_err_mm"], "equals_twin": bool(s["mismatches"] == 0 and res.passed),
                  "stages": None}
    return result.hdl


__all__ = ["Stages", "Source", "twin_trace", "TraceResult", "STAGES", "attribute", "trace", "plot_compare",
           "run_trace", "check_hdl", "term_label", "trace_design", "check_design_hdl"]
