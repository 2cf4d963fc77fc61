"""Bit-true twin of the family design: one class per new entity, same name, same integers.

The arithmetic is the fixed datapath's twin (:mod:`flann.hardware.fixed.twin`), fed with
the values the weight memory holds: :class:`FlannFamilyMem` encodes a sensor into memory
words and decodes words back into the constants the normaliser and multiplier use, so a
twin built from a memory image computes exactly what the hardware computes with that image.

Port behaviour (docs/production.md, "cfg port"): a cycle with ``cfg_we = 1`` writes
``cfg_data`` at ``cfg_addr`` and cancels the sample in flight (it gives no output); the
next accepted sample reads the memory as written.  Reset keeps the memory.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..fixed.spec import Spec
from ..fixed.twin import FlannMultiplier, FlannNorm, FlannTop
from .spec import DATA_BITS, FamilySpec


def _to_words(value: int, bits: int, words: int) -> list[int]:
    """A field's words, most significant first; a negative value is sign-extended into them."""
    v = int(value) & ((1 << bits) - 1)
    if value < 0:
        v = int(value) & ((1 << (words * DATA_BITS)) - 1)
    return [(v >> (DATA_BITS * k)) & ((1 << DATA_BITS) - 1) for k in reversed(range(words))]


def _from_words(ws, bits: int, signed: bool) -> int:
    v = 0
    for w in ws:
        v = (v << DATA_BITS) | (int(w) & ((1 << DATA_BITS) - 1))
    v &= (1 << bits) - 1
    if signed and v >= 1 << (bits - 1):
        v -= 1 << bits
    return v


class FlannFamilyMem:
    """The weight memory: ``mem_depth`` words of DATA_BITS; write port = cfg_*, read = the datapath."""

    latency = 1  # registered read

    def __init__(self, fam: FamilySpec, words=None):
        self.fam = fam
        self.words = [0] * fam.mem_depth
        if words is not None:
            self.load(words)

    @staticmethod
    def encode(fam: FamilySpec, spec: Spec) -> list[int]:
        """Memory image (mem_depth words) holding sensor ``spec``'s values (as the hardware uses them)."""
        s = spec
        half_v, half_l = 1 << (s.norm_guard - 1), 1 << (s.lin_guard - 1)
        values = {
            "clamp_lo": s.clamp_lo, "clamp_hi": s.clamp_hi, "ka": s.ka,
            "kb": (s.kb + half_v) % (1 << fam.norm_bits), "k1": s.k1, "k0": s.k0 + half_l,
        }
        words = [0] * fam.mem_depth
        for f in fam.fields:
            if f.name == "weights":
                for j, w in enumerate(w for lane in s.weight_rom for w in lane):
                    words[f.addr + j] = _to_words(w, f.bits, 1)[0]
            else:
                words[f.addr:f.addr + f.words] = _to_words(values[f.name], f.bits, f.words)
        return words

    def load(self, words) -> None:
        words = [int(w) for w in words]
        if len(words) > self.fam.mem_depth or any(not 0 <= w < (1 << DATA_BITS) for w in words):
            raise ValueError(f"a memory image is at most {self.fam.mem_depth} words of {DATA_BITS} bits")
        self.words = words + [0] * (self.fam.mem_depth - len(words))

    def write(self, addr: int, data: int) -> None:
        """One cfg_we cycle (addresses wrap to the address width, data to the word width)."""
        self.words[int(addr) % self.fam.mem_depth] = int(data) & ((1 << DATA_BITS) - 1)

    def decode(self) -> dict:
        """The constants the datapath reads: weights (list) and the normaliser's values."""
        fam, out = self.fam, {}
        for f in fam.fields:
            if f.name == "weights":
                out["weights"] = [_from_words([self.words[f.addr + j]], f.bits, True) for j in range(f.words)]
            else:
                out[f.name] = _from_words(self.words[f.addr:f.addr + f.words], f.bits, f.signed)
        return out

    def spec(self) -> Spec:
        """The fixed-datapath Spec the hardware computes with this memory content."""
        fam, d = self.fam, self.decode()
        s = fam.spec
        return replace(s, clamp_lo=d["clamp_lo"], clamp_hi=d["clamp_hi"], ka=d["ka"],
                       kb=(d["kb"] - (1 << (s.norm_guard - 1))) % (1 << fam.norm_bits),
                       k1=d["k1"], k0=d["k0"] - (1 << (s.lin_guard - 1)), weight_rom=(tuple(d["weights"]),))


class FlannFamilyNorm(FlannNorm):
    """flann_family_norm: the fixed normaliser's integers, its constants read from the memory
    (modulo arithmetic in a shared register: the same results, bit for bit)."""

    def __init__(self, fam: FamilySpec, mem: FlannFamilyMem):
        super().__init__(mem.spec())
        self.latency = fam.norm_latency


class FlannFamilyMultiplier(FlannMultiplier):
    """flann_family_multiplier: the shift-add multiplier reading its weight from the memory."""

    def __init__(self, fam: FamilySpec, mem: FlannFamilyMem):
        super().__init__(mem.spec())


class FlannFamilyTop:
    """flann_family_top: out_data / out_sat for every sample, given the memory content."""

    entity = "flann_family_top"

    def __init__(self, fam: FamilySpec, words=None):
        self.fam = fam
        self.mem = FlannFamilyMem(fam, words if words is not None else FlannFamilyMem.encode(fam, fam.spec))
        self.latency = fam.latency_cycles

    def write(self, addr: int, data: int) -> None:
        self.mem.write(addr, data)

    def load(self, words) -> None:
        self.mem.load(words)

    def top(self) -> FlannTop:
        """The fixed-datapath twin with the memory's values (same arithmetic, stage by stage)."""
        return FlannTop(self.mem.spec())

    def process(self, codes) -> tuple[np.ndarray, np.ndarray]:
        return self.top().process(codes)

    def all_codes(self) -> np.ndarray:
        s = self.fam.spec
        return np.arange(s.code_min, s.code_max + 1, dtype=np.int64)

    def error_vs_float(self, codes=None) -> dict:
        """max |twin - float model of the loaded sensor| (the fixed datapath's measure)."""
        return self.top().error_vs_float(codes)

    def trace(self, codes):
        return self.top().trace(codes)


__all__ = ["FlannFamilyMem", "FlannFamilyNorm", "FlannFamilyMultiplier", "FlannFamilyTop"]
