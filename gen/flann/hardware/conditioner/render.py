"""Render the conditioner's VHDL-93 entities from a :class:`~.spec.ConditionerSpec`.

One context per entity, computed here (widths, literals checked to fit); one template per
entity in ``hardware/conditioner/templates``; deterministic text (the header carries the spec).
"""

from __future__ import annotations

from dataclasses import dataclass

from ...numeric.fixed import bits_literal
from ...textgen import template
from ..header import header
from .spec import ConditionerSpec
from .twin import FlannCondDemod, FlannCondRatio, FlannCondRotate

TEMPLATES = "hardware/conditioner/templates"


@dataclass(frozen=True)
class Entity:
    name: str
    title: str


# compile order
ENTITIES = (
    Entity("flann_cond_nco", "excitation NCO: phase accumulator, cosine table, DAC port"),
    Entity("flann_cond_adc", "ADC input port"),
    Entity("flann_cond_demod", "synchronous I/Q demodulation and integration over whole carrier periods"),
    Entity("flann_cond_rotate", "fine reference phase: the window sums rotated by a calibrated angle"),
    Entity("flann_cond_ratio", "ratiometric (A - B) / (A + B), serial divider"),
    Entity("flann_cond_top", "LVDT conditioner, top level"),
)
TOP = "flann_cond_top"


def cycles_per_sample(s: ConditionerSpec) -> int:
    """Fewest clocks between converter strobes: the demodulator's serial product."""
    return FlannCondDemod(s).latency + 2


def _ubits(value: int) -> int:
    return max(1, int(value).bit_length())


def _table(s: ConditionerSpec) -> dict:
    return dict(depth=1 << s.table_bits, words=[bits_literal(int(w), s.sine_bits) for w in s.table()],
                table_bits=s.table_bits, sine_bits=s.sine_bits)


def contexts(s: ConditionerSpec) -> dict[str, dict]:
    """Template context of every entity, by its VHDL name."""
    ratio_busy = FlannCondRatio(s).latency
    return {
        "flann_cond_nco": dict(**_table(s), step=s.step, samples_per_period=s.samples_per_period,
                               phase_bits=s.phase_bits, table_lsb=s.phase_bits - s.table_bits,
                               step_literal=bits_literal(s.step, s.phase_bits, signed=False)),
        "flann_cond_adc": dict(adc_bits=s.adc_bits),
        "flann_cond_demod": dict(**_table(s), adc_bits=s.adc_bits, acc_bits=s.acc_bits, window=s.window,
                                 periods=s.periods_per_output, busy=cycles_per_sample(s),
                                 quarter_literal=bits_literal(s.quarter, s.table_bits, signed=False),
                                 count_bits=_ubits(s.window - 1), bit_bits=_ubits(s.adc_bits - 1),
                                 last_literal=bits_literal(s.window - 1, _ubits(s.window - 1), signed=False)),
        "flann_cond_rotate": dict(acc_bits=s.acc_bits, tan_bits=s.tan_bits, rot_bits=s.rotation_bits,
                                  prod_bits=s.acc_bits + s.tan_bits, bit_bits=_ubits(s.tan_bits - 1),
                                  busy=FlannCondRotate(s).latency,
                                  hi_literal=bits_literal((1 << (s.acc_bits - 1)) - 1, s.acc_bits),
                                  lo_literal=bits_literal(-(1 << (s.acc_bits - 1)), s.acc_bits)),
        "flann_cond_ratio": dict(in_bits=s.acc_bits, frac_bits=s.ratio_frac_bits, ratio_bits=s.ratio_bits,
                                 work_bits=s.sum_bits + 1, bit_bits=_ubits(s.ratio_frac_bits),
                                 busy=ratio_busy + 1,
                                 max_literal=bits_literal((1 << s.ratio_frac_bits) - 1, s.ratio_bits),
                                 min_literal=bits_literal(-((1 << s.ratio_frac_bits) - 1), s.ratio_bits)),
        "flann_cond_top": dict(adc_bits=s.adc_bits, table_bits=s.table_bits, sine_bits=s.sine_bits,
                               tan_bits=s.tan_bits, rot_bits=s.rotation_bits,
                               acc_bits=s.acc_bits, ratio_bits=s.ratio_bits, frac_bits=s.ratio_frac_bits,
                               window=s.window, cycles_per_sample=cycles_per_sample(s)),
    }


def render(s: ConditionerSpec, command: str = "flann gen") -> dict[str, str]:
    """{file name: VHDL text} of every entity, in compile order."""
    ctx = contexts(s)
    spec_dict = s.to_dict()
    return {f"{e.name}.vhd": template(f"{TEMPLATES}/{e.name}.vhd.j2").render(
        h=header(f"{e.name}.vhd", e.title, command, spec_dict), entity=e.name, **ctx[e.name])
        for e in ENTITIES}
