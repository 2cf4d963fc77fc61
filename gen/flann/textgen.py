"""The one jinja2 environment for every generated text (VHDL, TCL, UCF, FuseSoC core).

Templates live beside the code that fills them (``hardware/<datapath>/templates``,
``implement/templates``) and are named by their path inside the package; they only place
text: every width, literal and name is computed in Python and passed in.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import jinja2

PACKAGE_DIR = Path(__file__).resolve().parent


@lru_cache(maxsize=1)
def environment() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(PACKAGE_DIR)),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
    )


def template(path: str) -> jinja2.Template:
    """A template by its path inside the package, e.g. ``hardware/fixed/templates/flann_top.vhd.j2``."""
    return environment().get_template(path)


__all__ = ["environment", "template", "PACKAGE_DIR"]
