"""The whole chain as one design: the conditioner (:class:`~.twin.ConditionerChain`,
``flann_cond_top``) and the FLANN behind it (:class:`~flann.hardware.fixed.twin.FlannTop`,
``flann_top``), joined in ``flann_chain_top``: converter codes in, excitation out, displacement
code out.

The ratio code enters the FLANN as any converter wider than its input does
(:func:`flann.hardware.adc.wired_codes`: its top bits, the low ones not wired): the ratio is the
FLANN's converter, ``ratio_bits`` wide with ``2^-F`` a code, as training gave it the ratio.  The
divider saturates at +-(1 - 2^-F) and the FLANN clamps to its trained codes, so nothing wraps.
The chain's ``out_sat`` is the FLANN's (its input outside the trained range, or its output
saturated) or the divider's for the window it came from (the secondaries out of phase, or no
signal).

The FLANN takes one sample at a time; the conditioner gives one ratio a window of ``M``
converter strobes, each at least ``cycles_per_sample`` clocks apart, so the FLANN is idle when a
ratio comes when its own cycles per sample fit in that window (:class:`ChainSpec` refuses a
chain where they do not).

A two-input FLANN (:mod:`flann.hardware.thermal`, a model trained from waveforms at several
temperatures) adds the port ``in_temp``: the temperature code at a window's last converter
strobe is held for that window's ratio (a register the strobes' own count loads), so a window's
displacement is computed at its own temperature whenever the temperature code changes.

Public API: :class:`ChainSpec`, :class:`FlannChainTop`, :func:`render_chain`, ``CHAIN_TOP``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import SpecError
from ...numeric.fixed import bits_literal
from ...textgen import template
from ..adc import wired_codes
from ..fixed.spec import Spec
from ..fixed.twin import FlannTop
from ..thermal.spec import ThermalSpec
from ..thermal.twin import FlannThermalTop
from ..header import header
from ..twin import Record
from .render import TEMPLATES, cycles_per_sample
from .spec import ConditionerSpec, Reference
from .twin import ConditionerChain, FlannCondRatio

CHAIN_TOP = "flann_chain_top"


def window_temperatures(temp_codes, window: int, windows: int) -> np.ndarray:
    """The temperature code each of ``windows`` windows of ``window`` strobes is computed at:
    its last strobe's (the chain top's register, loaded by the strobes' count)."""
    return np.asarray(temp_codes, dtype=np.int64)[window - 1::window][:windows]


@dataclass(frozen=True)
class ChainSpec:
    """The conditioner's spec and the FLANN's behind it (one input, or two with the
    temperature); ``flann_top`` its entity's name."""

    conditioner: ConditionerSpec
    flann: Spec | ThermalSpec
    flann_top: str = "flann_top"

    def __post_init__(self):
        c, f = self.conditioner, self.flann
        if f.input_bits > c.ratio_bits:
            raise SpecError(f"the FLANN's {f.input_bits}-bit input is wider than the conditioner's "
                            f"{c.ratio_bits}-bit ratio: generate it behind the conditioner (flann gen MODEL)")
        if self.ratio_clocks < f.cycles_per_sample:
            raise SpecError(f"a ratio every {self.ratio_clocks} clocks ({c.window} strobes of {cycles_per_sample(c)}), "
                            f"but the FLANN takes {f.cycles_per_sample} clocks a sample: lower the output rate "
                            "(flann train --output-rate-hz) or train fewer terms")
        ratio_latency = ConditionerChain(c).latency
        if self.temp_bits and ratio_latency >= self.ratio_clocks:
            raise SpecError(f"a window's ratio comes {ratio_latency} clocks after its last strobe, "
                            f"not within the next window's {self.ratio_clocks}: its temperature would not be held "
                            "for it; lower the output rate (flann train --output-rate-hz)")

    @property
    def temp_bits(self) -> int | None:
        """The temperature code's width of a two-input FLANN; None for one input."""
        return getattr(self.flann, "temp_bits", None)

    @property
    def ratio_clocks(self) -> int:
        """Fewest clocks between two ratios: a window of strobes at the fastest."""
        return self.conditioner.window * cycles_per_sample(self.conditioner)

    @property
    def dropped(self) -> int:
        """Low ratio bits the FLANN's input does not take."""
        return self.conditioner.ratio_bits - self.flann.input_bits

    @property
    def latency(self) -> int:
        """Clocks from a window's last converter strobe to its displacement code (a window the
        divider saturates on comes earlier: :meth:`latencies`)."""
        return ConditionerChain(self.conditioner).latency + self.flann.latency_cycles

    def latencies(self, ratio_sat) -> np.ndarray:
        """Each window's clocks from its last strobe to its code: the divider answers a saturated
        ratio without dividing."""
        ratio = FlannCondRatio(self.conditioner)
        early = ratio.latency - ratio.saturated_latency
        return np.where(np.asarray(ratio_sat) != 0, self.latency - early, self.latency)

    def to_dict(self) -> dict:
        out = {"conditioner": self.conditioner.to_dict(), "flann_top": self.flann_top,
               "flann_input_bits": self.flann.input_bits, "flann_output_bits": self.flann.out_fmt.width,
               "dropped_ratio_bits": self.dropped}
        if self.temp_bits:
            out["flann_temp_bits"] = self.temp_bits
        return out


