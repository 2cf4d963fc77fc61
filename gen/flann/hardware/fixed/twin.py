"""Bit-true twin of the generated VHDL: one class per entity, same name, same integer arithmetic.

Every twin names its entity and latency; ``process`` is vectorised over samples (numpy
int64) and returns a record whose fields are the entity's output ports (plus its internal
stages), so a test bench (or ``flann trace``) can compare hardware and twin at any block
boundary.  Widths are those of the :class:`Spec` (flann_norm's and flann_expansion's: of its
:class:`FrontEnd`, which is all the float18 datapath gives them);
the few places where arithmetic is modular on purpose (phase = m v_n mod 2) are marked.

Term order inside the hardware: trig term ``j = 0 .. N-2`` is model term ``i = j + 1``
(its kind and harmonic from :func:`flann.golden.model.term_kind`, via ``Spec.trig_term``);
lane ``l`` handles ``j = k * lanes + l`` at step ``k``.  Model term 0 (``w0 v_n``) and the
bias are folded into the adder's start value by the normaliser.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...numeric.fixed import round_shift
from ..twin import Record, TopOut
from .latency import ADDER_EDGES, EXPANSION_ADVANCES, MULTIPLIER_ADVANCES, norm_latency
from .spec import FrontEnd, Spec


def _i64(x) -> np.ndarray:
    return np.asarray(x, dtype=np.int64)


@dataclass(frozen=True)
class NormOut(Record):
    """flann_norm's output ports, and the clamped code."""

    code: np.ndarray
    out_sat: np.ndarray
    out_theta: np.ndarray
    out_lin: np.ndarray


@dataclass(frozen=True)
class ExpansionOut(Record):
    """flann_expansion's out_terms (samples, steps, lanes), and its pipeline registers."""

    phase: np.ndarray
    addr: np.ndarray
    dq: np.ndarray
    neg: np.ndarray
    out_terms: np.ndarray


@dataclass(frozen=True)
class MultiplierOut(Record):
    out_products: np.ndarray  # (samples, steps, lanes)


@dataclass(frozen=True)
class AdderOut(Record):
    """flann_adder's output ports, the running sum after each step and the final accumulator."""

    running: np.ndarray
    acc: np.ndarray
    out_data: np.ndarray
    out_sat: np.ndarray

    ALIASES = {"out": "out_data"}


class FlannNorm:
    """Clamp the ADC code, then two serial code x constant products (theta and linear part)."""

    entity = "flann_norm"

    def __init__(self, spec: FrontEnd):
        self.spec = spec
        self.latency = norm_latency(spec.input_bits)

    def process(self, codes) -> NormOut:
        s = self.spec
        c_in = _i64(codes)
        c = np.clip(c_in, s.clamp_lo, s.clamp_hi)
        mod = 1 << (s.phase_bits + s.norm_guard)
        # modular on purpose: only v_n mod 2 (the phase) is kept
        acc_v = (s.ka * c) % mod
        theta = ((acc_v + s.kb_rounded) % mod) >> s.norm_guard
        # k1, k0 carry lin_guard extra fraction bits; rounding as the lin format's
        lin = s.lin_fmt.round_from(s.k1 * c + s.k0, s.lin_fmt.frac_bits + s.lin_guard)
        return NormOut(code=c, out_sat=c != c_in, out_theta=theta, out_lin=lin)


class FlannExpansion:
    """Phase accumulation m*theta mod 2, quarter-wave table with first-order slope correction
    (a slope table, or the shared table's difference of neighbouring samples)."""

    entity = "flann_expansion"
    latency = EXPANSION_ADVANCES  # advances from theta to the first term

    def __init__(self, spec: FrontEnd):
        self.spec = spec
        self.value_rom = _i64(spec.value_rom)
        self.slope_rom = _i64(spec.slope_rom)
        j = self.j_index()
        kinds = [[spec.trig_term(int(x)) for x in row] for row in j]
        self.harmonic = _i64([[m for _, m in row] for row in kinds])      # (steps, lanes)
        self.is_cos = np.array([[k == "cos" for k, _ in row] for row in kinds])

    def j_index(self) -> np.ndarray:
        """Trig term index j for (step, lane), shape (steps, lanes)."""
        s = self.spec
        return np.arange(s.steps)[:, None] * s.lanes + np.arange(s.lanes)[None, :]

    def process(self, theta) -> ExpansionOut:
        s = self.spec
        P, D = s.phase_bits, s.offset_bits
        th = _i64(theta)[:, None, None]
        phase = (self.harmonic[None] * th) % (1 << P)  # modular on purpose: sin/cos have period 2 (units of pi)
        psi = (phase + np.where(self.is_cos[None], 1 << (P - 2), 0)) % (1 << P)
        quad = psi >> (P - 2)
        r = psi & ((1 << (P - 2)) - 1)
        r = np.where(quad & 1, ((1 << (P - 2)) - 1) - r, r)
        addr = r >> D
        low = r & ((1 << D) - 1)
        if s.shared_table:  # unsigned offset from the bin's lower edge
            dq = 2 * low + 1
        else:  # signed offset from the bin centre
            dq = 2 * low + 1 - (1 << D)
        dq_t = dq >> (D + 1 - s.dq_bits)
        val = self.value_rom[addr]
        if s.shared_table:
            # the second port reads address + 1 mod N; the difference keeps its low C bits
            # (modular on purpose: sample 0 = 0 = 2^Tf mod 2^C stands for sin(pi/2))
            n, cmod = 1 << s.table_addr_bits, 1 << s.slope_rom_bits
            delta = (self.value_rom[(addr + 1) % n] - val) % cmod
            corr = round_shift(dq_t * delta, s.slope_guard)
        elif s.interp:
            corr = round_shift(dq_t * self.slope_rom[addr], s.slope_guard)
        else:
            corr = np.zeros_like(val)
        mag = val + corr
        term = np.where(quad & 2, -mag, mag)
        return ExpansionOut(phase=phase, addr=addr, dq=dq_t, neg=(quad >> 1).astype(bool), out_terms=term)


