"""The values of the one header every generated VHDL file starts with (``m.header`` in
``hardware/templates/macros.j2``): file, title, generator version and command, the model's
sha256 and the spec, one ``key = json`` line per field.  No timestamps, so regenerating gives
identical bytes."""

from __future__ import annotations

import json

from .. import __version__

NO_MODEL = "(not from a file)"


def header(file: str, title: str, command: str, spec: dict, model_sha256: str = "") -> dict:
    return dict(file=file, title=title, command=command, version=__version__,
                model_sha256=model_sha256 or NO_MODEL,
                spec_lines=[f"{k} = {json.dumps(v)}" for k, v in spec.items()])


__all__ = ["header", "NO_MODEL"]
