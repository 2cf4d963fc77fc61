"""Flag values checked where they are parsed: one ``error:`` line naming the flag, never a
crash or a silently ignored check further on.

:class:`flann.cli._Parser` makes every ``type=float`` flag refuse NaN and infinity
(``--max-error-mm nan`` would turn a check off, ``--from-mm nan`` crash a sweep); flags
with a physical range use :func:`bounded`.
"""

from __future__ import annotations

import argparse
import math

from .errors import FlannError


def finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r}: must be a finite number")
    return value


def bounded(kind: type = float, lo: float | None = None, hi: float | None = None, *,
            lo_open: bool = False, nonzero_abs: float | None = None):
    """An argparse ``type`` for a number in ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``);
    ``nonzero_abs``: the value's magnitude at least this (and not 0)."""
    def shown(v) -> str:
        return str(int(v)) if kind is int else f"{v:g}"

    def parse(text: str):
        if kind is int:
            try:
                value = int(text)
            except ValueError:
                raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
        else:
            value = finite_float(text)
        if lo is not None and (value <= lo if lo_open else value < lo):
            raise argparse.ArgumentTypeError(f"{text}: must be {'>' if lo_open else '>='} {shown(lo)}")
        if hi is not None and value > hi:
            raise argparse.ArgumentTypeError(f"{text}: must be <= {shown(hi)}")
        if nonzero_abs is not None and abs(value) < nonzero_abs:
            raise argparse.ArgumentTypeError(f"{text}: |value| must be >= {nonzero_abs:g}")
        return value

    parse.__name__ = kind.__name__
    return parse


# a seed sim hands to the benches and, with --post-route, to nextpnr, which reads a C int
TOOL_SEED = bounded(int, 0, 2**31 - 1)


def terms_or_auto(lo: int, hi: int):
    """An argparse ``type`` for ``--terms``: ``auto`` or an integer in ``[lo, hi]`` (``hi``:
    :data:`flann.golden.model.MAX_TERMS`, passed in: this module stays free of numpy, which
    every command's start-up would load)."""
    def parse(text: str):
        if text == "auto":
            return "auto"
        try:
            n = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be an integer or 'auto', got {text!r}") from None
        if not lo <= n <= hi:
            raise argparse.ArgumentTypeError(f"must be {lo}..{hi} (the most terms flann fits and builds), got {n}")
        return n

    parse.__name__ = "terms"
    return parse


def checked(parse_value):
    """An argparse ``type`` from ``parse_value(text)``, which returns the value or raises
    :class:`~flann.errors.FlannError`: the rule stays where the value is used."""
    def parse(text: str):
        try:
            return parse_value(text)
        except FlannError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = parse_value.__name__
    return parse


def png_path(text: str) -> str:
    """An argparse ``type`` for ``--plot``: figures are written as PNG, so the name says so
    (a figure in ``out.txt`` would be found by nobody)."""
    if not text.lower().endswith(".png"):
        raise argparse.ArgumentTypeError(f"{text}: the figure is written as PNG, name it *.png")
    return text


__all__ = ["bounded", "checked", "finite_float", "png_path", "terms_or_auto"]
