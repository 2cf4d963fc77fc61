"""The registry of datapaths: a design's ``manifest.json`` names its datapath, this finds it.

Adding a datapath: a folder under ``hardware/`` with its spec, twin, render, templates and a
``datapath.py`` holding one :class:`~flann.hardware.datapath.Datapath`; then one line here.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import FlannError
from ..golden.thermal import is_thermal, load_any_model
from .datapath import Datapath, Field, _int
from .family_thermal.build import is_thermal_family
from .family.datapath import DATAPATH as FAMILY
from .family_thermal.datapath import DATAPATH as FAMILY_THERMAL
from .fixed.datapath import DATAPATH as FIXED
from .float18.datapath import DATAPATH as FLOAT18
from .manifest import MANIFEST, Manifest, read_manifest
from .seed.datapath import DATAPATH as SEED
from .thermal.datapath import DATAPATH as THERMAL

def _no(what: str):
    def refuse(*_args, **_kw):
        raise FlannError(f"{WHY_PLAIN} {what}")
    return refuse


WHY_PLAIN = ("a design flann did not write (its manifest names no datapath and no flann spec): "
             "synthesis and the ISE handoff take it; it has no")
# VHDL with a hand-written manifest: `top`, `files` and the port widths the ISE pin map needs
PLAIN = Datapath(
    name="plain", top="", about="VHDL with a hand-written manifest (synth and ise only)",
    generate=_no("generator"), rebuild=_no("twin"), twin=_no("twin"), estimate=lambda man: None,
    common=(Field("top", (str,)), Field("files", (list,)), _int("input_bits", 2), _int("output_bits", 2),
            Field("spec", (dict,), optional=True)),
    model_field="", why_no_bench=f"{WHY_PLAIN} bench", why_no_stages=f"{WHY_PLAIN} stage model",
    why_no_eval=f"{WHY_PLAIN} twin", why_no_explore=f"{WHY_PLAIN} model",
)
DATAPATHS: dict[str, Datapath] = {dp.name: dp for dp in (FIXED, FLOAT18, FAMILY, FAMILY_THERMAL, SEED, THERMAL, PLAIN)}
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
    model file says which it is); a one-input model the format's."""
    try:
        two_inputs = is_thermal(load_any_model(model))
    except FlannError:
        two_inputs = False  # the format's datapath names what is wrong with the file
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
    return man, dp


__all__ = ["DATAPATHS", "FORMATS", "PLAIN", "FIXED", "FLOAT18", "FAMILY", "FAMILY_THERMAL", "SEED", "THERMAL", "datapath", "datapath_for_model", "read_design"]
