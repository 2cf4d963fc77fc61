"""Bit-true twin of ``flann_seed_top`` (the seed's parallel architecture)."""

from __future__ import annotations

import numpy as np

from ...errors import SpecError
from ..twin import TopOut
from .spec import ENTITY, SeedSpec


class FlannSeedTop:
    """out_data / out_sat of flann_seed_top for each input code, exactly as the VHDL computes them."""

    entity = ENTITY

    def __init__(self, spec: SeedSpec):
        self.spec = spec
        self.latency = spec.latency_cycles

    def process(self, codes) -> TopOut:
        s = self.spec
        wf = s.word_fmt
        c_in = np.asarray(codes, dtype=np.int64)
        c = np.clip(c_in, s.clamp_lo, s.clamp_hi)
        W = s.word
        v = wf.overflow_policy((c * s.ka + s.kb) >> s.norm_guard)  # saturated v_n
        table = np.asarray(s.table, dtype=np.int64)
        terms = [v >> 1]
        for m, off in zip(s.harmonics, s.phase_offsets):
            theta = ((v * m) + off) & ((1 << W) - 1)  # modular on purpose: phase mod 2
            terms.append(table[theta >> (W - s.addr_bits)])
        acc = np.zeros_like(v)
        for t, w, r in zip(terms, s.weights_q, s.rounds):
            p = (t * w + r) >> s.shift
            if not wf.fits(p):
                raise SpecError("seed architecture: a product overflows the accumulator format")
            acc = acc + p
        if not wf.fits(acc):
            raise SpecError("seed architecture: the adder tree overflows")
        return TopOut(out_data=acc, out_sat=c != c_in)

    def all_codes(self) -> np.ndarray:
        return np.arange(-(1 << (self.spec.input_bits - 1)), 1 << (self.spec.input_bits - 1), dtype=np.int64)

    def error_vs_float(self, codes=None) -> dict:
        s = self.spec
        codes = np.arange(s.clamp_lo, s.clamp_hi + 1, dtype=np.int64) if codes is None else np.asarray(codes)
        out = self.process(codes).out_data
        ref = s.model.predict(codes * s.input_lsb_v)
        e = float(np.max(np.abs(out * s.output_lsb_mm - ref)))
        return {"max_err_lsb": e / s.output_lsb_mm, "max_err_mm": e, "codes": int(codes.size)}


__all__ = ["FlannSeedTop"]
