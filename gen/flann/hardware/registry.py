"""The registry of datapaths: a design's ``manifest.json`` names its datapath, this finds it.

Adding a datapath: a folder under ``hardware/`` with its spec, twin, render, templates and a
``datapath.py`` holding one :class:`~flann.hardware.datapath.Datapath`; then one line here.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import FlannError
from .datapath import Datapath
from .family.datapath import DATAPATH as FAMILY
from .fixed.datapath import DATAPATH as FIXED
from .float18.datapath import DATAPATH as FLOAT18
from .manifest import MANIFEST, Manifest, read_manifest
from .seed.datapath import DATAPATH as SEED

DATAPATHS: dict[str, Datapath] = {dp.name: dp for dp in (FIXED, FLOAT18, FAMILY, SEED)}
# what `flann gen --format` chooses among (the family is chosen by --family)
FORMATS = (FIXED.name, FLOAT18.name)


def datapath(name: str) -> Datapath:
    if name not in DATAPATHS:
        raise FlannError(f"datapath {name!r}: known ones are {', '.join(DATAPATHS)}")
    return DATAPATHS[name]


def _legacy_name(data: dict) -> str | None:
    """The datapath of a manifest written before the field existed (by its top entity)."""
    return next((dp.name for dp in DATAPATHS.values() if dp.top == data.get("top")), None)


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


__all__ = ["DATAPATHS", "FORMATS", "FIXED", "FLOAT18", "FAMILY", "SEED", "datapath", "read_design"]
