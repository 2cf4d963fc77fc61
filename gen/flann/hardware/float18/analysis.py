"""The float18 datapath's analysis: its stage model (``flann trace``), ``flann trace --hdl`` of a
model's design through its top-level bench (internal stages captured too), and its design space
(``flann explore``: the width presets of its fixed front end, each generated, synthesised with
``flann synth``'s flow and scored by its twin)."""

from __future__ import annotations

import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

from ...analysis.explore import F18, NARROW_BITS, WIDTH_PRESETS, Row, check_width_preset, seed_rows
from ...analysis.plugin import Insight
from ...analysis.trace import Stages, run_trace, twin_trace
from ...errors import FlannError
from ...golden.model import load_model
from ...implement import synth
from ...implement.synth import Resources, shortfall, smallest_fit, synthesize
from ..manifest import write_design
from ...numeric.float18 import FLOAT18
from ..target import CLOCK_HZ, DEFAULT_PART, parse_part
from .datapath import DATAPATH
from .render import generate, render_block
from .spec import FlannF18Top
from .verify import run_top


def stages(fspec, codes=None) -> Stages:
    codes, t = twin_trace(FlannF18Top(fspec), codes)
    fmt = fspec.fmt
    base = fspec.front
    m = fspec.model
    N = m.terms
    Tf = fspec.term_frac_bits
    v = t.code * base.input_lsb_v
    g_terms = m.features(v)
    g_terms[:, 0] = t.code * 2.0 ** -Tf              # term 0 enters as the code (see float18_top)
    dec = fmt.decode_array
    return Stages(
        fmt=fspec.number_format, codes=codes, volts=codes * base.input_lsb_v,
        valid=(codes >= base.clamp_lo) & (codes <= base.clamp_hi), term_index=list(range(N)),
        g_terms=g_terms, g_weights=fspec.golden_weights(),
        g_start=np.full(codes.size, fspec.golden_start()),
        h_fixed_terms=t.fixed_terms.astype(float) * 2.0 ** -Tf, h_terms=dec(t.terms),
        h_weights=dec(np.asarray(fspec.weight_codes)), h_products=dec(t.products),
        h_start=np.full(codes.size, float(fmt.decode(fspec.start_code))), h_running=dec(t.running),
        step_cols=[[i] for i in range(N)], h_out=dec(t.out), start_stage="weights", converts=True,
        info=dict(table_addr_bits=base.table_addr_bits, interp=base.interp, phase_bits=base.phase_bits,
                  term_frac_bits=Tf, sig_bits=fmt.sig_bits, format=fmt.describe(),
                  input_lsb_v=base.input_lsb_v),
    )


def hdl(model_path, options: dict, build_dir: Path, stage_codes, design_model) -> tuple:
    r = run_top(model_path, build_dir, stage_codes=stage_codes, **options)
    return r["codes"], FLOAT18.decode_array(r["out"]), r["mismatches"], r["manifest"]["top"], r["stages"]


def measure(model_path, device: str = DEFAULT_PART, abc: str = "full", **options) -> dict:
    with tempfile.TemporaryDirectory(prefix="flann-f18-") as tmp:
        out = Path(tmp) / DATAPATH.name
        man = generate(model_path, out, **options)
        rep = synth.synthesize(out, device, progress=False, abc=abc).to_dict()
    tr = run_trace(load_model(model_path), DATAPATH.name, **options)
    return {
        "format": DATAPATH.number_format, "top": man["top"], "device": device,
        "luts": rep["luts"], "ffs": rep["ffs"], "brams": rep["brams"], "fits": rep["fits"],
        "cycles_per_sample": man["cycles_per_sample"],
        "samples_per_s_at_50mhz": round(CLOCK_HZ / man["cycles_per_sample"], 1),
        "max_err_mm": tr.total["max_mm"], "rms_err_mm": tr.total["rms_mm"],
        "dominant_error_stage": tr.dominant["stage"],
    }


def float18_row(model_path, device: str, widths: str, options: dict, abc: str = "full") -> Row:
    """The serial float18 design with ``options`` (derive options of the float18 datapath), measured."""
    r = Row(f"{F18} (serial)", 1, F18, widths)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the front end's fixed output-LSB bound: no output LSB here
            m = measure(model_path, device, abc=abc, **options)
        r.luts, r.ffs, r.brams, r.fits = m["luts"], m["ffs"], m["brams"], m["fits"]
        r.cycles_per_sample, r.samples_per_s = m["cycles_per_sample"], m["samples_per_s_at_50mhz"]
        r.max_err_mm = m["max_err_mm"]
        r.note = f"dominant error: {m['dominant_error_stage']}"
        part = parse_part(device)
        best = smallest_fit(Resources(m["luts"], m["ffs"], m["brams"], 0, 0, 0, 0, 0, 0), part)
        r.smallest_device = best.name if best else None
    except FlannError as exc:
        r.note = str(exc)
    return r


