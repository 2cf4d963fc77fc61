"""The ``--family`` option of ``flann gen``: its arguments and their checks (not a subcommand of its own)."""

from __future__ import annotations


from ..argtypes import terms_or_auto
from ..errors import FlannError
from ..golden.model import MAX_TERMS
from ..hardware.family.build import MIN_TERMS
from ..hardware.family.spec import DEFAULT_MARGIN
from ..hardware.registry import FAMILY


def add_family_arguments(parser) -> None:
    g = parser.add_argument_group("one design for a family of sensors (docs/production.md)")
    g.add_argument("--family", nargs="+", metavar="REC_OR_MODEL", default=None,
                   help="size one design for these sensors (recordings .csv or model .json); per-sensor "
                        "values go to a weight memory loadable through cfg_we/cfg_addr/cfg_data; recordings "
                        "at several temperatures add in_temp and one memory per temperature order")
    g.add_argument("--terms", type=terms_or_auto(MIN_TERMS, MAX_TERMS), default=None,
                   help="--family: expansion terms (per temperature order with temperature) when training "
                        "recordings, or 'auto' (default): chosen like flann train --terms auto (--temperature "
                        "with temperature) for the member that needs the most (docs/production.md)")
    g.add_argument("--margin", type=float, default=DEFAULT_MARGIN,
                   help="--family: headroom for sensors like these, 0.5 = 50 %% larger weights and "
                        "ranges (default %(default)s)")


def check_family_args(args) -> None:
    if args.family is None:
        raise FlannError("give a model.json, or --family REC_OR_MODEL...")
    if args.model is not None:
        raise FlannError(f"{args.model}: give either a model or --family, not both")
    if args.format != FAMILY.number_format:
        raise FlannError(f"--family generates the {FAMILY.number_format} datapath only "
                         f"(--format {FAMILY.number_format})")
