"""The seed paper's FLANN architecture, fully parallel, in fixed point: its spec.

Every expansion output at once, one multiplier per term and a binary tree of two-input
adders (paper, section "FPGA Implementation"), in ``word``-bit fixed point instead of the
paper's 18-bit floating point.  It exists to be measured beside the project's serial
design (``flann explore``), with the same ADC scaling and clamp.

Formats (all ``word`` = 18 bits, signed): v in Q1.17 (saturated), terms with 16 fraction
bits, weights with ``weight_frac`` fraction bits, products rounded to the accumulator
format with ``acc_frac`` fraction bits, chosen so that bias + sum |w_i| fits: the adder
tree cannot overflow.  Phase of harmonic m: (m v) mod 2 on ``word`` bits.  Every constant
is derived here; the twin (:mod:`.twin`) and the renderer (:mod:`.render`) only read it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...errors import SpecError
from ...golden.model import FlannModel, load_model, model_sha256, term_kind
from ...numeric.fixed import FixedFormat
from ..fixed.spec import derive_spec

ENTITY = "flann_seed_top"


@dataclass(frozen=True)
class SeedSpec:
    model: FlannModel = field(repr=False)
    input_bits: int
    input_lsb_v: float
    clamp_lo: int
    clamp_hi: int
    word: int = 18
    addr_bits: int = 10
    norm_guard: int = 16
    model_sha256: str = ""

    @property
    def terms(self) -> int:
        return self.model.terms

    @property
    def frac_v(self) -> int:
        return self.word - 1

    @property
    def frac_t(self) -> int:
        return self.word - 2

    @property
    def word_fmt(self):
        return FixedFormat(self.word, self.word)

    @property
    def ka(self) -> int:
        return round(self.input_lsb_v / self.model.input_scale_v * 2.0 ** (self.frac_v + self.norm_guard))

    @property
    def kb(self) -> int:
        """Offset of v_n plus the half LSB that makes the normaliser's shift round to nearest."""
        off = -self.model.input_offset_v / self.model.input_scale_v
        return round(off * 2.0 ** (self.frac_v + self.norm_guard)) + (1 << (self.norm_guard - 1))

    @property
    def weight_frac(self) -> int:
        wmax = max(abs(w) for w in self.model.weights)
        return math.floor(math.log2(self.word_fmt.max_int / wmax))

    @property
    def weights_q(self) -> list[int]:
        return [round(w * 2.0 ** self.weight_frac) for w in self.model.weights]

    @property
    def acc_frac(self) -> int:
        bound = abs(self.model.bias) + sum(abs(w) for w in self.model.weights)
        room = self.word_fmt.max_int - self.terms  # one rounding LSB per product
        return math.floor(math.log2(room / bound))

    @property
    def shift(self) -> int:
        s = self.frac_t + self.weight_frac - self.acc_frac
        if s < 1:
            raise SpecError(f"seed architecture: product shift {s} < 1 (weights too small for {self.word} bits)")
        return s

    @property
    def bias_q(self) -> int:
        return round(self.model.bias * 2.0 ** (self.frac_t + self.weight_frac))

    @property
    def rounds(self) -> list[int]:
        """Constant added to each product before its shift: half an LSB (rounding), and the bias on term 0."""
        half = 1 << (self.shift - 1)
        return [half + self.bias_q] + [half] * (self.terms - 1)

    @property
    def table(self) -> list[int]:
        n = 1 << self.addr_bits
        k = np.arange(n)
        vals = np.round(np.sin(2 * np.pi * (k + 0.5) / n) * 2.0 ** self.frac_t).astype(np.int64)
        return [int(v) for v in self.word_fmt.overflow_policy(vals)]

    @property
    def harmonics(self) -> list[int]:
        return [term_kind(i)[1] for i in range(1, self.terms)]

    @property
    def phase_offsets(self) -> list[int]:
        quarter = 1 << (self.word - 2)  # pi/2 in units of pi with word-1 fraction bits
        return [quarter if term_kind(i)[0] == "cos" else 0 for i in range(1, self.terms)]

    @property
    def levels(self) -> list[dict]:
        """Adder tree levels: input offset, output offset, pairs, and the pass-through
        registers ({"src", "dst"} node indices) that carry an odd node to the next level."""
        out, inp, n, nxt = [], 0, self.terms, self.terms
        while n > 1:
            pairs, odd = n // 2, n % 2
            passes = [{"src": inp + 2 * pairs, "dst": nxt + pairs}] if odd else []
            out.append({"inp": inp, "out": nxt, "pairs": pairs, "passes": passes})
            inp, n = nxt, pairs + odd
            nxt = inp + n
        return out

    @property
    def n_adders(self) -> int:
        return sum(lv["pairs"] for lv in self.levels)

    @property
    def nodes(self) -> int:
        lv = self.levels
        return (lv[-1]["out"] + 1) if lv else self.terms

    @property
    def latency_cycles(self) -> int:
        return 5 + len(self.levels)

    @property
    def output_lsb_mm(self) -> float:
        return 2.0 ** -self.acc_frac

    @property
    def widths(self) -> dict:
        ka_bits = max(2, int(self.ka).bit_length() + 1)
        norm_bits = max(self.input_bits + ka_bits, int(abs(self.kb)).bit_length() + 1) + 1
        harm_bits = max(self.harmonics, default=1).bit_length() + 1
        phase_prod_bits = self.word + harm_bits  # v x harmonic, before the phase keeps its low word bits
        pmax = (1 << (self.word - 1)) ** 2 + max(abs(r) for r in self.rounds)
        prod_bits = max(2 * self.word, pmax.bit_length() + 1)
        return dict(ka_bits=ka_bits, norm_bits=norm_bits, harm_bits=harm_bits, phase_prod_bits=phase_prod_bits,
                    prod_bits=prod_bits)

    def to_dict(self) -> dict:
        return {
            "architecture": "seed_parallel",
            "number_format": f"fixed{self.word}",
            "terms": self.terms,
            "multipliers": self.terms,
            "adders": self.n_adders,
            "input_bits": self.input_bits,
            "input_lsb_v": self.input_lsb_v,
            "clamp_codes": [self.clamp_lo, self.clamp_hi],
            "table_addr_bits": self.addr_bits,
            "weight_frac_bits": self.weight_frac,
            "acc_frac_bits": self.acc_frac,
            "output_lsb_mm": self.output_lsb_mm,
        }


def derive_seed_spec(model_path, **options) -> SeedSpec:
    """The seed architecture with the same ADC scaling and clamp as our design for this model."""
    path = Path(model_path)
    model = load_model(path)
    spec = derive_spec(model, check_device=False, **options)
    return SeedSpec(
        model=model, input_bits=spec.input_bits, input_lsb_v=spec.input_lsb_v,
        clamp_lo=spec.clamp_lo, clamp_hi=spec.clamp_hi, model_sha256=model_sha256(path),
    )


__all__ = ["ENTITY", "SeedSpec", "derive_seed_spec"]
