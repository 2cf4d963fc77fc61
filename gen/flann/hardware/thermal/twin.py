"""Bit-true twin of the two-input datapath (:mod:`.spec`): the same integer arithmetic.

``FlannThermalTop(spec).process(in_data, in_temp)`` returns the output ports ``out_data`` (in
output LSBs) and ``out_sat`` (an input outside the calibrated codes, clamped, or the output
saturated at the calibrated displacement limits ``spec.out_lo``/``spec.out_hi``), plus the
internal stages in :class:`ThermalTrace`.  The order datapaths are
:class:`flann.hardware.fixed.twin.FlannTop`, unchanged.  The entity is the rendered top's (:mod:`.render`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...numeric.fixed import round_shift
from ..fixed.twin import FlannTop
from ..twin import TopOut
from .spec import ThermalSpec


def _horner(coefs, t, frac_bits: int) -> np.ndarray:
    """coefs[0] + t (coefs[1] + t (coefs[2] ...)) with t at frac_bits, one rounding per step."""
    acc = np.full(t.shape, coefs[-1], dtype=np.int64)
    for c in reversed(coefs[:-1]):
        acc = round_shift(acc * t, frac_bits) + c
    return acc


@dataclass(frozen=True)
class ThermalTrace:
    t_n: np.ndarray          # at FT fraction bits
    gain: np.ndarray         # at FG fraction bits
    fine_code: np.ndarray    # c' in grid codes at interp_bits fraction bits
    parts: tuple             # each order's out_data (q / 2^K)
    acc: np.ndarray          # after Horner, q / 2^K
    out_data: np.ndarray
    out_sat: np.ndarray


class FlannThermalTop:
    entity = "flann_thermal_top"

    def __init__(self, spec: ThermalSpec):
        self.spec = spec
        self.latency = spec.latency_cycles
        self.orders = [FlannTop(s) for s in spec.orders]

    def trace(self, in_data, in_temp) -> ThermalTrace:
        s = self.spec
        c_in, tau_in = np.broadcast_arrays(np.asarray(in_data, dtype=np.int64),
                                           np.asarray(in_temp, dtype=np.int64))
        c = np.clip(c_in, s.clamp_lo, s.clamp_hi)
        tau = np.clip(tau_in, s.temp_lo, s.temp_hi)
        sat = (c != c_in) | (tau != tau_in)
        t_n = round_shift(tau * s.t_scale_int + s.t_offset_int, s.t_shift)
        gain = _horner(s.gain_int, t_n, s.t_frac_bits)
        offset = _horner(s.offset_int, t_n, s.t_frac_bits)
        fine = round_shift((c << (s.fine_bits + s.interp_bits)) * gain + offset, s.g_frac_bits)
        node = fine >> s.interp_bits
        frac = fine & ((1 << s.interp_bits) - 1)
        parts = []
        # each order's datapath once per distinct grid code (a node and the next)
        distinct, back = np.unique(np.concatenate([node.ravel(), node.ravel() + 1]), return_inverse=True)
        back_a, back_b = back[:node.size].reshape(node.shape), back[node.size:].reshape(node.shape)
        for top in self.orders:
            out, osat = top.process(distinct)
            a, b = out[back_a], out[back_b]
            parts.append(a + round_shift((b - a) * frac, s.interp_bits))
            sat = sat | osat[back_a]
        acc = parts[-1]
        for part in reversed(parts[:-1]):
            acc = round_shift(acc * t_n, s.t_frac_bits) + part
        # saturate at the calibrated displacement limits (within the output format)
        rounded = round_shift(acc, s.inner_bits)
        out = np.clip(rounded, s.out_lo, s.out_hi)
        clipped = out != rounded
        return ThermalTrace(t_n, gain, fine, tuple(parts), acc, out, sat | clipped)

    def process(self, in_data, in_temp) -> TopOut:
        t = self.trace(in_data, in_temp)
        return TopOut(out_data=t.out_data, out_sat=t.out_sat)

    def all_codes(self) -> np.ndarray:
        """Every voltage code (each is checked at the temperature codes the bench states)."""
        return np.arange(self.spec.code_min, self.spec.code_max + 1, dtype=np.int64)

    def all_temp_codes(self) -> np.ndarray:
        return np.arange(self.spec.temp_code_min, self.spec.temp_code_max + 1, dtype=np.int64)

    def error_vs_float(self, temp_codes=None, codes=None) -> dict:
        """max |twin - float| (output LSBs) over every voltage code (default) at each of
        ``temp_codes`` (default: every temperature code); the float reference is saturated at the
        output limits as the hardware is, so a saturated output is compared with its limit."""
        s = self.spec
        codes = self.all_codes() if codes is None else np.asarray(codes, dtype=np.int64)
        temp_codes = self.all_temp_codes() if temp_codes is None else temp_codes
        worst = 0.0
        for tau in np.asarray(temp_codes, dtype=np.int64):
            out, _sat = self.process(codes, tau)
            ref = s.float_reference(codes, tau) / s.output_lsb_mm
            worst = max(worst, float(np.max(np.abs(out - ref))))
        return {"max_err_lsb": worst, "max_err_mm": worst * s.output_lsb_mm,
                "codes": int(codes.size), "temperature_codes": int(np.size(temp_codes))}


__all__ = ["FlannThermalTop", "ThermalTrace"]
