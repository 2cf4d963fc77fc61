"""The registry of datapaths: a design's ``manifest.json`` names its datapath, this finds it.

Adding a datapath: a folder under ``hardware/`` with its spec, twin, render, templates and a
``datapath.py`` holding one :class:`~flann.hardware.datapath.Datapath`; then one line here.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import FlannError
from ..golden.thermal import is_thermal, load_any_model
from ..numeric.fixed import FixedFormat
from .adc import ADC_BITS, CHAIN_INPUT_BITS, MAX_DESIGN_INPUT_BITS
from .conditioner.datapath import DATAPATH as CONDITIONER
from .datapath import Datapath, Field, _int
from .family_thermal.build import is_thermal_family
from .family.datapath import DATAPATH as FAMILY
from .family_thermal.datapath import DATAPATH as FAMILY_THERMAL
from .fixed.datapath import DATAPATH as FIXED
from .float18.datapath import DATAPATH as FLOAT18
from .manifest import MANIFEST, Manifest, read_manifest
from .seed.datapath import DATAPATH as SEED
from .thermal.datapath import DATAPATH as THERMAL
from .thermal.spec import MAX_INPUT_BITS as THERMAL_INPUT_BITS

def _no(what: str):
    def refuse(*_args, **_kw):
        raise FlannError(f"{WHY_PLAIN}; it has no {what}")
    return refuse


WHY_PLAIN = ("a design flann did not write (its manifest names no datapath and no flann spec): "
             "synthesis and the ISE handoff take it")
# VHDL with a hand-written manifest: `top`, `files` and the port widths the ISE pin map needs
PLAIN = Datapath(
    name="plain", top="", about="VHDL with a hand-written manifest (synth and ise only)",
    generate=_no("generator"), rebuild=_no("twin"), twin=_no("twin"), estimate=lambda man: None,
    common=(Field("top", (str,)), Field("files", (list,)), _int("input_bits", 2), _int("output_bits", 2),
            Field("spec", (dict,), optional=True)),
    model_field="", lacks=WHY_PLAIN,
)
DATAPATHS: dict[str, Datapath] = {dp.name: dp for dp in (FIXED, FLOAT18, FAMILY, FAMILY_THERMAL, SEED, THERMAL, CONDITIONER, PLAIN)}
# what `flann gen --format` chooses among (the family is chosen by --family)
FORMATS = (FIXED.name, FLOAT18.name)


def datapath(name: str) -> Datapath:
    if name not in DATAPATHS:
        raise FlannError(f"datapath {name!r}: known ones are {', '.join(DATAPATHS)}")
    return DATAPATHS[name]


def family_datapath(sources) -> Datapath:
    """The datapath ``flann gen --family SOURCES`` builds: with temperature when a member is a
    two-input model or a recording at several temperatures."""
    return FAMILY_THERMAL if is_thermal_family(sources) else FAMILY


def datapath_for_model(model, format_name: str) -> Datapath:
    """The datapath ``flann gen MODEL --format F`` builds: a two-input model has its own (the
    model file says which it is), a model trained from waveforms the conditioner's; a one-input
    model the format's."""
    try:
        loaded = load_any_model(model)
        two_inputs = is_thermal(loaded)
    except FlannError:
        loaded, two_inputs = None, False  # the format's datapath names what is wrong with the file
    if getattr(loaded, "conditioner", None) is not None:
        # trained from waveforms: the conditioner at its settings and the FLANN behind it
        if format_name != FIXED.name:
            raise FlannError(f"--format {format_name}: a model trained from waveforms is generated with its "
                             f"conditioner in fixed point only (--format {FIXED.name})")
        return CONDITIONER
    if not two_inputs:
        return datapath(format_name)
    if format_name != THERMAL.number_format:
        raise FlannError(f"--format {format_name}: a two-input model is generated in fixed point only "
                         f"(--format {THERMAL.number_format})")
    return THERMAL


