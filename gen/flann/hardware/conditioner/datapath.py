"""The LVDT conditioner as a datapath: its record, the design directory it writes, its hooks.

``write_conditioner(spec, out_dir)`` writes the VHDL of every entity and a ``manifest.json``
with the common fields (``input_bits`` the converters', ``output_bits`` the ratio's,
``cycles_per_sample`` the fewest clocks between converter strobes, ``latency_cycles`` from a
window's last strobe to its ratio) and the spec.

``flann gen MODEL`` of a model trained from waveforms (its ``conditioner`` settings) writes the
same directory at the model's settings together with the FLANN's fixed-point design (its
entities, the model, and its own manifest under the field ``flann``), which takes the ratio
code as its converter, and the two joined in one top entity, ``flann_chain_top``
(:mod:`.chain`): converter codes in, displacement code out.  The top-level fields then describe
the chain (``output_bits`` the FLANN's, ``latency_cycles`` from a window's last strobe to its
displacement code), ``chain`` records how the two are joined, and the calibrated reference
(``reference``: ``in_offset``, ``in_tan``) is a constant of the board.  The recording the model
was trained from, when it lies beside the model (or in the working directory) with the sha256
the model records, is kept as ``waveform`` for ``flann sim``'s whole-chain run.
"""

from __future__ import annotations

import hashlib
import warnings
from pathlib import Path

from ...errors import FlannError
from ...golden.model import model_sha256
from ...golden.thermal import ThermalModel, load_any_model
from ..adc import plan_adc
from ..datapath import Datapath, _int
from ..fixed import datapath as fixed_datapath
from ..fixed import render as fixed_render
from ..header import NO_MODEL
from ..manifest import write_design
from ..options import GenOptions
from ..thermal import datapath as thermal_datapath
from ..thermal import render as thermal_render
from ..thermal.widths import widths_warning
from .chain import CHAIN_TOP, ChainSpec, render_chain
from .condition import adc_lsb_v
from .render import ENTITIES, TOP, cycles_per_sample, render
from .settings import flann_options, of_model
from .spec import ConditionerSpec
from .twin import ConditionerChain
from ... import __version__

NAME = "conditioner"
FLANN = "flann"   # the manifest field holding the FLANN design's own manifest
WAVEFORM = "waveform.csv"   # the training recording, kept for flann sim's whole-chain run
LACKS = ("written from a spec, or joined to its FLANN, it has the conditioner's benches and the FLANN's (flann sim) "
         "and synthesis (flann synth) only")


def latency_cycles(spec: ConditionerSpec) -> int:
    return ConditionerChain(spec).latency


def manifest(spec: ConditionerSpec, input_lsb_v: float) -> dict:
    return {"top": TOP, "files": [f"{e.name}.vhd" for e in ENTITIES], "datapath": NAME,
            "input_bits": spec.adc_bits, "input_lsb_v": input_lsb_v, "output_bits": spec.ratio_bits,
            "latency_cycles": latency_cycles(spec), "cycles_per_sample": cycles_per_sample(spec),
            "generator_version": __version__, "model_sha256": NO_MODEL, "spec": spec.to_dict()}


def write_conditioner(spec: ConditionerSpec, out_dir, adc_range_v: float) -> dict:
    """Write the conditioner's design directory; returns its manifest."""
    return write_design(render(spec), manifest(spec, adc_lsb_v(spec.adc_bits, adc_range_v)), out_dir)


def rebuild(model, man: dict, where="design"):
    """The spec a manifest records, checked by deriving its dependent widths again."""
    try:
        spec = ConditionerSpec(**man["spec"])
    except TypeError as exc:
        raise FlannError(f"{where}: the manifest's spec is not a conditioner's ({exc})") from None
    chain = man.get("chain")
    if (man.get("top") == CHAIN_TOP) != isinstance(chain, dict) or (chain is not None and FLANN not in man):
        raise FlannError(f"{where}: top {man.get('top')!r} with{'' if chain is not None else 'out'} a 'chain' field "
                         f"(the conditioner joined to its FLANN has top {CHAIN_TOP!r}, a chain and a {FLANN!r} "
                         "field): regenerate the design")
    out_bits = chain.get("flann_output_bits") if isinstance(chain, dict) else spec.ratio_bits
    if man.get("output_bits") != out_bits or man.get("input_bits") != spec.adc_bits or \
            (isinstance(chain, dict) and chain.get("conditioner") != spec.to_dict()):
        raise FlannError(f"{where}: input_bits/output_bits differ from its spec: regenerate the design")
    return spec, spec.to_dict()


def training_waveform(model_path, m) -> str | None:
    """The recording ``m`` was trained from, found beside the model file or in the working
    directory under the name the model records, with the sha256 it records; None elsewhere."""
    training = m.training if isinstance(m.training, dict) else {}
    name, sha = training.get("data_file"), training.get("data_sha256")
    if not isinstance(name, str) or not isinstance(sha, str) or Path(name).name != name:
        return None
    for place in (Path(model_path).resolve().parent, Path.cwd()):
        path = place / name
        if path.is_file():
            data = path.read_bytes()
            if hashlib.sha256(data).hexdigest() == sha:
                try:
                    return data.decode("utf-8")
                except UnicodeDecodeError:
                    return None   # kept as text, byte for byte: a recording in another encoding is not
    return None


