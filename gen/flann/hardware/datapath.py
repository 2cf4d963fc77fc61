"""What every datapath offers, whatever its number format or architecture.

A datapath (``fixed``, ``float18``, ``family``, ``thermal``, ...: one folder each under
``hardware/``) is one :class:`Datapath` object, registered in :mod:`flann.hardware.registry`.
Its folder also holds what the later layers do with its designs: ``verify.py`` (its bench, its
netlist sweep, its fuzz check: :mod:`flann.verify.plugin`) and ``analysis.py`` (its stage model
and design space: :mod:`flann.analysis.plugin`).  Commands never
ask a datapath's name: they read a design's ``manifest.json`` (whose ``datapath`` field names
it), look the datapath up there, and call it:

* ``generate(model, out_dir, options)``: derive the spec, render the VHDL, write the design
  directory as a whole (VHDL, ``manifest.json`` and the model it came from);
* ``rebuild(model, manifest)``: the spec of a written design, derived again from its model and
  the options the manifest records, checked field for field (``from_manifest``);
* ``twin(spec)``: the bit-true top-level twin (``entity``, ``latency``, ``process``,
  ``all_codes``, ``error_vs_float``);
* ``fields``: the manifest fields this datapath's readers rely on, with their types, so
  one reader refuses a tampered manifest in one line naming the field;
* ``derive(model, **options)``: the spec of a model traced or fuzzed without a design directory;
* ``number_format``: its arithmetic, asked instead of its name (``flann gen --family`` takes the
  family's number format only);
* ``lacks``: why its designs lack what they lack; a command they cannot take says so in one line
  (:meth:`Datapath.lacking`);
* ``estimate(manifest)``: resources before synthesis (LUT4, flip-flops, block RAMs), so
  ``flann ise`` can refuse a part the design cannot fit.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..errors import FlannError
from ..golden.model import model_sha256

NUMBER = (int, float)


@dataclass(frozen=True)
class Field:
    """One manifest field: dotted path, allowed types, and the smallest value of a number."""

    path: str
    types: tuple
    minimum: float | None = None
    optional: bool = False  # older designs lack it

    def what(self) -> str:
        names = {int: "an integer", float: "a number", str: "a string", list: "a list", dict: "an object",
                 bool: "true or false"}
        return " or ".join(dict.fromkeys(names[t] for t in self.types))


def _int(path: str, minimum: int | None = 1) -> Field:
    return Field(path, (int,), minimum)


def _num(path: str, minimum: float | None = None) -> Field:
    return Field(path, NUMBER, minimum)


# the fields every design's readers use (simulation, synthesis, the ISE pin map)
COMMON_FIELDS = (
    Field("top", (str,)), Field("files", (list,)), Field("datapath", (str,)), Field("model", (str,), optional=True),
    _int("input_bits", 2), _num("input_lsb_v", 0), _int("output_bits", 2),
    _int("latency_cycles", 0), _int("cycles_per_sample"), Field("generator_version", (str,)),
    Field("spec", (dict,)),
)


def _lookup(man: dict, f: Field, where):
    """(found, value) of a dotted field; a missing required one (or a parent that is not an
    object) is one FlannError naming it."""
    value, here = man, ""
    for part in f.path.split("."):
        here = f"{here}.{part}" if here else part
        if not isinstance(value, dict):
            raise FlannError(f"{where}: field {here.rsplit('.', 1)[0]!r} must be an object, got {value!r}")
        if part not in value:
            if f.optional:
                return False, None
            raise FlannError(f"{where}: field {here!r} is missing (regenerate the design with flann gen)")
        value = value[part]
    return True, value


def check_fields(man: dict, fields, where) -> None:
    """One FlannError naming the first field of ``fields`` that is missing or of the wrong type."""
    for f in fields:
        found, value = _lookup(man, f, where)
        if not found:
            continue
        if not isinstance(value, f.types) or (isinstance(value, bool) and bool not in f.types):
            raise FlannError(f"{where}: field {f.path!r} must be {f.what()}, got {value!r}")
        if f.minimum is not None and value < f.minimum:
            raise FlannError(f"{where}: field {f.path!r} must be >= {f.minimum:g}, got {value!r}")


def rebuild_matching(man: dict, where, derive: Callable, options_of: Callable) -> tuple:
    """(spec, options) whose spec reproduces the manifest's ``spec`` field for field, trying the
    options ``options_of(clamp)`` with clamping on, then off (as generated); else one FlannError
    (``where`` names the design): another model or generator version made it."""
    last = ""
    for clamp in (True, False):
        options = options_of(clamp)
        try:
            spec = derive(options)
        except FlannError as exc:
            last = str(exc)
            continue
        got = json.loads(json.dumps(spec.to_dict()))
        if got == man["spec"]:
            return spec, options
        last = f"field(s) {', '.join(sorted(k for k, v in got.items() if man['spec'].get(k) != v))} differ"
    raise FlannError(f"{where}: the manifest's spec cannot be derived again ({last}): generated by another "
                     "version of flann; regenerate the design")


def check_design_model(model, man: dict, directory) -> None:
    """``model`` must be the model the design in ``directory`` was generated from (its sha256)."""
    sha = model_sha256(model)
    if man.get("model_sha256") != sha:
        raise FlannError(f"{directory}: generated from another model (sha256 {str(man.get('model_sha256'))[:12]}, "
                         f"{Path(model).name} is {sha[:12]}): evaluate the model the design keeps "
                         f"({Path(directory) / man.get('model', 'model.json')})")


@dataclass(frozen=True)
class Datapath:
    """One datapath: its name (the manifest's ``datapath``), its top entity and its hooks."""

    name: str
    top: str
    about: str
    generate: Callable                 # (model path, out_dir, GenOptions, **extra) -> manifest dict
    rebuild: Callable                  # (model path, manifest) -> (spec, options dict)
    twin: Callable                     # spec -> top-level twin
    estimate: Callable                 # manifest -> {"luts", "ffs", "brams"}
    fields: tuple = ()                 # manifest fields beyond COMMON_FIELDS
    model_field: str = "model"         # manifest field naming the model file in the directory
    eval_spec: Callable | None = None  # (model path, manifest, directory) -> fixed Spec of flann eval --design
    lacks: str = ""                    # why its designs lack what they lack (a bench, a stage model, ...)
    ise: bool = True                   # flann ise writes a project for it
    lint: bool = True                  # its VHDL passes VSG with the repository's vsg.yaml
    derive_options: Callable | None = None  # (GenOptions, compared) -> keyword arguments of its derive
    summary: Callable | None = None    # manifest -> lines flann gen prints
    derive: Callable | None = None     # (FlannModel, **derive options) -> spec of a model with no design directory
    number_format: str = ""            # the arithmetic of its products and sum (what flann gen --format names)
    common: tuple = COMMON_FIELDS      # the shared key set (a design flann did not write: fewer)
    other_tops: tuple = ()             # further top entities its designs may have (a top joining it to another)

    def lacking(self, directory, what: str) -> FlannError:
        """The one-line refusal of a command its designs cannot take: ``what`` they have none of."""
        why = f": {self.lacks}" if self.lacks else ""
        return FlannError(f"{directory}: a {self.name} design has no {what}{why}")

    def check(self, man: dict, where) -> None:
        check_fields(man, tuple(self.common) + tuple(self.fields), where)
        if self.top and man["top"] not in (self.top, *self.other_tops):
            raise FlannError(f"{where}: field 'top' is {man['top']!r}, the {self.name} datapath's top is "
                             + " or ".join(repr(t) for t in (self.top, *self.other_tops)))

    def model_path(self, directory: Path, man: dict) -> Path | None:
        name = man.get(self.model_field)
        return (Path(directory) / name) if isinstance(name, str) and name else None


__all__ = ["check_design_model", "rebuild_matching", "Datapath", "Field", "COMMON_FIELDS", "check_fields", "NUMBER"]
