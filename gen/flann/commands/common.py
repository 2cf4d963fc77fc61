"""The flags every subcommand spells the same way, each defined here once, and what they do.

``-o/--output PATH``  where a command writes its product (``--out``: a hidden alias kept for
                      the scripts of ``flann gen`` and ``flann calibrate``, which used it).
``--json [FILE]``     the command's report as JSON: on stdout in place of the text report, or
                      with FILE (``--json FILE``, ``--json=FILE``) written to FILE, atomically,
                      the text report printed as usual.  A word after a bare ``--json`` is FILE
                      only where the command does not need it as an input:
                      ``flann eval --json model.json rec.csv`` reads model.json (the parser
                      tries the other reading when the first leaves an input missing, see
                      :meth:`flann.cli._Parser.parse_known_args`; an optional input a command
                      cannot do without is taken back with :func:`json_word_as_input`).
``-j/--jobs N``       at most N workers or simulation shards (default: every core).
``--quiet``           no progress or informational lines on stderr; warnings and errors, and
                      every verdict, are still said.

Light on purpose (no numpy): the parser of every command imports it.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
from typing import Any

from ..errors import FlannError

JSON_STDOUT = "-"   # the value of a bare --json


def add_output(p, help: str, *, metavar: str = "OUT", required: bool = False, default=None,
               legacy_out: bool = False) -> None:
    """``-o/--output``; ``legacy_out``: ``--out`` also accepted (not shown in --help)."""
    flags = ["-o", "--output"] + (["--out"] if legacy_out else [])
    action = p.add_argument(*flags, dest="output", required=required, default=default, metavar=metavar,
                            help=help)
    # the parser still knows --out (it looked the strings up when the flag was added); help,
    # usage and error messages name the flag as it is documented
    action.option_strings = ["-o", "--output"]


def add_json(p, what: str = "the report") -> None:
    p.add_argument("--json", nargs="?", const=JSON_STDOUT, default=None, metavar="FILE",
                   help=f"print {what} as JSON; with FILE, write it there (the text as usual)")


def add_jobs(p, what: str = "simulation shards") -> None:
    # checked where it is used (one error line, exit 2), as calibrate always did
    p.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                   help=f"run at most N {what} at once (default: every core)")


def add_quiet(p) -> None:
    p.add_argument("--quiet", action="store_true",
                   help="no progress or notes on stderr (warnings and errors still)")


def add_common(p, *, output: dict | None = None, json: str | None = None, jobs: str | None = None,
               quiet: bool = True) -> None:
    """The shared flags a command has: ``output`` = :func:`add_output`'s keywords, ``json`` =
    what its report is, ``jobs`` = what runs side by side; ``--quiet`` everywhere."""
    if output is not None:
        add_output(p, **output)
    if json is not None:
        add_json(p, json)
    if jobs is not None:
        add_jobs(p, jobs)
    if quiet:
        add_quiet(p)


# -- what they do ---------------------------------------------------------------------------

def emit_json(args, obj: Any) -> bool:
    """The report ``obj`` as --json asks: True when it went to stdout (in place of the text
    report); False when there is no --json or it went into its FILE (the text report follows)."""
    if args.json == JSON_STDOUT:
        print(json.dumps(obj, indent=2))
        return True
    if args.json:
        from ..fileio import atomic_write_json

        atomic_write_json(args.json, obj)
    return False


def json_to_stdout(args) -> bool:
    return getattr(args, "json", None) == JSON_STDOUT


def json_word_as_input(args, dest: str) -> None:
    """An input the command cannot do without is missing and ``--json WORD`` was given: WORD is
    that input (``flann gen --json model.json -o DIR``), the JSON goes to stdout."""
    if getattr(args, dest) is None and args.json not in (None, JSON_STDOUT):
        setattr(args, dest, args.json)
        args.json = JSON_STDOUT


def check_model_inputs(model, rec, model_path) -> None:
    """The recordings hold every input the model takes, or one line saying which column is missing."""
    missing = [name for name in model.inputs if getattr(rec, name, None) is None]
    if missing:
        kind = {1: "one-input", 2: "two-input"}.get(len(model.inputs), f"{len(model.inputs)}-input")
        raise FlannError(f"{rec.source}: {model_path} is a {kind} model ({', '.join(model.inputs)}): the recordings "
                         f"need a {' and a '.join(missing)} column")


def quiet(args) -> bool:
    return bool(getattr(args, "quiet", False))


def info(args, *lines: str) -> None:
    """Informational lines on stderr, unless --quiet."""
    if not quiet(args):
        for line in lines:
            print(line, file=sys.stderr)


def on_terminal(args) -> bool:
    """Progress for a person watching: stderr a terminal and no --quiet."""
    return not quiet(args) and sys.stderr.isatty()


def check_jobs(jobs: int | None) -> None:
    if jobs is not None and jobs < 1:
        raise FlannError(f"-j {jobs}: must be >= 1")


@contextlib.contextmanager
def cores_limited(jobs: int | None):
    """``-j N`` for the simulations' shards: this process and what it starts run on N of the
    cores it may use, and the shard counts (:func:`flann.verify.shards.cores`, which reads the
    same affinity) follow; None: unchanged.  Where a process cannot choose its cores (not
    Linux), every core is used."""
    check_jobs(jobs)
    if jobs is None or not hasattr(os, "sched_setaffinity"):
        yield
        return
    before = os.sched_getaffinity(0)
    if jobs >= len(before):
        yield
        return
    os.sched_setaffinity(0, sorted(before)[:jobs])
    try:
        yield
    finally:
        with contextlib.suppress(OSError):
            os.sched_setaffinity(0, before)


__all__ = ["JSON_STDOUT", "add_common", "add_jobs", "add_json", "add_output", "add_quiet", "check_jobs",
           "cores_limited", "emit_json", "info", "json_to_stdout", "json_word_as_input", "on_terminal", "quiet"]
