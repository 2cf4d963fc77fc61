"""A design directory, opened once: its manifest, its datapath and (when asked) its bit-true twin.

Every command that takes a design directory (sim, synth, ise, trace, eval --design, explore,
calibrate) opens it here once, into one :class:`Design`, and hands that object on: the manifest
is read and checked field by field against the datapath it names (:mod:`flann.hardware.registry`)
once per command.  :meth:`Design.with_twin` derives the spec again from the model kept in the
directory (or ``--model``; its sha256 must match) and the options the manifest records, field for
field, without reading the directory again.  ``flann sim MODEL`` generates into the build
directory first (:func:`from_model`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ..errors import FlannError
from ..golden.model import model_sha256
from ..golden.thermal import load_any_model
from .datapath import Datapath
from .fixed.render import generate, load, manifest_options
from .manifest import MANIFEST, Manifest
from .registry import FIXED, REPEATED, check_repeated, read_design


@dataclass(frozen=True)
class Design:
    """A generated design: ``manifest`` (read and checked), ``datapath`` (the manifest names it);
    with its twin: ``model`` (the model file it was generated from), ``options`` (the keyword
    arguments that rebuild the spec) and ``spec`` (the datapath's spec); None before."""

    directory: Path
    manifest: Manifest
    model: Path | None = None
    options: dict | None = None
    spec: Any = None
    datapath: Datapath = FIXED

    @property
    def files(self) -> list[Path]:
        return list(self.manifest.files)

    @property
    def top(self) -> str:
        return self.manifest.top

    def twin(self):
        if self.spec is None:
            raise FlannError(f"{self.directory}: opened without its twin")
        return self.datapath.twin(self.spec)

    def with_twin(self, model=None) -> "Design":
        """This design with its spec rebuilt from its model (``model``, else the one it keeps)."""
        if self.spec is not None and model is None:
            return self
        dp, man = self.datapath, self.manifest
        where = f"cannot rebuild the twin of {self.directory}"
        if not dp.model_field:
            # a datapath written from a spec: its manifest alone rebuilds it (or says why not)
            spec, options = dp.rebuild(None, man, where)
            return replace(self, options=options, spec=spec)
        model = design_model(self.directory, man, dp, model)
        spec, options = dp.rebuild(model, man, where)
        _check_top_level(man, spec, self.directory / MANIFEST)
        return replace(self, model=model, options=options, spec=spec)


def open_directory(directory) -> Design:
    """The design in ``directory``: its manifest read and checked against its datapath, once."""
    directory = Path(directory).resolve()
    man, dp = read_design(directory)
    return Design(directory, man, datapath=dp)


def as_design(source) -> Design:
    """``source`` as a :class:`Design`: itself, or the directory it names opened."""
    return source if isinstance(source, Design) else open_directory(source)


def is_design_dir(path) -> bool:
    return Path(path).is_dir()


def from_model(model, build_dir, options: dict | None = None) -> Design:
    """Generate the fixed-point design of ``model`` with ``options`` into ``build_dir/hdl``."""
    try:
        conditioned = getattr(load_any_model(model), "conditioner", None) is not None
    except FlannError:
        conditioned = False   # the generator names what is wrong with the file
    if conditioned:
        raise FlannError(f"{model}: trained from waveforms, its design holds the conditioner too: "
                         f"flann gen {model} -o DIR, then flann sim DIR")
    options = dict(options or {})
    hdl = Path(build_dir).resolve() / "hdl"
    man = generate(model, hdl, **options)
    return Design(hdl, Manifest.written(hdl, man), Path(model).resolve(), options, load(model, **options))


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
    if not (Path(directory) / MANIFEST).is_file():
        raise FlannError(f"{Path(directory).resolve()}: no {MANIFEST} (a design directory is written by flann gen "
                         "-o DIR)")
    return open_directory(directory).with_twin(model)


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


__all__ = ["Design", "from_model", "from_directory", "open_directory", "as_design", "open_design",
           "manifest_options", "is_design_dir", "design_model"]
