"""The LVDT conditioner as a datapath: its record, the design directory it writes, its hooks.

``write_conditioner(spec, out_dir)`` writes the VHDL of every entity and a ``manifest.json``
with the common fields (``input_bits`` the converters', ``output_bits`` the ratio's,
``cycles_per_sample`` the fewest clocks between converter strobes, ``latency_cycles`` from a
window's last strobe to its ratio) and the spec.

``flann gen MODEL`` of a model trained from waveforms (its ``conditioner`` settings) writes the
same directory at the model's settings together with the FLANN's fixed-point design (its
entities, the model, and its own manifest under the field ``flann``), which takes the ratio
code as its converter: one directory that ``flann sim`` verifies whole.  The two are not joined
into one top entity: ``flann_cond_top``'s ``out_ratio`` feeds ``flann_top``'s ``in_data``
through the bits the FLANN's manifest names (``adc_bits`` -> ``input_bits``), and the
calibrated reference (``reference``: ``in_offset``, ``in_tan``) is a constant of the board.
"""

from __future__ import annotations

from ...errors import FlannError
from ...golden.model import load_model
from ..adc import plan_adc
from ..datapath import Datapath, _int
from ..fixed import datapath as fixed_datapath
from ..fixed import render as fixed_render
from ..header import NO_MODEL
from ..manifest import write_design
from ..options import GenOptions
from .render import ENTITIES, TOP, cycles_per_sample, render
from .settings import flann_options, of_model
from .spec import ConditionerSpec
from .twin import ConditionerChain
from ... import __version__

NAME = "conditioner"
FLANN = "flann"   # the manifest field holding the FLANN design's own manifest
LACKS = ("written from a spec, or beside a FLANN not joined to it, it has the conditioner's benches and the "
         "FLANN's (flann sim) and synthesis (flann synth) only")


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


def generate(model, out_dir, options: GenOptions | None = None, **_extra) -> dict:
    """The conditioner at the settings of ``model`` (trained from waveforms) and its FLANN, one
    directory; returns the manifest."""
    m = load_model(model)
    settings = of_model(m, str(model))
    if settings is None:
        raise FlannError(f"{model}: trained from demodulated readings, it has no conditioner: generate it "
                         "with flann gen --format fixed (train from a waveform recording for the conditioner)")
    opts = flann_options(m, options or GenOptions(), source=str(model))
    fspec = fixed_render.load(model, opts)
    ftexts = fixed_render.render(fspec)
    fman = fixed_render.manifest(fspec, list(ftexts), plan_adc(fspec.model, opts.input_bits, opts.input_lsb_v,
                                                                opts.clamp))
    spec = settings.spec
    ctexts = render(spec)
    ref = settings.reference
    man = {**manifest(spec, 2.0 * settings.adc_range_v / (1 << spec.adc_bits)),
           "files": [*ctexts, *ftexts], "model": fixed_render.MODEL_FILE, "model_sha256": fspec.model_sha256,
           "reference": {"offset": ref.offset, "tan": ref.tan}, FLANN: fman}
    return write_design({**ctexts, **ftexts, fixed_render.MODEL_FILE: fixed_render.model_text(model)}, man, out_dir)


def summary(man: dict) -> list[str]:
    s, ref = man["spec"], man.get("reference", {})
    lines = [f"  conditioner: {s['adc_bits']}-bit converters, {s['samples_per_period']} samples a period, "
             f"{s['periods_per_output']} periods a ratio of {man['output_bits']} bits; reference in_offset "
             f"{ref.get('offset')}, in_tan {ref.get('tan')}"]
    flann = man.get(FLANN)
    if isinstance(flann, dict):
        dropped = flann["adc_bits"] - flann["input_bits"]
        lines.append(f"  FLANN ({flann['top']}) behind it, not joined: wire out_ratio({flann['adc_bits'] - 1} downto "
                     f"{dropped}) to its in_data")
        lines += fixed_datapath.summary(flann)
    return lines


DATAPATH = Datapath(
    name=NAME, top=TOP, about="LVDT conditioner: excitation NCO, ADC ports, I/Q demodulation, ratio",
    generate=generate, rebuild=rebuild, twin=ConditionerChain, estimate=lambda man: None,
    fields=(_int("spec.adc_bits", 4), _int("spec.table_bits", 2), _int("spec.sine_bits", 4),
            _int("spec.samples_per_period", 8), _int("spec.periods_per_output"), _int("spec.ratio_frac_bits")),
    model_field="", lacks=LACKS, ise=False, summary=summary,
)

__all__ = ["DATAPATH", "write_conditioner", "manifest", "latency_cycles"]