@dataclass(frozen=True)
class ChainTopOut(Record):
    out_data: np.ndarray    # per window: the displacement code
    out_sat: np.ndarray     # the FLANN's saturation or the divider's
    ratio: np.ndarray       # the conditioner's ratio code
    ratio_sat: np.ndarray   # the divider's saturation
    flann_code: np.ndarray  # the FLANN's input code (the ratio's top bits)
    temp_code: np.ndarray | None = None   # a two-input FLANN's: the code at the window's last strobe


class FlannChainTop:
    """Converter codes (and a two-input FLANN's temperature codes, one a strobe) to
    displacement codes: the conditioner's twin, the ratio wired to the FLANN's input, the
    FLANN's twin."""

    entity = CHAIN_TOP

    def __init__(self, spec: ChainSpec):
        self.spec = spec
        self.conditioner = ConditionerChain(spec.conditioner)
        self.flann = FlannThermalTop(spec.flann) if spec.temp_bits else FlannTop(spec.flann)

    @property
    def latency(self) -> int:
        return self.spec.latency

    def process(self, codes_a, codes_b, ref: Reference, temp_codes=None) -> ChainTopOut:
        """Every whole window of the codes at the reference ``ref``: its displacement code;
        ``temp_codes`` (one a strobe) for a two-input FLANN, which takes each window's last."""
        if (temp_codes is None) != (self.spec.temp_bits is None):
            raise SpecError("temperature codes are for a FLANN with a temperature input, and it needs them")
        c = self.conditioner.process(codes_a, codes_b, ref)
        code = wired_codes(c.out_ratio, self.spec.conditioner.ratio_bits, self.spec.flann.input_bits)
        temp = None
        if temp_codes is None:
            f = self.flann.process(code)
        else:
            temp = window_temperatures(temp_codes, self.spec.conditioner.window, code.size)
            f = self.flann.process(code, temp)
        sat = (np.asarray(f.out_sat, dtype=bool) | (c.out_sat != 0)).astype(np.int64)
        return ChainTopOut(f.out_data, sat, c.out_ratio, c.out_sat, code, temp)


def render_chain(spec: ChainSpec, command: str = "flann gen", model_sha256: str = "") -> dict[str, str]:
    """{file name: VHDL text} of the chain's top (the conditioner's and the FLANN's entities are
    rendered by their own datapaths)."""
    c, f = spec.conditioner, spec.flann
    name = f"{CHAIN_TOP}.vhd"
    count_bits = max(1, (c.window - 1).bit_length())   # the strobes of a window, counted for its temperature
    h = header(name, "LVDT conditioner and FLANN, top level", command, spec.to_dict(), model_sha256)
    return {name: template(f"{TEMPLATES}/{CHAIN_TOP}.vhd.j2").render(
        h=h, entity=CHAIN_TOP, flann_top=spec.flann_top, adc_bits=c.adc_bits, table_bits=c.table_bits,
        sine_bits=c.sine_bits, tan_bits=c.tan_bits, ratio_bits=c.ratio_bits, dropped=spec.dropped,
        in_bits=f.input_bits, out_bits=f.out_fmt.width, cycles_per_sample=cycles_per_sample(c),
        window=c.window, flann_cycles=f.cycles_per_sample, latency=spec.latency, temp_bits=spec.temp_bits,
        count_bits=count_bits, last_count=bits_literal(c.window - 1, count_bits, signed=False))}


__all__ = ["CHAIN_TOP", "ChainSpec", "ChainTopOut", "FlannChainTop", "render_chain", "window_temperatures"]