class FlannMultiplier:
    """Term x weight (weights from the per-lane ROM), rounded to the product format."""

    entity = "flann_multiplier"
    latency = MULTIPLIER_ADVANCES  # advances from term to product

    def __init__(self, spec: Spec):
        self.spec = spec
        self.weights = _i64(spec.weight_rom).T  # (steps, lanes)

    def process(self, terms) -> MultiplierOut:
        s = self.spec
        full = _i64(terms) * self.weights[None, :, :]
        return MultiplierOut(out_products=s.product_fmt.round_from(
            full, s.term_fmt.frac_bits + s.weight_fmt.frac_bits))


class FlannAdder:
    """Start at the linear part, add every product, round to the output LSB, saturate."""

    entity = "flann_adder"
    latency = ADDER_EDGES  # clock edges from in_finish to out_valid (the rounded, saturated sum registered)

    def __init__(self, spec: Spec):
        self.spec = spec

    def process(self, lin, products, in_sat) -> AdderOut:
        s = self.spec
        step_sum = _i64(products).sum(axis=2)  # (n, steps)
        running = _i64(lin)[:, None] + np.cumsum(step_sum, axis=1)
        acc = running[:, -1]
        out, clipped = s.out_fmt.saturate(s.out_fmt.round_from(acc, s.acc_fmt.frac_bits))
        return AdderOut(running=running, acc=acc, out_data=out, out_sat=np.asarray(in_sat, bool) | clipped)


@dataclass
class TopTrace:
    """Every stage of the twin for a batch of input codes (arrays indexed by sample first)."""

    codes: np.ndarray
    norm: NormOut
    expansion: ExpansionOut
    multiplier: MultiplierOut
    adder: AdderOut
    n_trig: int = 0

    @property
    def out(self) -> np.ndarray:
        return self.adder.out_data

    @property
    def sat(self) -> np.ndarray:
        return self.adder.out_sat

    def by_term(self, key: str, stage: str = "expansion") -> np.ndarray:
        """(n, steps, lanes) stage array -> (n, N-1) in model term order i = 1..N-1."""
        a = getattr(self, stage)[key]
        n = a.shape[0]
        return a.reshape(n, -1)[:, : self.n_trig]


class FlannTop:
    """The whole datapath; values equal those of flann_top's out_data / out_sat."""

    entity = "flann_top"

    def __init__(self, spec: Spec):
        self.spec = spec
        self.latency = spec.latency_cycles
        self.norm = FlannNorm(spec)
        self.expansion = FlannExpansion(spec)
        self.multiplier = FlannMultiplier(spec)
        self.adder = FlannAdder(spec)

    def trace(self, codes) -> TopTrace:
        codes = _i64(codes)
        n = self.norm.process(codes)
        e = self.expansion.process(n.out_theta)
        p = self.multiplier.process(e.out_terms)
        a = self.adder.process(n.out_lin, p.out_products, n.out_sat)
        return TopTrace(codes=codes, norm=n, expansion=e, multiplier=p, adder=a, n_trig=self.spec.n_trig)

    def process(self, codes) -> TopOut:
        t = self.trace(codes)
        return TopOut(out_data=t.out, out_sat=t.sat)

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


__all__ = ["FlannNorm", "FlannExpansion", "FlannMultiplier", "FlannAdder", "FlannTop", "TopTrace",
           "NormOut", "ExpansionOut", "MultiplierOut", "AdderOut"]
