"""Generator fuzzing: random valid generator configurations on models of random sensors.

One case: draw a sensor (a closed-form saturating S-curve with random span, sensitivity,
roll-off, asymmetry, sign and noise; not the project's physics model), record it through an
ADC of random width, fit a FLANN with a random number of terms, draw generator options (input
and output widths, lanes, multiplier style and digit, interpolation, number format), then

  * generate the design (a refusal must be a FlannError with a message, never a crash);
  * fixed point: the twin over EVERY input code within the spec's stated bound of the float
    model (``analysis.bound_total_lsb``; at least 1 LSB);
  * the HDL on a sample of codes (a random window plus the clamp edges) bit-exact against the
    twin: the VHDL sweep harness (fixed) or the float18 cocotb bench.

``run_cases(seed, n)`` is the fixed-seed set of ``make test`` and ``bench/fuzz_gen.py``.
"""

from __future__ import annotations

import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import FlannError
from ..golden.train import fit_lstsq
from ..hardware.fixed.render import write
from ..hardware.fixed.twin import FlannTop
from ..hardware.float18.spec import FlannF18Top
from ..hardware.registry import DATAPATHS, datapath
from ..hardware.design import Design
from ..hardware.manifest import Manifest
from .float18 import run_top
from .runner import sweep


@dataclass
class Case:
    index: int
    options: dict
    terms: int
    number_format: str
    outcome: str = ""           # "ok", "refused" (a FlannError, listed), "FAIL"
    detail: str = ""
    codes_twin: int = 0          # codes whose twin output was checked against the float bound
    codes_hdl: int = 0           # codes simulated and compared with the twin
    mismatches: int = 0
    max_err_lsb: float = float("nan")
    bound_lsb: float = float("nan")
    extra: dict = field(default_factory=dict)


