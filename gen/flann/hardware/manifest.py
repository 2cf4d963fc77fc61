"""The design manifest: ``manifest.json`` beside the generated VHDL, written and read here only.

Every datapath writes its files and its manifest through :func:`write_design` (atomically,
so a failed generation leaves nothing); every consumer (simulation, synthesis, ISE export)
reads it through :func:`read_manifest`, which checks the two fields all of them rely on:
``top`` (the top entity) and ``files`` (VHDL files in compile order, present in the directory).
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

from ..errors import FlannError
from ..fileio import atomic_directory
from ..inputs import parse_json, read_text

MANIFEST = "manifest.json"


def flat_port(direction: str, width: int = 0) -> dict:
    """A port a datapath adds to the common interface, as its manifest lists it under
    ``cfg_port.ports``: ``direction`` "in" or "out", ``width`` bits (0: a std_logic)."""
    return {"direction": direction, "width": int(width)}


class Manifest(dict):
    """manifest.json as a dict, plus where it was read: ``directory``, ``top`` and ``files``
    (paths of the VHDL files in compile order)."""

    def __init__(self, directory: Path, top: str, files: tuple[Path, ...], data: dict):
        super().__init__(data)
        self.directory, self.top, self.files = directory, top, files

    @property
    def data(self) -> dict:
        return dict(self)

    @classmethod
    def written(cls, directory, data: dict) -> "Manifest":
        """The manifest a generator just wrote into ``directory`` (not read again)."""
        directory = Path(directory).resolve()
        return cls(directory, data["top"], tuple(directory / f for f in data["files"]), data)


def is_design(directory: Path) -> bool:
    """A directory flann wrote a design into (so it may be replaced as a whole)."""
    return (Path(directory) / MANIFEST).is_file()


def refuse_design_directory(path, flag: str) -> None:
    """A build or work directory (``--build``, ``--work``) must not be a design directory or lie
    inside one: its build files would make the design one that ``flann gen`` no longer replaces."""
    if path is None:
        return
    p = Path(os.path.abspath(path))
    for d in (p, *p.parents):
        if is_design(d):
            where = "is" if d == p else f"lies inside {d},"
            raise FlannError(f"{flag} {path}: {where} a flann design directory; build files go beside the "
                             "design, not into it (give another directory)")


def foreign_entries(directory: Path) -> list[str]:
    """What a design directory holds beyond what flann gen wrote into it (its manifest's files,
    model and weight images): a user's notes, calibrate's certificates.  Replacing the design
    would delete them.  An unreadable manifest owns nothing but itself."""
    directory = Path(directory)
    try:
        man = parse_json(read_text(directory / MANIFEST, FlannError, "manifest.json"), MANIFEST, FlannError)
    except FlannError:
        man = {}
    man = man if isinstance(man, dict) else {}
    own = {MANIFEST, man.get("model"), man.get("init_model"), man.get("waveform")}
    own |= set(f for f in man.get("files", []) if isinstance(f, str))
    own |= {im.get(k) for im in man.get("images", []) if isinstance(im, dict) for k in ("hex", "model")}
    return sorted(p.name + ("/" if p.is_dir() else "") for p in directory.iterdir() if p.name not in own)


def _replaceable(directory: Path) -> bool:
    """A design flann gen wrote and nothing else (:func:`foreign_entries` is refused in one line)."""
    if not is_design(directory):
        return False
    if extra := foreign_entries(directory):
        shown = ", ".join(extra[:3]) + (f" and {len(extra) - 3} more" if len(extra) > 3 else "")
        raise FlannError(f"{directory}: a flann design that also holds what flann gen did not write ({shown}); "
                         "replacing it would delete them: move them or choose another directory")
    return True


def write_design(texts: dict[str, str], man: dict, out_dir) -> dict:
    """Write rendered files and manifest.json into ``out_dir`` atomically; return the manifest."""
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise FlannError(f"{out_dir}: exists and is not a directory")
    with atomic_directory(out_dir, _replaceable, "flann design") as tmp:
        for name, text in texts.items():
            (tmp / name).write_text(text, newline="")
        (tmp / MANIFEST).write_text(json.dumps(man, indent=2) + "\n", newline="")
    return man


def read_manifest(directory) -> Manifest:
    directory = Path(directory)
    path = directory / MANIFEST
    if not path.is_file():
        raise FlannError(f"{path} not found: generate the design first (flann gen MODEL -o {directory})")
    data = parse_json(read_text(path, FlannError, "a design's manifest.json"), str(path), FlannError)
    if not isinstance(data, dict):
        raise FlannError(f"{path}: expected a JSON object with 'top' and 'files'")
    top, files = data.get("top"), data.get("files")
    if not isinstance(top, str) or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", top):
        raise FlannError(f"{path}: field 'top' must name the top entity (a VHDL identifier), got {top!r}")
    if not isinstance(files, list) or not files or not all(isinstance(f, str) for f in files):
        raise FlannError(f"{path}: field 'files' must be a non-empty list of VHDL files in compile order")
    paths = []
    for f in files:
        paths.append(_listed_file(path, directory, f, "vhd", "listed file"))
        if paths.count(paths[-1]) > 1:
            raise FlannError(f"{path}: field 'files' lists {f!r} twice")
    _kept_files(path, directory, data)
    _top_declared(path, top, paths)
    _clamp_codes(path, data)
    return Manifest(directory, top, tuple(paths), data)


def _top_declared(path: Path, top: str, files) -> None:
    """The top entity must be declared in a listed file: a harness instantiates it as a
    component, and an unbound component simulates without an error and never answers."""
    pattern = re.compile(rf"^\s*entity\s+{re.escape(top)}\s+is\b", re.I | re.M)
    if not any(pattern.search(f.read_text(errors="replace")) for f in files):
        raise FlannError(f"{path}: top entity {top!r} is declared in none of the files it lists "
                         "(renamed by hand?): regenerate the design with flann gen")


def _clamp_codes(path: Path, data: dict) -> None:
    """``clamp_codes``: the lowest and highest input code the design uses, as its spec says."""
    if "clamp_codes" not in data:
        return
    c = data["clamp_codes"]
    if (not isinstance(c, list) or len(c) != 2 or not all(isinstance(x, int) and not isinstance(x, bool) for x in c)
            or c[0] > c[1]):
        raise FlannError(f"{path}: field 'clamp_codes' must be [lowest, highest] input code, got {c!r}")
    spec = data.get("spec")
    if isinstance(spec, dict) and "clamp_codes" in spec and spec["clamp_codes"] != c:
        raise FlannError(f"{path}: field 'clamp_codes' {c} differs from the design's spec "
                         f"{spec['clamp_codes']!r}: regenerate the design with flann gen")


# VHDL names go to GHDL and ISE command lines; a kept model or image is named after the user's
# recording (any characters but a directory separator)
_NAMES = {"vhd": re.compile(r"[A-Za-z0-9_][A-Za-z0-9._+-]*\.vhd"),
          "json": re.compile(r"(?!\.\.?$)[^/\\\x00]+\.json"),
          "hex": re.compile(r"(?!\.\.?$)[^/\\\x00]+\.hex"),
          "csv": re.compile(r"(?!\.\.?$)[^/\\\x00]+\.csv")}


def _listed_file(path: Path, directory: Path, name: str, suffix: str, what: str, must_exist: bool = True) -> Path:
    """``directory/name`` for a file the manifest names: a plain ``*.<suffix>`` name of a regular
    file in the directory.  Consumers hand these to GHDL, cocotb, ISE or a JSON/hex reader, so a
    path out of the directory ('../x.csv', '/etc/passwd', a symlink leading out) or another kind
    of file is refused here."""
    if not _NAMES[suffix].fullmatch(name):
        raise FlannError(f"{path}: {what} {name!r} is not a plain *.{suffix} file name in {directory} "
                         "(no directory part, no '..')")
    p = directory / name
    if not p.is_file():
        absent = not p.exists() and not p.is_symlink()   # a dangling link is there, and refused
        if absent and not must_exist:
            return p
        raise FlannError(f"{path}: {what} {name!r} " + ("does not exist in " + str(directory) if not p.exists()
                                                          else "is not a regular file"))
    if Path(os.path.realpath(p)).parent != Path(os.path.realpath(directory)):
        raise FlannError(f"{path}: {what} {name!r} leads out of {directory} (a symbolic link)")
    return p


def _kept_files(path: Path, directory: Path, data: dict) -> None:
    """The model, weight images and waveform recording a design keeps beside its VHDL, confined
    like its files (a missing one is the reader's to report: a design may be checked in without
    its model)."""
    for key in ("model", "init_model"):
        model = data.get(key)
        if model is not None:
            if not isinstance(model, str):
                raise FlannError(f"{path}: field {key!r} must be a file name, got {model!r}")
            _listed_file(path, directory, model, "json", "kept model" if key == "model" else "initial model",
                         must_exist=False)
    waveform = data.get("waveform")
    if waveform is not None:
        if not isinstance(waveform, str):
            raise FlannError(f"{path}: field 'waveform' must be a file name, got {waveform!r}")
        _listed_file(path, directory, waveform, "csv", "kept waveform recording", must_exist=False)
    images = data.get("images")
    if images is None:
        return
    if not isinstance(images, list) or not all(isinstance(im, dict) and isinstance(im.get("name"), str)
                                                and isinstance(im.get("hex"), str) for im in images):
        raise FlannError(f"{path}: field 'images' must be a list of {{\"name\", \"hex\"}} objects")
    for im in images:
        _listed_file(path, directory, im["hex"], "hex", "kept weight image")
        if im.get("model") is not None:
            if not isinstance(im["model"], str):
                raise FlannError(f"{path}: field 'images[].model' must be a file name, got {im['model']!r}")
            _listed_file(path, directory, im["model"], "json", f"model of image {im['name']!r}", must_exist=False)


__all__ = ["MANIFEST", "Manifest", "is_design", "refuse_design_directory", "read_manifest", "write_design"]
