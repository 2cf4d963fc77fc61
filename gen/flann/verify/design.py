"""The design under verification: a generated directory (manifest + VHDL + model) and its bit-true twin.

``flann sim DIR`` / ``flann trace DIR`` / ``flann eval --design DIR`` verify exactly the files in
DIR, whatever its datapath: the manifest names the datapath (:mod:`flann.hardware.registry`),
whose ``rebuild`` derives the spec again from the model kept in DIR (or ``--model``; its sha256
must match) and the options the manifest records, field for field.  ``flann sim MODEL``
generates into the build directory first, as before.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..errors import FlannError
from ..golden.model import model_sha256
from ..hardware.datapath import Datapath
from ..hardware.fixed.render import generate, load, manifest_options
from ..hardware.manifest import MANIFEST
from ..hardware.registry import FIXED, REPEATED, check_repeated, read_design


@dataclass(frozen=True)
class Design:
    directory: Path
    manifest: dict
    model: Path
    options: dict  # keyword arguments that rebuild the spec (and the twin)
    spec: object   # the datapath's spec (fixed Spec, F18Spec, FamilySpec)
    datapath: Datapath = FIXED

    @property
    def files(self) -> list[Path]:
        return [self.directory / f for f in self.manifest["files"]]

    def twin(self):
        return self.datapath.twin(self.spec)


def is_design_dir(path) -> bool:
    return Path(path).is_dir()


def from_model(model, build_dir, options: dict | None = None) -> Design:
    """Generate the fixed-point design of ``model`` with ``options`` into ``build_dir/hdl``."""
    options = dict(options or {})
    hdl = Path(build_dir).resolve() / "hdl"
    man = generate(model, hdl, **options)
    return Design(hdl, man, Path(model).resolve(), options, load(model, **options))


def design_model(directory, man: dict, dp: Datapath, model=None) -> Path:
    """The model a design was generated from: ``model``, else the one kept in the directory."""
    directory = Path(directory)
    if model is None:
        model = dp.model_path(directory, man)
        if model is None:
            raise FlannError(f"{directory / MANIFEST} does not name its model: pass --model MODEL.json "
                             "(or regenerate the design: flann gen keeps the model in the directory)")
    model = Path(model).resolve()
    if not model.is_file():
        raise FlannError(f"{model}: model file not found")
    sha = model_sha256(model)
    if man.get("model_sha256") and sha != man["model_sha256"]:
        raise FlannError(f"{model} is not the model {directory.name} was generated from "
                         f"(sha256 {sha[:12]}... vs manifest {str(man['model_sha256'])[:12]}...)")
    return model


def from_directory(directory, model=None) -> Design:
    """The design in ``directory`` with its twin, rebuilt through the manifest's datapath."""
    directory = Path(directory).resolve()
    if not (directory / MANIFEST).is_file():
        raise FlannError(f"{directory}: no {MANIFEST} (a design directory is written by flann gen -o DIR)")
    man, dp = read_design(directory)
    where = f"cannot rebuild the twin of {directory}"
    if not dp.model_field:
        dp.rebuild(None, man, where)  # says why this datapath has no twin rebuilt from a directory
    model = design_model(directory, man, dp, model)
    spec, options = dp.rebuild(model, man, where)
    _check_top_level(man, spec, directory / MANIFEST)
    return Design(directory, man, model, options, spec, dp)


def _check_top_level(man: dict, spec, where) -> None:
    """The manifest's top-level widths and LSBs (the benches and plots read them) equal to the
    rebuilt spec's, for what a spec records outside its manifest object (read_design compares
    the rest)."""
    rebuilt = {key: getattr(spec, key, None) for key in REPEATED if key != "output_bits"}
    rebuilt["output_bits"] = getattr(getattr(spec, "out_fmt", None), "width", None)
    check_repeated(man, rebuilt, where)


def open_design(target, build_dir, options: dict | None = None, model=None) -> Design:
    """A design directory (verified as it is) or a model file (generated with ``options``)."""
    if is_design_dir(target):
        return from_directory(target, model)
    if not Path(target).is_file():
        raise FlannError(f"{target}: no such model file or design directory")
    return from_model(target, build_dir, options)


__all__ = ["Design", "from_model", "from_directory", "open_design", "manifest_options", "is_design_dir",
           "design_model"]
