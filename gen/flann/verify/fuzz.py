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

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import FlannError
from ..golden.train import fit_lstsq
from ..hardware.registry import DATAPATHS, datapath
from .plugin import verification


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


def fuzzed() -> list:
    """(datapath, its verification) of the datapaths fuzzed, the smallest share first."""
    found = [(dp, v) for dp in DATAPATHS.values() if (v := verification(dp)) is not None and v.fuzz_share > 0]
    return sorted(found, key=lambda f: f[1].fuzz_share)


def _draw_datapath(rng):
    """One datapath, drawn with its verification's share (one uniform draw picks one)."""
    drawn = fuzzed()
    r, upto = rng.random() * sum(v.fuzz_share for _, v in drawn), 0.0
    for dp, v in drawn:
        upto += v.fuzz_share
        if r < upto:
            return dp, v
    return drawn[-1]


def draw_case(rng, index: int):
    """A model and generator options; the options are valid on their face (the generator may
    still refuse a combination, e.g. a design too large for every Spartan-II)."""
    v, x, lsb, bits = _sensor(rng)
    terms = int(rng.integers(3, 52))
    model = fit_lstsq(v, x, terms)
    dp, checks = _draw_datapath(rng)
    opts = {"input_bits": bits, "input_lsb_v": float(f"{lsb:.6g}"), "interp": bool(rng.random() < 0.8)}
    if checks.fuzz_options is not None:
        opts.update(checks.fuzz_options(rng))
    return model, Case(index, opts, terms, dp.name)


def window(lo: int, hi: int, rng, n: int) -> tuple[int, int]:
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
    return verification(dp).fuzz(model, case, spec, rng, work, hdl_codes)


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


__all__ = ["Case", "draw_case", "check_case", "run_cases", "window", "fuzzed"]
