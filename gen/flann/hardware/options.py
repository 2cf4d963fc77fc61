"""Generator options: every default in one frozen dataclass; argparse is built from it.

``flann gen``, ``flann sim`` and ``flann trace`` share these options; the library takes
them as keyword arguments (``derive_spec(model, lanes=2)``) or as a :class:`GenOptions`.
``None`` means "chosen by the error analysis" (see :mod:`flann.hardware.fixed.spec`).
Each field's metadata holds its command-line flag and help text, so a default is written
once and ``--help`` always shows the value the library uses.
"""

from __future__ import annotations

import argparse
from dataclasses import MISSING, asdict, dataclass, field, fields, replace

from ..errors import SpecError
from .target import DEFAULT_PART

MULT_STYLES = ("lut", "shiftadd")
TWO_INPUT = ("temp_bits", "temp_lsb_c")  # options only a two-input (temperature) model uses


def _opt(default, help: str, *, flag: str | None = None, type=None, choices=None):
    return field(default=default, metadata={"help": help, "flag": flag, "type": type, "choices": choices})


@dataclass(frozen=True)
class GenOptions:
    """What the user may choose about a generated design; ``None``: derived from the error budget."""

    device: str = _opt(DEFAULT_PART, "target part-package-speed (default %(default)s)", type=str)
    input_bits: int = _opt(12, "signed ADC code width (default %(default)s)", type=int)
    input_lsb_v: float | None = _opt(None, "volts per input code (default: trained range + 10%%)", type=float)
    temp_bits: int = _opt(12, "two-input models: signed temperature code width (default %(default)s)", type=int)
    temp_lsb_c: float = _opt(0.0625, "two-input models: degC per temperature code (default %(default)s)",
                             type=float)
    clamp: bool = _opt(True, "do not clamp codes to the trained range", flag="--no-clamp")
    output_bits: int | None = _opt(None, "signed output width", type=int)
    output_lsb_mm: float | None = _opt(None, "mm per output code", type=float)
    lanes: int = _opt(1, "parallel term lanes (default %(default)s)", type=int)
    mult_style: str = _opt("shiftadd", "multiplier style (default %(default)s)", type=str, choices=MULT_STYLES)
    mult_digit_bits: int = _opt(2, "shift-add: weight bits per cycle (default %(default)s)", type=int)
    interp: bool = _opt(True, "plain table lookup, no slope correction", flag="--no-interp")
    phase_bits: int | None = _opt(None, "phase width (units of pi, mod 2)", type=int)
    table_addr_bits: int | None = _opt(None, "quarter-wave table address bits", type=int)
    term_frac_bits: int | None = _opt(None, "fraction bits of sin/cos terms", type=int)
    weight_frac_bits: int | None = _opt(None, "fraction bits of weights (output LSB units)", type=int)
    product_frac_bits: int | None = _opt(None, "fraction bits kept after each product", type=int)

    def to_kwargs(self) -> dict:
        """The one-input datapaths' keyword arguments (the two-input ones' read as attributes)."""
        return {k: v for k, v in asdict(self).items() if k not in TWO_INPUT}

    def changed(self) -> dict:
        """The options that differ from their defaults."""
        return {k: v for k, v in asdict(self).items() if v != default(k)}

    @classmethod
    def of(cls, options: "GenOptions | None" = None, **overrides) -> "GenOptions":
        """``options`` (default: all defaults) with ``overrides``; SpecError names an unknown option."""
        unknown = sorted(set(overrides) - set(NAMES))
        if unknown:
            raise SpecError(f"unknown generator option(s) {', '.join(unknown)}; allowed: {', '.join(NAMES)}")
        return replace(options or cls(), **overrides)


NAMES = tuple(f.name for f in fields(GenOptions))
_DEFAULTS = {f.name: f.default for f in fields(GenOptions) if f.default is not MISSING}


def default(name: str):
    """The default of one generator option."""
    return _DEFAULTS[name]


GIVEN = "generator_options_given"  # the parsed command line's names of the options typed on it


def _note(namespace, dest: str) -> None:
    setattr(namespace, GIVEN, (*getattr(namespace, GIVEN, ()), dest))


class _Store(argparse.Action):
    """Store the value and note the option as given: argparse calls an action only for a flag
    on the command line, so a flag typed at its default value is told from one left out."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        _note(namespace, self.dest)


class _SwitchOff(argparse.Action):
    """A ``--no-...`` flag: store False and note it as given."""

    def __init__(self, option_strings, dest, default=True, help=None):
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, False)
        _note(namespace, self.dest)


def given(args: argparse.Namespace) -> tuple[str, ...]:
    """The names of the generator options typed on the command line (in field order)."""
    typed = getattr(args, GIVEN, ())
    return tuple(n for n in NAMES if n in typed)


def flag_text(name: str, value) -> str:
    """An option as it is typed: ``--input-bits 10``, ``--no-interp``."""
    md = {f.name: f.metadata for f in fields(GenOptions)}[name]
    flag = md["flag"] or "--" + name.replace("_", "-")
    return flag if isinstance(value, bool) else f"{flag} {value}"


def add_arguments(parser: argparse.ArgumentParser, only: tuple[str, ...] | None = None) -> None:
    """Add the generator options (or the ``only`` ones) to a command's parser; :func:`given`
    tells which were typed."""
    g = parser.add_argument_group("architecture and widths (defaults from the error analysis)")
    for f in fields(GenOptions):
        if only is not None and f.name not in only:
            continue
        md = f.metadata
        if isinstance(f.default, bool):
            # a True default is switched off by its --no-... flag
            g.add_argument(md["flag"], dest=f.name, action=_SwitchOff, help=md["help"])
            continue
        flag = md["flag"] or "--" + f.name.replace("_", "-")
        kw = dict(dest=f.name, type=md["type"], default=f.default, help=md["help"], action=_Store)
        if md["choices"]:
            kw["choices"] = md["choices"]
        g.add_argument(flag, **kw)


def from_args(args: argparse.Namespace) -> GenOptions:
    """The options a parsed command line holds (fields it does not carry keep their defaults)."""
    return GenOptions.of(**{k: getattr(args, k) for k in NAMES if hasattr(args, k)})


__all__ = ["GenOptions", "MULT_STYLES", "NAMES", "add_arguments", "default", "flag_text", "from_args", "given"]
