"""The two-input (voltage, temperature) datapath behind the common :class:`Datapath` interface."""

from __future__ import annotations

from ..datapath import Datapath, Field, _int, _num, check_design_model
from ..fixed.datapath import DATAPATH as FIXED
from . import render
from .twin import FlannThermalTop


def eval_spec(model, man: dict, directory):
    """The design's ThermalSpec for ``model``, which must be the two-input model it was generated
    from (a one-input model is refused by the rebuild in one line)."""
    render.load_model(model)
    check_design_model(model, man, directory)
    return render.rebuild(model, man, directory)[0]


def estimate(man: dict) -> dict | None:
    return None  # no estimate before synthesis: flann synth measures it


def summary(man: dict) -> list[str]:
    a = man["analysis"]
    return [f"  {man['input_bits']}-bit input x {man['input_lsb_v']} V, {man['temp_bits']}-bit temperature x "
            f"{man['temp_lsb_c']} degC -> {man['output_bits']}-bit output x {man['output_lsb_mm']} mm; "
            f"{man['cycles_per_sample']} cycles/sample",
            f"  error bound {a['pre_rounding_lsb'] + 0.5:.3f} LSB; {len(man['spec']['orders'])} temperature "
            "order(s), each a one-input datapath"]


FIELDS = (
    _num("output_lsb_mm", 0), Field("model_sha256", (str,)), _int("temp_bits", 2), _num("temp_lsb_c", 0),
    Field("clamp_codes", (list,)), Field("temp_clamp_codes", (list,)),
    _int("spec.input_bits", 2), _num("spec.input_lsb_v", 0), _int("spec.temp_bits", 2),
    _num("spec.temp_lsb_c", 0), _num("spec.output_lsb_mm", 0), Field("spec.orders", (list,)),
    _num("analysis.pre_rounding_lsb", 0),
)

DATAPATH = Datapath(
    name=render.DATAPATH, top=render.TOP,
    about="two inputs (voltage, temperature): one fixed datapath per temperature order",
    generate=render.generate, rebuild=render.rebuild, twin=FlannThermalTop, estimate=estimate, fields=FIELDS,
    summary=summary, number_format=FIXED.number_format, eval_spec=eval_spec,
    lacks="flann explore explores one-input models; a thermal design keeps a two-input model",
)

__all__ = ["DATAPATH"]
