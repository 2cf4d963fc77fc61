"""The design under verification: a generated directory (manifest + VHDL) and its bit-true twin.

``flann sim DIR`` / ``flann trace DIR`` verify exactly the files in DIR: the twin is rebuilt from
the model and the options recorded in ``DIR/manifest.json`` (the model's sha256 must match, and
the rebuilt spec must equal the manifest's), and the simulation compiles DIR's own VHDL.
``flann sim MODEL`` generates into the build directory first, as before.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..errors import FlannError
from ..golden.model import model_sha256
from ..hardware.fixed.render import MANIFEST, generate, load, manifest_options, read_manifest, rebuild_spec
from ..hardware.fixed.spec import Spec


@dataclass(frozen=True)
class Design:
    directory: Path
    manifest: dict
    model: Path
    options: dict  # derive_spec keyword arguments that rebuild the spec (and the twin)
    spec: Spec

    @property
    def files(self) -> list[Path]:
        return [self.directory / f for f in self.manifest["files"]]


def is_design_dir(path) -> bool:
    return Path(path).is_dir()


def from_model(model, build_dir, options: dict | None = None) -> Design:
    """Generate the design of ``model`` with ``options`` into ``build_dir/hdl``."""
    options = dict(options or {})
    hdl = Path(build_dir).resolve() / "hdl"
    man = generate(model, hdl, **options)
    return Design(hdl, man, Path(model).resolve(), options, load(model, **options))


def from_directory(directory, model=None) -> Design:
    """The design in ``directory`` with the twin of ``model`` (default: the manifest's 'model')."""
    directory = Path(directory).resolve()
    if not (directory / MANIFEST).is_file():
        raise FlannError(f"{directory}: no {MANIFEST} (a design directory is written by flann gen -o DIR)")
    man = read_manifest(directory)
    if man.get("spec", {}).get("number_format", "fixed") != "fixed" or man.get("top") != "flann_top":
        raise FlannError(f"{directory}: only fixed-point flann_top designs can be simulated from a directory")
    if model is None:
        model = man.get("model")
        if not model:
            raise FlannError(f"{directory / MANIFEST} does not name its model: pass --model MODEL.json")
        model = (directory / model) if not Path(model).is_absolute() else Path(model)
    model = Path(model).resolve()
    if not model.is_file():
        raise FlannError(f"{model}: model file not found")
    sha = model_sha256(model)
    if man.get("model_sha256") and sha != man["model_sha256"]:
        raise FlannError(f"{model} is not the model {directory.name} was generated from "
                         f"(sha256 {sha[:12]}... vs manifest {str(man['model_sha256'])[:12]}...)")
    for f in man.get("files", []):
        if not (directory / f).is_file():
            raise FlannError(f"{directory / MANIFEST}: listed file {f!r} does not exist")
    spec, options = rebuild_spec(model, man, f"cannot rebuild the twin of {directory}")
    return Design(directory, man, model, options, spec)


def open_design(target, build_dir, options: dict | None = None, model=None) -> Design:
    """A design directory (verified as it is) or a model file (generated with ``options``)."""
    if is_design_dir(target):
        return from_directory(target, model)
    if not Path(target).is_file():
        raise FlannError(f"{target}: no such model file or design directory")
    return from_model(target, build_dir, options)


__all__ = ["Design", "from_model", "from_directory", "open_design", "manifest_options", "is_design_dir"]