def explore_widths(model_path, device: str = DEFAULT_PART, lanes=None, styles=None, widths=WIDTH_PRESETS,
                    seed: bool = True, progress: bool = True, abc: str = "fast", adc: dict | None = None) -> list[Row]:
    """The float18 design's own choices: the width presets of its fixed front end's terms
    (budget: the error budget's term width, widened to the code's; narrow: NARROW_BITS fraction
    bits fewer), each generated, synthesised and scored by its twin.  Its float format is the
    seed's 18 bits (the float blocks are written for it) and it has one lane and the seed's
    float multiplier, so --lanes other than 1 and --mult are refused."""
    parse_part(device)
    if lanes is not None and tuple(lanes) != (1,):
        raise FlannError(f"--lanes {','.join(map(str, lanes))}: a {F18} design has one lane (its float sum "
                         "is sequential, in model term order); explore its --widths")
    if styles is not None:
        raise FlannError(f"--mult {','.join(styles)}: a {F18} design multiplies with the seed's {F18} "
                         "multiplier, it has no multiplier style; explore its --widths")
    for preset in widths:
        check_width_preset(preset)
    rows = []
    for k, preset in enumerate(widths, 1):
        if progress:
            print(f"explore [{k}/{len(widths)}] {F18} widths={preset}", file=sys.stderr)
        options = dict(adc or {})
        if preset == "narrow":
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    ref = DATAPATH.derive(load_model(model_path), **options)
            except FlannError as exc:
                rows.append(Row(f"{F18} (serial)", 1, F18, preset, note=str(exc)))
                continue
            options["term_frac_bits"] = max(4, ref.term_frac_bits - NARROW_BITS)
        rows.append(float18_row(model_path, device, preset, options, abc))
    if seed:
        rows += seed_rows(model_path, device, abc=abc, progress=progress)
    return rows


def float18_rows(model_path, device: str, abc: str = "fast", seed_terms: int | None = None,
                 progress: bool = True) -> list[Row]:
    """The paper's 18-bit floating point: the project's serial float18 design, and the
    seed architecture's arithmetic in float18 (N multipliers + N-1 adders, each block
    synthesised once with this flow and multiplied by its count; tables not included).
    """
    if progress:
        print("explore: float18 design (serial)", file=sys.stderr)
    rows = [float18_row(model_path, device, F18, {})]

    n = seed_terms or load_model(model_path).terms
    per = {}
    with tempfile.TemporaryDirectory(prefix="flann-f18blk-") as tmp:
        for kind in ("mul", "add"):
            if progress:
                print(f"explore: float18 {kind} block", file=sys.stderr)
            name, text = render_block(kind)
            d = Path(tmp) / kind
            write_design({name: text}, {"top": name[:-4], "files": [name]}, d)
            rep = synthesize(d, device, abc=abc)
            per[kind] = (rep.resources.luts, rep.resources.ffs, rep.resources.brams)
    luts = n * per["mul"][0] + (n - 1) * per["add"][0]
    ffs = n * per["mul"][1] + (n - 1) * per["add"][1]
    brams = n * per["mul"][2] + (n - 1) * per["add"][2]
    part = parse_part(device)
    res = Resources(luts, ffs, brams, 0, 0, 0, 0, 0, 0)
    best = smallest_fit(res, part)
    rows.append(Row(
        f"seed arithmetic in {F18}, {n} terms", None, F18, F18, luts=luts, ffs=ffs, brams=brams,
        cycles_per_sample=1, samples_per_s=CLOCK_HZ, fits=not shortfall(res, part),
        smallest_device=best.name if best else None,
        note=(f"{n} x flann_f18_mul ({per['mul'][0]} LUT4, {per['mul'][1]} FF) + {n - 1} x flann_f18_add "
              f"({per['add'][0]} LUT4, {per['add'][1]} FF), each synthesised once; expansion tables not counted"),
    ))
    return rows


INSIGHT = Insight(stages=stages, hdl=hdl, stage_capture=True, explore=explore_widths)

__all__ = ["INSIGHT", "stages", "hdl", "measure", "float18_row", "explore_widths", "float18_rows"]
