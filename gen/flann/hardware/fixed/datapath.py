"""The fixed-point datapath (``flann gen MODEL``) behind the common :class:`Datapath` interface."""

from __future__ import annotations

import warnings

from ...golden.model import load_model

from ..datapath import Datapath, Field, _int, _num, check_design_model
from ..options import GenOptions
from . import render
from .spec import derive_spec
from .twin import FlannTop


def generate(model, out_dir, options: GenOptions | None = None) -> dict:
    return render.generate(model, out_dir, options)


def rebuild(model, man: dict, where="design"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return render.rebuild_spec(model, man, where, check_device=False)


def eval_spec(model, man: dict, directory):
    """The design's Spec for ``model``, which must be the model it was generated from."""
    load_model(model)  # a file that is not a model says so before the hash is compared
    check_design_model(model, man, directory)
    return rebuild(model, man, directory)[0]


def estimate(man: dict) -> dict:
    return dict(man["analysis"]["estimate"])


def summary(man: dict) -> list[str]:
    a = man["analysis"]
    return [f"  {man['input_bits']}-bit input x {man['input_lsb_v']} V -> {man['output_bits']}-bit output x "
            f"{man['output_lsb_mm']} mm; {man['cycles_per_sample']} cycles/sample",
            f"  error bound {a['bound_total_lsb']:.3f} LSB; estimate {a['estimate']}"]


FIELDS = (
    _num("output_lsb_mm", 0), Field("model_sha256", (str,)),
    _int("adc_bits", 2), _num("adc_lsb_v", 0), Field("clamp_codes", (list,)),
    _int("spec.input_bits", 2), _num("spec.input_lsb_v", 0), Field("spec.output", (str,)),
    _int("spec.lanes"), Field("spec.mult_style", (str,)), _int("spec.phase_bits"),
    _int("spec.table_addr_bits"), Field("spec.interp", (bool,)),
    _int("analysis.estimate.luts", 0), _int("analysis.estimate.ffs", 0), _int("analysis.estimate.brams", 0),
)

DATAPATH = Datapath(
    name=render.DATAPATH, top=render.TOP, about="fixed point, widths from the error budget",
    generate=generate, rebuild=rebuild, twin=FlannTop, estimate=estimate, fields=FIELDS,
    derive_options=lambda options, compared=False: options.to_kwargs(),
    summary=summary, eval_spec=eval_spec, derive=derive_spec, number_format=render.DATAPATH,
)

__all__ = ["DATAPATH"]
