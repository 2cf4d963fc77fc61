"""The LVDT conditioner as a datapath: its record, the design directory it writes, its hooks.

``write_conditioner(spec, out_dir)`` writes the VHDL of every entity and a ``manifest.json``
with the common fields (``input_bits`` the converters', ``output_bits`` the ratio's,
``cycles_per_sample`` the fewest clocks between converter strobes, ``latency_cycles`` from a
window's last strobe to its ratio) and the spec.  ``flann gen`` does not write it from a
model yet: that needs a model trained from waveforms that carries the conditioner's settings.
"""

from __future__ import annotations

from ...errors import FlannError
from ..datapath import Datapath, _int
from ..header import NO_MODEL
from ..manifest import write_design
from .render import ENTITIES, TOP, cycles_per_sample, render
from .spec import ConditionerSpec
from .twin import ConditionerChain
from ... import __version__

NAME = "conditioner"
WHY = "the conditioner is written from a spec (write_conditioner), not yet from a model: it has no {}"
LACKS = "it is written from a spec (write_conditioner), not from a model"


def latency_cycles(spec: ConditionerSpec) -> int:
    return ConditionerChain(spec).latency


def manifest(spec: ConditionerSpec, input_lsb_v: float) -> dict:
    return {"top": TOP, "files": [f"{e.name}.vhd" for e in ENTITIES], "datapath": NAME,
            "input_bits": spec.adc_bits, "input_lsb_v": input_lsb_v, "output_bits": spec.ratio_bits,
            "latency_cycles": latency_cycles(spec), "cycles_per_sample": cycles_per_sample(spec),
            "generator_version": __version__, "model_sha256": NO_MODEL, "spec": spec.to_dict()}


def write_conditioner(spec: ConditionerSpec, out_dir, adc_range_v: float) -> dict:
    """Write the conditioner's design directory; returns its manifest."""
    return write_design(render(spec), manifest(spec, 2.0 * adc_range_v / (1 << spec.adc_bits)), out_dir)


def rebuild(model, man: dict, where="design"):
    """The spec a manifest records, checked by deriving its dependent widths again."""
    try:
        spec = ConditionerSpec(**man["spec"])
    except TypeError as exc:
        raise FlannError(f"{where}: the manifest's spec is not a conditioner's ({exc})") from None
    if man.get("output_bits") != spec.ratio_bits or man.get("input_bits") != spec.adc_bits:
        raise FlannError(f"{where}: input_bits/output_bits differ from its spec: regenerate the design")
    return spec, spec.to_dict()


def generate(model, out_dir, options=None, **_extra) -> dict:
    raise FlannError(WHY.format("generator from a model.json (flann gen)"))


DATAPATH = Datapath(
    name=NAME, top=TOP, about="LVDT conditioner: excitation NCO, ADC ports, I/Q demodulation, ratio",
    generate=generate, rebuild=rebuild, twin=ConditionerChain, estimate=lambda man: None,
    fields=(_int("spec.adc_bits", 4), _int("spec.table_bits", 2), _int("spec.sine_bits", 4),
            _int("spec.samples_per_period", 8), _int("spec.periods_per_output"), _int("spec.ratio_frac_bits")),
    model_field="", lacks=LACKS, ise=False,
)

__all__ = ["DATAPATH", "write_conditioner", "manifest", "latency_cycles"]