def flann_datapath(fman: dict) -> Datapath:
    """The datapath of the FLANN behind a conditioner, by its manifest: the two-input one, or the
    fixed one."""
    return thermal_datapath.DATAPATH if fman.get("datapath") == thermal_datapath.DATAPATH.name else \
        fixed_datapath.DATAPATH


def _flann(model, m, opts: GenOptions):
    """(spec, {file: VHDL}, manifest, model sha256) of the FLANN behind the conditioner: the
    fixed datapath for a one-input model, the two-input one (its temperature port) for a model
    trained at several temperatures."""
    if isinstance(m, ThermalModel):
        tspec = thermal_render.derive(m, opts)
        lost = widths_warning(tspec)
        if lost:
            warnings.warn(lost)   # said before the design is written
        sha = model_sha256(model)
        texts = thermal_render.render(tspec, sha)
        return tspec, texts, thermal_render.manifest(tspec, list(texts), sha), sha
    fspec = fixed_render.load(model, opts)
    texts = fixed_render.render(fspec)
    plan = plan_adc(fspec.model, opts.input_bits, opts.input_lsb_v, opts.clamp)
    return fspec, texts, fixed_render.manifest(fspec, list(texts), plan), fspec.model_sha256


def generate(model, out_dir, options: GenOptions | None = None, **_extra) -> dict:
    """The conditioner at the settings of ``model`` (trained from waveforms), its FLANN and the
    chain joining them, one directory; returns the manifest."""
    m = load_any_model(model)
    settings = of_model(m, str(model))
    if settings is None:
        raise FlannError(f"{model}: trained from demodulated readings, it has no conditioner: generate it "
                         "with flann gen --format fixed (train from a waveform recording for the conditioner)")
    opts = flann_options(m, options or GenOptions(), source=str(model))
    fspec, ftexts, fman, sha = _flann(model, m, opts)
    spec = settings.spec
    chain = ChainSpec(spec, fspec, fman["top"])   # refuses a FLANN slower than the ratio
    ctexts, chtexts = render(spec), render_chain(chain, model_sha256=sha)
    ref = settings.reference
    texts = {**ctexts, **ftexts, **chtexts, fixed_render.MODEL_FILE: fixed_render.model_text(model)}
    man = {**manifest(spec, adc_lsb_v(spec.adc_bits, settings.adc_range_v)),
           "top": CHAIN_TOP, "files": [*ctexts, *ftexts, *chtexts], "output_bits": fspec.out_fmt.width,
           "output_lsb_mm": fspec.output_lsb_mm, "latency_cycles": chain.latency,
           "model": fixed_render.MODEL_FILE, "model_sha256": sha,
           "reference": {"offset": ref.offset, "tan": ref.tan}, "chain": chain.to_dict(), FLANN: fman}
    if chain.temp_bits:
        man["cfg_port"] = fman["cfg_port"]   # in_temp, beyond the common interface
    wave = training_waveform(model, m)
    if wave is not None:
        texts[WAVEFORM] = wave
        man["waveform"] = WAVEFORM
    return write_design(texts, man, out_dir)


def summary(man: dict) -> list[str]:
    s, ref = man["spec"], man.get("reference", {})
    lines = [f"  conditioner: {s['adc_bits']}-bit converters, {s['samples_per_period']} samples a period, "
             f"{s['periods_per_output']} periods a ratio of {s['ratio_frac_bits'] + 1} bits; reference in_offset "
             f"{ref.get('offset')}, in_tan {ref.get('tan')}"]
    flann, chain = man.get(FLANN), man.get("chain")
    if isinstance(flann, dict) and isinstance(chain, dict):
        lines.append(f"  FLANN ({flann['top']}) behind it, joined in {man['top']}: "
                     f"out_ratio({man['spec']['ratio_frac_bits']} downto {chain['dropped_ratio_bits']}) to its "
                     f"in_data; {man['output_bits']}-bit displacement code {man['latency_cycles']} clocks after a "
                     "window's last strobe")
        lines += flann_datapath(flann).summary(flann)
        lines.append("  flann sim's whole-chain run: " + (f"the training recording, kept as {man['waveform']}"
                     if man.get("waveform") else "the closed-form LVDT (the training recording was not found "
                     "beside the model under the name and sha256 it records)"))
    return lines


DATAPATH = Datapath(
    name=NAME, top=TOP, about="LVDT conditioner: excitation NCO, ADC ports, I/Q demodulation, ratio",
    generate=generate, rebuild=rebuild, twin=ConditionerChain, estimate=lambda man: None,
    fields=(_int("spec.adc_bits", 4), _int("spec.table_bits", 2), _int("spec.sine_bits", 4),
            _int("spec.samples_per_period", 8), _int("spec.periods_per_output"), _int("spec.ratio_frac_bits")),
    model_field="", lacks=LACKS, ise=False, summary=summary, other_tops=(CHAIN_TOP,),
)

__all__ = ["DATAPATH", "flann_datapath", "write_conditioner", "manifest", "latency_cycles", "training_waveform", "WAVEFORM"]
