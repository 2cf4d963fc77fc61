"""Bit-true twin of the generated VHDL: one class per entity, same name, same integer arithmetic.

Every ``process`` method is vectorised over samples (numpy int64) and returns the values the
entity's output registers hold, stage by stage, so a test bench (or ``flann trace``) can
compare hardware and twin at any block boundary.  Widths are those of the :class:`Spec`;
the few places where arithmetic is modular on purpose (phase = m v_n mod 2) are marked.

Term order inside the hardware: trig term ``j = 0 .. N-2`` is model term ``i = j + 1``
(j even: sin, j odd: cos, harmonic ``m = j // 2 + 1``); lane ``l`` handles
``j = k * lanes + l`` at step ``k``.  Model term 0 (``w0 v_n``) and the bias are folded
into the adder's start value by the normaliser.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...numeric.fixed import round_shift, saturate
from .spec import Spec


def _i64(x) -> np.ndarray:
    return np.asarray(x, dtype=np.int64)


class FlannNorm:
    """Clamp the ADC code, then two serial code x constant products (theta and linear part)."""

    def __init__(self, spec: Spec):
        self.spec = spec

    def process(self, codes) -> dict:
        s = self.spec
        c_in = _i64(codes)
        c = np.clip(c_in, s.clamp_lo, s.clamp_hi)
        sat = c != c_in
        mod = 1 << (s.phase_bits + s.norm_guard)
        # modular on purpose: only v_n mod 2 (the phase) is kept
        acc_v = (s.ka * c) % mod
        theta = ((acc_v + s.kb + (1 << (s.norm_guard - 1))) % mod) >> s.norm_guard
        lin = round_shift(s.k1 * c + s.k0, s.lin_guard)
        return {"code": c, "sat": sat, "theta": theta, "lin": lin}


class FlannExpansion:
    """Phase accumulation m*theta mod 2, quarter-wave table with first-order slope correction."""

    def __init__(self, spec: Spec):
        self.spec = spec
        self.value_rom = _i64(spec.value_rom)
        self.slope_rom = _i64(spec.slope_rom)

    def j_index(self) -> np.ndarray:
        """Trig term index j for (step, lane), shape (steps, lanes)."""
        s = self.spec
        return np.arange(s.steps)[:, None] * s.lanes + np.arange(s.lanes)[None, :]

    def process(self, theta) -> dict:
        s = self.spec
        P, A = s.phase_bits, s.table_addr_bits
        D = P - 2 - A
        th = _i64(theta)[:, None, None]
        j = self.j_index()[None, :, :]
        m = j // 2 + 1
        phase = (m * th) % (1 << P)  # modular on purpose: sin/cos have period 2 (units of pi)
        psi = (phase + np.where(j % 2 == 1, 1 << (P - 2), 0)) % (1 << P)
        quad = psi >> (P - 2)
        r = psi & ((1 << (P - 2)) - 1)
        r = np.where(quad & 1, ((1 << (P - 2)) - 1) - r, r)
        addr = r >> D
        low = r & ((1 << D) - 1)
        dq = 2 * low + 1 - (1 << D)
        dq_t = dq >> (D + 1 - s.dq_bits)
        val = self.value_rom[addr]
        if s.interp:
            corr = round_shift(dq_t * self.slope_rom[addr], s.slope_guard)
        else:
            corr = np.zeros_like(val)
        mag = val + corr
        term = np.where(quad & 2, -mag, mag)
        return {"phase": phase, "addr": addr, "dq": dq_t, "neg": (quad >> 1).astype(bool), "terms": term}


class FlannMultiplier:
    """Term x weight (weights from the per-lane ROM), rounded to the product format."""

    def __init__(self, spec: Spec):
        self.spec = spec
        self.weights = _i64(spec.weight_rom).T  # (steps, lanes)

    def process(self, terms) -> dict:
        s = self.spec
        full = _i64(terms) * self.weights[None, :, :]
        return {"products": round_shift(full, s.product_shift)}


class FlannAdder:
    """Start at the linear part, add every product, round to the output LSB, saturate."""

    def __init__(self, spec: Spec):
        self.spec = spec

    def process(self, lin, products, in_sat) -> dict:
        s = self.spec
        step_sum = _i64(products).sum(axis=2)  # (n, steps)
        running = _i64(lin)[:, None] + np.cumsum(step_sum, axis=1)
        acc = running[:, -1]
        y = round_shift(acc, s.product_fmt.frac_bits)
        out, clipped = saturate(y, s.out_fmt.width, signed=True)
        return {"running": running, "acc": acc, "out": out, "sat": np.asarray(in_sat, bool) | clipped}


@dataclass
class TopTrace:
    """Every stage of the twin for a batch of input codes (arrays indexed by sample first)."""

    codes: np.ndarray
    norm: dict
    expansion: dict
    multiplier: dict
    adder: dict
    n_trig: int = 0

    @property
    def out(self) -> np.ndarray:
        return self.adder["out"]

    @property
    def sat(self) -> np.ndarray:
        return self.adder["sat"]

    def by_term(self, key: str, stage: str = "expansion") -> np.ndarray:
        """(n, steps, lanes) stage array -> (n, N-1) in model term order i = 1..N-1."""
        a = getattr(self, stage)[key]
        n = a.shape[0]
        return a.reshape(n, -1)[:, : self.n_trig]


class FlannTop:
    """The whole datapath; values equal those of flann_top's out_data / out_sat."""

    def __init__(self, spec: Spec):
        self.spec = spec
        self.norm = FlannNorm(spec)
        self.expansion = FlannExpansion(spec)
        self.multiplier = FlannMultiplier(spec)
        self.adder = FlannAdder(spec)

    def trace(self, codes) -> TopTrace:
        codes = _i64(codes)
        n = self.norm.process(codes)
        e = self.expansion.process(n["theta"])
        p = self.multiplier.process(e["terms"])
        a = self.adder.process(n["lin"], p["products"], n["sat"])
        return TopTrace(codes=codes, norm=n, expansion=e, multiplier=p, adder=a, n_trig=self.spec.n_trig)

    def process(self, codes) -> tuple[np.ndarray, np.ndarray]:
        t = self.trace(codes)
        return t.out, t.sat

    def all_codes(self) -> np.ndarray:
        return np.arange(self.spec.code_min, self.spec.code_max + 1, dtype=np.int64)

    def error_vs_float(self, codes=None) -> dict:
        """max |twin - float model| over ``codes`` (default: every input code)."""
        s = self.spec
        codes = self.all_codes() if codes is None else _i64(codes)
        out, sat = self.process(codes)
        ref = s.float_reference(codes) / s.output_lsb_mm
        err = np.abs(out - ref)
        ok = ~(sat & (np.abs(ref) > s.out_fmt.max_int))  # output clipping is not an error
        e = float(err[ok].max()) if ok.any() else 0.0
        return {"max_err_lsb": e, "max_err_mm": e * s.output_lsb_mm, "codes": int(codes.size)}


__all__ = ["FlannNorm", "FlannExpansion", "FlannMultiplier", "FlannAdder", "FlannTop", "TopTrace"]
