"""Templates only place text: every width and index the VHDL declares is computed in Python
(the spec or the render context), where the error/range analysis and its checks are, and a
template writes ``{{ name }}`` or VHDL's ``{{ name - 1 }} downto 0`` for a width's msb."""

from __future__ import annotations

import re
from importlib.resources import files

import pytest

TEMPLATES = sorted(p for p in files("flann").joinpath("hardware").rglob("*.j2"))
EXPRESSION = re.compile(r"{{(.*?)}}", re.S)
ARITHMETIC = re.compile(r"[-+*/%]|\blength\b")
MSB = re.compile(r"^\s*[A-Za-z_][\w.]*\s*-\s*1\s*$")


def arithmetic(text: str) -> list[str]:
    """The expressions of a template that compute a number, the msb idiom aside."""
    return [e.strip() for e in EXPRESSION.findall(text) if ARITHMETIC.search(e) and not MSB.match(e)]


def test_the_rule_finds_arithmetic():
    assert arithmetic("x({{ a + b - 1 }} downto 0) y({{ n - 1 }} downto 0) {{ k|length - 1 }}") == \
        ["a + b - 1", "k|length - 1"]


@pytest.mark.parametrize("path", TEMPLATES, ids=lambda p: "/".join(p.parts[-3:]))
def test_templates_compute_no_widths(path):
    assert arithmetic(path.read_text()) == []