def _sensor(rng) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Recordings (voltage, displacement) of a random sensor through a random ADC; (v, x, lsb, bits)."""
    span = float(rng.choice([2.0, 5.0, 10.0, 30.0, 60.0]))
    w = span * rng.uniform(0.5, 1.0)
    sharp = rng.uniform(1.5, 4.0)
    amp = rng.uniform(0.5, 6.0)
    asym = rng.uniform(-0.05, 0.05)
    sign = float(rng.choice([1.0, -1.0]))
    bits = int(rng.choice([8, 10, 12, 14, 16]))
    x = np.linspace(-span, span, int(rng.integers(40, 200)))
    u = x / w
    v = sign * amp * (1 + np.where(u >= 0, asym, -asym)) * u / (1 + np.abs(u) ** sharp) ** (1 / sharp)
    vmax = float(np.max(np.abs(v))) * rng.uniform(1.02, 1.3)
    lsb = 2 * vmax / 2 ** bits
    v = np.round((v + rng.normal(0, rng.uniform(0.0, 2.0) * lsb, v.size)) / lsb) * lsb
    return v, x, lsb, bits


# the datapaths fuzzed, the smallest share first (one uniform draw picks one)
FUZZED = tuple(sorted((dp for dp in DATAPATHS.values() if dp.fuzz_share > 0), key=lambda dp: dp.fuzz_share))


def _draw_datapath(rng):
    r, upto = rng.random() * sum(dp.fuzz_share for dp in FUZZED), 0.0
    for dp in FUZZED:
        upto += dp.fuzz_share
        if r < upto:
            return dp
    return FUZZED[-1]


def draw_case(rng, index: int):
    """A model and generator options; the options are valid on their face (the generator may
    still refuse a combination, e.g. a design too large for every Spartan-II)."""
    v, x, lsb, bits = _sensor(rng)
    terms = int(rng.integers(3, 52))
    model = fit_lstsq(v, x, terms)
    dp = _draw_datapath(rng)
    opts = {"input_bits": bits, "input_lsb_v": float(f"{lsb:.6g}"), "interp": bool(rng.random() < 0.8)}
    if dp.fuzz_options is not None:
        opts.update(dp.fuzz_options(rng))
    return model, Case(index, opts, terms, dp.name)


def _window(lo: int, hi: int, rng, n: int) -> tuple[int, int]:
    n = min(n, hi - lo + 1)
    a = int(rng.integers(lo, hi - n + 2))
    return a, a + n - 1


def check_case(model, case: Case, rng, work: Path, hdl_codes: int = 24) -> Case:
    work = Path(work)
    try:
        dp = datapath(case.number_format)
        spec = dp.derive(model, **case.options)
    except FlannError as exc:
        case.outcome, case.detail = "refused", str(exc)
        return case
    return CHECKS[dp.bench](model, case, spec, rng, work, hdl_codes)


def _check_sweep(model, case: Case, spec, rng, work: Path, hdl_codes: int) -> Case:
    try:
        top = FlannTop(spec)
        codes = top.all_codes()
        out, _ = top.process(codes)
        err = np.abs(out - spec.float_reference(codes) / spec.output_lsb_mm)
        case.codes_twin = int(codes.size)
        case.max_err_lsb = round(float(err.max()), 4)
        case.bound_lsb = round(max(1.0, float(spec.analysis["bound_total_lsb"])), 4)
        man = write(spec, work / "hdl")
        model.save(work / "model.json")
        design = Design((work / "hdl").resolve(), Manifest.written(work / "hdl", man), (work / "model.json").resolve(),
                        case.options, spec)
        windows = [_window(spec.code_min, spec.code_max, rng, hdl_codes),
                   (max(spec.code_min, spec.clamp_lo - 2), min(spec.code_max, spec.clamp_lo + 2)),
                   (max(spec.code_min, spec.clamp_hi - 2), min(spec.code_max, spec.clamp_hi + 2))]
        sample = sorted({c for a, b in windows for c in range(a, b + 1)})
        r = sweep(design, work / "build", codes=sample, shards=1)
        total = len(sample)
        want_out, want_sat = top.process(r["codes"])
        case.mismatches = int(np.count_nonzero((r["data"] != want_out) | (r["sat"] != want_sat)))
        case.mismatches += total - int(r["codes"].size)
        if not r["bench"].ok:
            case.mismatches = max(case.mismatches, 1)
            case.detail = f"sweep bench failed: {r['bench'].failed_tests}"
        case.codes_hdl = total
        bad = case.max_err_lsb > case.bound_lsb + 1e-9 or case.mismatches
        case.outcome = "FAIL" if bad else "ok"
        if case.max_err_lsb > case.bound_lsb + 1e-9:
            case.detail = f"twin {case.max_err_lsb} LSB from the float model > bound {case.bound_lsb}"
    except FlannError as exc:
        case.outcome, case.detail = "FAIL", f"after a valid spec: {exc}"
    except Exception:  # a crash is a finding: record it, go on with the next case
        case.outcome, case.detail = "FAIL", traceback.format_exc(limit=3).strip().splitlines()[-1]
    return case


def _check_f18_top(model, case: Case, fspec, rng, work: Path, hdl_codes: int) -> Case:
    try:
        top = FlannF18Top(fspec)
        codes = top.all_codes()
        lo, hi = _window(int(codes[0]), int(codes[-1]), rng, hdl_codes)
        r = run_top(model, work, codes=np.arange(lo, hi + 1), seed=case.index, **case.options)
        case.codes_twin = int(codes.size)
        case.codes_hdl = int(r["codes"].size)
        case.mismatches = r["mismatches"] if r["mismatches"] is not None else hi - lo + 1
        case.outcome = "FAIL" if (case.mismatches or r["bench_failed"]) else "ok"
    except Exception:
        case.outcome, case.detail = "FAIL", traceback.format_exc(limit=3).strip().splitlines()[-1]
    return case


# how a fuzz case is checked, by the datapath's bench (Datapath.bench)
CHECKS = {"sweep": _check_sweep, "f18_top": _check_f18_top}


def run_cases(seed: int, n: int, work, hdl_codes: int = 24, progress=None) -> list[Case]:
    """``n`` cases from ``seed`` (reproducible), each checked in its own directory under ``work``."""
    rng = np.random.default_rng(seed)
    cases = []
    for i in range(n):
        model, case = draw_case(rng, i)
        cases.append(check_case(model, case, rng, Path(work) / f"case_{i}", hdl_codes))
        if progress:
            progress(cases[-1])
    return cases


__all__ = ["Case", "draw_case", "check_case", "run_cases"]
