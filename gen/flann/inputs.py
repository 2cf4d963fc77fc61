"""The input layer for structured files (model.json, sensor TOML, manifests): read once,
numbers bounded before anything uses them.

A hostile or damaged file must end as one :class:`~flann.errors.FlannError` line, never as
a RecursionError, an OverflowError or a 4,300-digit ValueError deep in a command:

* nesting deeper than :data:`MAX_DEPTH` is refused (the parsers' own recursion is caught);
* integers longer than :data:`MAX_INT_DIGITS` digits or beyond 64 bits are refused before
  Python converts them;
* a float that overflows to infinity (``1e999``) and JSON's ``NaN``/``Infinity`` are refused.

Every file read here is noted as an input of the command (:func:`flann.fileio.note_input`),
so no output of the same command can overwrite it.
"""

from __future__ import annotations

import json
import math
import os
import tomllib
from pathlib import Path

from .errors import FlannError
from .fileio import note_input

MAX_DEPTH = 32           # the deepest file flann writes nests 4 levels
MAX_INT_DIGITS = 19      # 64-bit integers
MAX_TEXT_BYTES = 64 << 20  # a model, sensor or manifest is a few kB


def input_error(path, exc: OSError, error: type[FlannError], what: str) -> FlannError:
    """One ``error`` line for an input that cannot be opened or read."""
    if isinstance(exc, FileNotFoundError):
        return error(f"{path}: no such file")
    if isinstance(exc, IsADirectoryError):
        return error(f"{path}: is a directory, expected {what}")
    return error(f"{path}: cannot read ({exc.strerror or exc.__class__.__name__})")


def read_bytes(path: str | os.PathLike, error: type[FlannError], what: str, limit: int | None = None) -> bytes:
    """The bytes of an input file (noted as an input of the running command), or one
    ``error`` line: missing, a directory, unreadable, or more than ``limit`` bytes."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read() if limit is None else fh.read(limit + 1)
    except OSError as exc:
        raise input_error(path, exc, error, what) from None
    if limit is not None and len(raw) > limit:
        raise error(f"{path}: larger than {limit >> 20} MB, not {what}")
    note_input(path)
    return raw


def read_text(path: str | os.PathLike, error: type[FlannError], what: str) -> str:
    """UTF-8 text of an input file, or one ``error`` line (missing, a directory, too large,
    not text)."""
    raw = read_bytes(path, error, what, MAX_TEXT_BYTES)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        raise error(f"{path}: not UTF-8 text, expected {what}") from None


class _Refused(Exception):
    pass


def _int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_INT_DIGITS:
        raise _Refused(f"integer of {len(text.lstrip('-'))} digits (at most {MAX_INT_DIGITS})")
    return int(text)


def _float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise _Refused(f"number {text[:40]} is not finite (overflows a double)")
    return value


def _constant(text: str):
    raise _Refused(f"{text} is not a number flann accepts")


def _check(obj, depth: int = 0) -> None:
    """Depth and number bounds over a parsed document (TOML has no integer hook)."""
    if depth > MAX_DEPTH:
        raise _Refused(f"nested deeper than {MAX_DEPTH} levels")
    if isinstance(obj, dict):
        for v in obj.values():
            _check(v, depth + 1)
    elif isinstance(obj, list):
        for v in obj:
            _check(v, depth + 1)
    elif isinstance(obj, bool):
        return
    elif isinstance(obj, int):
        if not -(1 << 63) <= obj < (1 << 63):
            raise _Refused(f"integer {str(obj)[:20]}... beyond 64 bits")
    elif isinstance(obj, float) and not math.isfinite(obj):
        raise _Refused(f"number {obj} is not finite")


def parse_json(text: str, source: str, error: type[FlannError]):
    """A JSON document with bounded numbers and depth, or one ``error`` line."""
    try:
        doc = json.loads(text, parse_int=_int, parse_float=_float, parse_constant=_constant)
        _check(doc)
    except json.JSONDecodeError as exc:
        raise error(f"{source}: not valid JSON ({exc.msg}, line {exc.lineno})") from None
    except _Refused as exc:
        raise error(f"{source}: {exc}") from None
    except RecursionError:
        raise error(f"{source}: nested deeper than {MAX_DEPTH} levels") from None
    return doc


def parse_toml(text: str, source: str, error: type[FlannError]):
    """A TOML document with bounded numbers and depth, or one ``error`` line."""
    try:
        doc = tomllib.loads(text, parse_float=_float)
        _check(doc)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{source}: not valid TOML ({exc})") from None
    except _Refused as exc:
        raise error(f"{source}: {exc}") from None
    except RecursionError:
        raise error(f"{source}: nested deeper than {MAX_DEPTH} levels") from None
    except ValueError as exc:   # Python's limit on integer digits (4,300), inside tomllib
        raise error(f"{source}: a number too large to read ({exc.__class__.__name__})") from None
    return doc


def number(value, label: str, source: str, error: type[FlannError], *, integer: bool = False,
           lo: float = -1e12, hi: float = 1e12, tiny: float = 0.0):
    """A JSON/TOML value as a bounded number: a bool or string is not a number, an integer
    field takes no fraction, ``lo <= value <= hi`` and a non-zero ``|value| >= tiny``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise error(f"{source}: {label} must be a number, got {_show(value)}")
    if integer and not (isinstance(value, int) or float(value).is_integer()):
        raise error(f"{source}: {label} must be an integer, got {value!r}")
    if not math.isfinite(value) or not lo <= value <= hi:
        raise error(f"{source}: {label} = {value!r} out of range [{lo:g}, {hi:g}]")
    if value != 0 and abs(value) < tiny:
        raise error(f"{source}: {label} = {value!r} is too small (|value| >= {tiny:g} or 0)")
    return int(value) if integer else float(value)


def _show(value) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


__all__ = ["MAX_DEPTH", "MAX_INT_DIGITS", "read_bytes", "read_text", "parse_json", "parse_toml", "number"]
