"""Bit-true twin of flann_family_thermal_top: the orders' family twins, then Horner in t_n.

Order j is :class:`flann.hardware.family.twin.FlannFamilyTop` with memory j's words (the
hardware shares one expansion, driven by order 0's normaliser: every order of an image holds
the same input scale and clamp, checked on load); the top
combines the order outputs (LSB q / 2^K) with the exact t_n code (``tau - mid``, S fraction
bits) as the VHDL does: ``acc = f_{P-1}``; per step ``acc = round(acc x t, S) + f_j`` (the
serial multiplier forms the exact product, one rounding: add 2^(S-1), shift right); the output
is ``round(acc, K)`` saturated to the output code.  A memory image of a sensor is every
order's memory in turn (``mem_depth`` words each).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ...numeric.fixed import round_shift
from ..family.twin import FlannFamilyMem, FlannFamilyTop
from ..twin import TopOut
from .spec import FamilyThermalSpec, check_member


@dataclass(frozen=True)
class FamilyThermalTrace(TopOut):
    """The output ports and the internal values: each order's output (LSB q / 2^K), the t_n
    code (tau clamped, minus mid: S fraction bits) and the Horner sum before the output rounding."""

    parts: list = field(default_factory=list)
    t_n: np.ndarray | None = None
    acc: np.ndarray | None = None


# normaliser values every order's memory holds alike (order 0's drive the shared expansion)
SHARED_FIELDS = ("clamp_lo", "clamp_hi", "ka", "kb")


def encode_image(spec: FamilyThermalSpec, model) -> list[int]:
    """A sensor's image: every order's memory words in turn (FitError if it does not fit)."""
    words = []
    for order_spec in check_member(spec, model):
        words += FlannFamilyMem.encode(spec.fam, order_spec)
    return words


class FlannFamilyThermalTop:
    entity = "flann_family_thermal_top"

    def __init__(self, spec: FamilyThermalSpec, words=None):
        self.spec = spec
        self.latency = spec.latency_cycles
        self.load(encode_image(spec, spec.model) if words is None else words)

    def load(self, words) -> None:
        words = [int(w) for w in words]
        d = self.spec.fam.mem_depth
        if len(words) != self.spec.image_words:
            raise ValueError(f"a memory image is {self.spec.image_words} words ({self.spec.orders} x {d})")
        orders = [FlannFamilyTop(self.spec.fam, words[j * d:(j + 1) * d]) for j in range(self.spec.orders)]
        # the hardware's one expansion runs on order 0's phase: an image whose orders hold
        # another input scale or clamp is one the design does not compute (encode_image never
        # writes one)
        shared = [{k: v for k, v in o.mem.decode().items() if k in SHARED_FIELDS} for o in orders]
        if any(f != shared[0] for f in shared[1:]):
            raise ValueError(f"an image's orders must hold one {', '.join(SHARED_FIELDS)} (the expansion is shared)")
        self.orders = orders

    def trace(self, in_data, in_temp) -> FamilyThermalTrace:
        """The top's internal values (flann trace): each order's output, t_n, the Horner sum."""
        s = self.spec
        codes, temps = np.broadcast_arrays(np.asarray(in_data, dtype=np.int64), np.asarray(in_temp, dtype=np.int64))
        distinct, back = np.unique(codes, return_inverse=True)
        parts, sat = [], (temps < s.temp.lo) | (temps > s.temp.hi)
        for top in self.orders:
            out, osat = top.process(distinct)
            parts.append(np.asarray(out, dtype=np.int64)[back].reshape(codes.shape))
            sat = sat | np.asarray(osat, dtype=bool)[back].reshape(codes.shape)
        t = s.temp.t_code(temps)
        acc = parts[-1]
        for part in reversed(parts[:-1]):
            acc = round_shift(acc * t, s.temp.shift) + part
        out = round_shift(acc, s.inner_bits)
        clipped = (out > s.out_fmt.max_int) | (out < s.out_fmt.min_int)
        return FamilyThermalTrace(np.clip(out, s.out_fmt.min_int, s.out_fmt.max_int), sat | clipped,
                                  parts, t, acc)

    def process(self, in_data, in_temp) -> TopOut:
        tr = self.trace(in_data, in_temp)
        return TopOut(tr.out_data, tr.out_sat)

    def all_codes(self) -> np.ndarray:
        return np.arange(self.spec.code_min, self.spec.code_max + 1, dtype=np.int64)

    def error_vs_float(self, temp_codes=None, codes=None, model=None) -> dict:
        """max |twin - float model| (output LSBs) over ``codes`` (every voltage code) at each
        of ``temp_codes`` (default: the calibrated temperature codes' ends and middle);
        output clipping is not an error."""
        s = self.spec
        codes = self.all_codes() if codes is None else np.asarray(codes, dtype=np.int64)
        temp_codes = [s.temp.lo, s.temp.mid, s.temp.hi] if temp_codes is None else temp_codes
        ref_spec = s if model is None else replace(s, model=model)
        worst = 0.0
        for tau in np.asarray(temp_codes, dtype=np.int64):
            r = self.process(codes, tau)
            ref = ref_spec.float_reference(codes, tau) / s.output_lsb_mm
            ok = ~(r.out_sat & (np.abs(ref) > s.out_fmt.max_int))
            if ok.any():
                worst = max(worst, float(np.max(np.abs(r.out_data - ref)[ok])))
        return {"max_err_lsb": worst, "max_err_mm": worst * s.output_lsb_mm, "codes": int(codes.size),
                "temperature_codes": int(np.size(temp_codes))}


__all__ = ["FlannFamilyThermalTop", "FamilyThermalTrace", "TopOut", "encode_image"]