def _legacy_name(data: dict) -> str:
    """The datapath of a manifest written before the field existed: what its spec says it is
    (a family has its ``family`` entry), else a design flann did not write."""
    spec = data.get("spec") if isinstance(data.get("spec"), dict) else {}
    if "family" in data:
        return FAMILY.name
    if data.get("number_format") == FLOAT18.name:
        return FLOAT18.name
    if spec.get("number_format") == FIXED.name:
        return FIXED.name
    if spec.get("architecture") == "seed_parallel":
        return SEED.name
    return PLAIN.name


def read_design(directory) -> tuple[Manifest, Datapath]:
    """manifest.json of ``directory``, checked field by field against its datapath's key set."""
    man = read_manifest(directory)
    where = Path(directory) / MANIFEST
    name = man.get("datapath", _legacy_name(man))
    if not isinstance(name, str) or name not in DATAPATHS:
        raise FlannError(f"{where}: field 'datapath' must name one of {', '.join(DATAPATHS)}, got {name!r}")
    if "datapath" not in man:
        man["datapath"] = name
    dp = DATAPATHS[name]
    dp.check(man, where)
    if dp is not PLAIN:
        check_widths(man, where)
    return man, dp


# input widths flann gen builds: the one-input datapaths take 16 bits at most, the two-input
# one more (its grid coarser than the code); the rebuild holds each datapath to its own
INPUT_BITS = (ADC_BITS[0], max(MAX_DESIGN_INPUT_BITS, THERMAL_INPUT_BITS, CHAIN_INPUT_BITS))
# what a manifest repeats at its top level of what its spec records: the benches, the netlist
# sweeps and the ISE pin map read the top level, the rebuilt twin the spec
REPEATED = ("input_bits", "input_lsb_v", "output_bits", "output_lsb_mm", "temp_bits", "temp_lsb_c")


def _spec_states(spec: dict) -> dict:
    """The values of REPEATED that ``spec`` records, wherever its datapath keeps them (a key of its
    own, the width of its ``output`` format, its ``temperature`` object)."""
    said = {k: spec[k] for k in REPEATED if k in spec}
    out = spec.get("output")
    if "output_bits" not in said and isinstance(out, dict) and "width" in out:
        said["output_bits"] = out["width"]
    elif "output_bits" not in said and isinstance(out, str):
        try:
            said["output_bits"] = FixedFormat.parse(out).width
        except (FlannError, ValueError):
            pass  # the datapath's rebuild names a malformed format
    temp = spec.get("temperature")
    if isinstance(temp, dict):
        for key, tkey in (("temp_bits", "bits"), ("temp_lsb_c", "lsb_c")):
            if key not in said and tkey in temp:
                said[key] = temp[tkey]
    return said


def check_widths(man: dict, where) -> None:
    """A flann design's input width within what the generator builds, and its top-level widths
    and LSBs equal to its spec's: every code of a 64-bit input would be swept for ever, and a
    top level disagreeing with the spec the twin is rebuilt from tests another design."""
    lo, hi = INPUT_BITS
    bits = man["input_bits"]
    if not lo <= bits <= hi:
        raise FlannError(f"{where}: field 'input_bits' is {bits}, flann gen builds {lo}..{hi}-bit inputs "
                         "(regenerate the design with flann gen --input-bits)")
    adc = man.get("adc_bits")
    if adc is not None and (isinstance(adc, bool) or not isinstance(adc, int) or not ADC_BITS[0] <= adc <= ADC_BITS[1]):
        raise FlannError(f"{where}: field 'adc_bits' must be an integer in {ADC_BITS[0]}..{ADC_BITS[1]}, got {adc!r}")
    check_repeated(man, _spec_states(man["spec"]), where)


def check_repeated(man: dict, stated: dict, where) -> None:
    """Each of the manifest's top-level REPEATED fields equal to what the spec ``stated`` gives
    (None: the spec does not say)."""
    for key, value in stated.items():
        if value is not None and key in man and man[key] != value:
            raise FlannError(f"{where}: field {key!r} is {man[key]!r} but the spec says {value!r}: "
                             "the manifest was edited; regenerate the design with flann gen")


__all__ = ["DATAPATHS", "FORMATS", "PLAIN", "FIXED", "FLOAT18", "FAMILY", "FAMILY_THERMAL", "SEED", "THERMAL", "datapath", "datapath_for_model", "read_design",
           "REPEATED", "check_repeated", "check_widths"]
