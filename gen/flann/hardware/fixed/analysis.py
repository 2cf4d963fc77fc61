"""The fixed-point datapath's analysis: its stage model (``flann trace``), how ``flann trace
--hdl`` simulates a model's design (the sweep harness), and its design space (``flann explore``:
lanes x multiplier styles x width presets)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...analysis import explore
from ...analysis.plugin import Insight
from ...analysis.trace import Stages, twin_trace
from ...errors import FlannError
from ...verify.runner import sweep
from ..design import open_design
from .twin import FlannTop


def stages(spec, codes=None) -> Stages:
    codes, t = twin_trace(FlannTop(spec), codes)
    m = spec.model
    q = spec.output_lsb_mm
    Tf, Wf, Pf = spec.term_fmt.frac_bits, spec.weight_fmt.frac_bits, spec.product_fmt.frac_bits
    N = m.terms
    c = t.norm["code"]
    v = c * spec.input_lsb_v
    vn = m.normalise(v)
    idx = list(range(1, N))
    g_terms = m.features(v)[:, 1:]
    g_w = np.asarray(m.weights[1:], dtype=float)
    L = spec.lanes
    rom = np.asarray(spec.weight_rom, dtype=np.int64)          # [lane][step]
    w_int = np.array([rom[j % L][j // L] for j in range(N - 1)], dtype=np.int64)
    h_terms = t.by_term("terms").astype(float) * 2.0 ** -Tf
    h_w = w_int * 2.0 ** -Wf * q
    h_p = t.by_term("products", "multiplier").astype(float) * 2.0 ** -Pf * q
    running = t.adder["running"].astype(float) * 2.0 ** -Pf * q
    step_cols = [[j for j in range(k * L, min((k + 1) * L, N - 1))] for k in range(spec.steps)]
    return Stages(
        fmt=spec.number_format, codes=codes, volts=codes * spec.input_lsb_v,
        valid=(codes >= spec.clamp_lo) & (codes <= spec.clamp_hi), term_index=idx,
        g_terms=g_terms, g_weights=g_w, g_start=m.bias + m.weights[0] * vn,
        h_fixed_terms=h_terms, h_terms=h_terms, h_weights=h_w, h_products=h_p,
        h_start=t.norm["lin"].astype(float) * 2.0 ** -Pf * q, h_running=running,
        step_cols=step_cols, h_out=t.adder["out"].astype(float) * q, start_stage="linear",
        info=dict(table_addr_bits=spec.table_addr_bits, interp=spec.interp, phase_bits=spec.phase_bits,
                  term_frac_bits=Tf, weight_frac_bits=Wf, product_frac_bits=Pf, output_lsb_mm=q,
                  lanes=L, input_lsb_v=spec.input_lsb_v),
    )


def hdl(model_path, options: dict, build_dir: Path, stage_codes, design_model) -> tuple:
    """The fixed-point sweep harness; the design's blocks are checked by their own block benches."""
    design = open_design(model_path, build_dir, options, model=design_model)
    sw = sweep(design, build_dir)
    if sw["codes"].size == 0:
        raise FlannError(f"fixed-point simulation produced no outputs (see {build_dir})")
    spec = design.spec
    codes, data = sw["codes"], sw["data"]
    mism = int(np.count_nonzero(data != FlannTop(spec).process(codes)[0]))
    return codes, data * spec.output_lsb_mm, mism, design.manifest["top"], None


def explore_space(model_path, device, lanes=None, styles=None, **kw) -> list:
    """lanes x multiplier styles (None: the defaults) x width presets, each synthesised."""
    return explore.explore(model_path, device, lanes=explore.DEFAULT_LANES if lanes is None else lanes,
                           styles=explore.DEFAULT_STYLES if styles is None else styles, **kw)


INSIGHT = Insight(stages=stages, hdl=hdl, explore=explore_space)

__all__ = ["INSIGHT", "stages", "hdl", "explore_space"]
