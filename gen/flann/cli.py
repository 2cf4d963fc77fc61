"""The ``flann`` console command.

Subcommands live in :mod:`flann.commands` (one module each, exposing ``HELP``,
``add_arguments(parser)`` and ``run(args) -> int``).  A module is imported only when its
subcommand is used, so one command's heavy imports never slow down or break another.
"""

from __future__ import annotations

import sys

# Ctrl-C seen by our handler, or raised inside a callback (an import lock's weakref, a
# __del__), where it cannot propagate and Python would print it with a traceback; a library
# that imports an optional module inside ``try/except ImportError`` can swallow it too. The
# flag is checked again once the command's modules are in.
_interrupted: list[int] = []


def _unraisable(info, default=sys.unraisablehook):
    if isinstance(info.exc_value, KeyboardInterrupt):
        _interrupted.append(2)   # SIGINT
    else:
        default(info)


sys.unraisablehook = _unraisable

try:   # Ctrl-C while the interpreter imports this module: one line too, not a traceback
    import argparse
    import copy
    import importlib
    import os
    import signal
    import warnings

    from . import __version__
    from .argtypes import finite_float
    from .errors import FlannError, Terminated, one_line
    from .fileio import guarding_inputs
except KeyboardInterrupt:
    sys.stderr.write("error: interrupted\n")
    sys.exit(130)

# name -> one-line help; the module is flann.commands.<name>
COMMANDS: dict[str, str] = {
    "train": "train a FLANN inverse model on recordings",
    "predict": "apply a model to recordings",
    "eval": "accuracy of a model on recordings",
    "paper": "reproduce the seed paper's tables and figures",
    "gen": "generate VHDL-93 for a model",
    "sim": "co-simulate the generated VHDL under GHDL/cocotb",
    "synth": "resource estimate via GHDL synthesis and Yosys",
    "explore": "design-space table (lanes x multiplier x widths)",
    "ise": "write an ISE 10.1 project for the generated VHDL",
    "trace": "stage-by-stage error of hardware against the golden model",
    "simulate": "LVDT physics simulator: write recordings from a sensor file",
    "diagnose": "locate and name the physics missing between simulation and recordings",
    "calibrate": "calibrate sensors for a family design: weight images and certificates",
}


def _load(name: str):
    return importlib.import_module(f"flann.commands.{name.replace('-', '_')}")


class _Parser(argparse.ArgumentParser):
    """Wrong flags and values are bad input like any other: one line, exit code 2 (the
    usage block argparse prints would bury the message; it is one ``--help`` away)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.register("type", float, finite_float)   # no flag takes NaN or infinity

    def error(self, message: str):
        if _Parser._trying:
            raise _NotThisReading(message)
        self.exit(2, f"error: {self.prog}: {one_line(message)} (see {self.prog} --help)\n")

    _trying = 0   # > 0 while a reading of --json WORD is tried (an error then tries the other)

    def parse_known_args(self, args=None, namespace=None):
        """``--json WORD``: WORD is the JSON file, unless the command then misses an input WORD
        would be: ``flann eval --json model.json rec.csv`` reads model.json and prints the JSON
        (``--json=FILE`` always names the file).  When neither reading parses whole, the error
        said is the second's if the first failed, else the first's (unrecognized arguments)."""
        args = list(sys.argv[1:] if args is None else args)
        action = self._option_string_actions.get("--json")
        other = _json_word_as_positional(args) if action is not None and action.nargs == "?" else None
        if other is None:
            return super().parse_known_args(args, namespace)
        said = args   # the reading whose error is said when neither parses whole
        for reading in (args, other):
            _Parser._trying += 1
            try:
                ns, extra = super().parse_known_args(list(reading), copy.copy(namespace))
            except _NotThisReading:
                if reading is args:   # WORD as the file fails: the other reading's error says why
                    said = other
                continue
            finally:
                _Parser._trying -= 1
            if not extra:
                return ns, extra
        return super().parse_known_args(said, namespace)


class _NotThisReading(Exception):
    pass


def _json_word_as_positional(args: list[str]) -> list[str] | None:
    """``args`` with every ``--json WORD`` read as a bare ``--json`` before the word WORD (None
    when there is no such pair): the other reading of the command line."""
    out, changed = [], False
    for k, a in enumerate(args):
        if a == "--":
            out += args[k:]
            break
        nxt = args[k + 1] if k + 1 < len(args) else None
        if a == "--json" and nxt is not None and nxt != "-" and not nxt.startswith("-"):
            out.append("--json=-")   # flann.commands.common.JSON_STDOUT: the JSON on stdout
            changed = True
        else:
            out.append(a)
    return out if changed else None


def build_parser(selected: str | None = None) -> argparse.ArgumentParser:
    parser = _Parser(
        prog="flann", description="LVDT linearisation with a FLANN: model, VHDL, simulation, physics."
    )
    parser.add_argument("--version", action="version", version=f"flann {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, help_text in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        if name == selected:
            _load(name).add_arguments(p)
    return parser


def _one_line_warnings() -> None:
    def show(message, category, filename, lineno, file=None, line=None):
        print(f"warning: {one_line(message)}", file=sys.stderr)

    warnings.showwarning = show


def main(argv: list[str] | None = None) -> int:
    interrupted = _interrupted

    def on_sigint(signum, frame):
        interrupted.append(signum)
        raise KeyboardInterrupt

    def on_sigterm(signum, frame):
        interrupted.append(signum)
        raise Terminated

    try:
        # an ignored SIGINT (a background job of a script, nohup) stays ignored
        previous = (None if signal.getsignal(signal.SIGINT) is signal.SIG_IGN
                    else signal.signal(signal.SIGINT, on_sigint))
        previous_term = signal.signal(signal.SIGTERM, on_sigterm)
    except ValueError:   # not the main thread (an embedding program): leave the signals alone
        previous = previous_term = None
    try:
        return _main(argv)
    except Terminated:
        _end_children()
        print("error: terminated", file=sys.stderr)
        return 128 + signal.SIGTERM
    except KeyboardInterrupt:
        # anywhere, even while a command's modules are still importing (the first ~0.2 s)
        print("error: interrupted", file=sys.stderr)
        return 130
    except Exception:
        # a KeyboardInterrupt inside a C extension's import comes out as an ImportError
        if interrupted:
            print("error: interrupted", file=sys.stderr)
            return 130
        raise
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
        if previous_term is not None:
            signal.signal(signal.SIGTERM, previous_term)


def _end_children() -> None:
    """SIGTERM reaches flann alone (a terminal's Ctrl-C reaches its whole process group): the
    tools it started (GHDL shards, Yosys, Verilator) end with it, not run on as orphans."""
    from .verify.shards import end_children

    end_children()


def _main(argv: list[str] | None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    selected = next((a for a in argv if a in COMMANDS), None)
    parser = build_parser(selected)
    args, extra = parser.parse_known_args(argv)
    if extra:   # the subcommand's flags are the ones to see, not flann's
        prog = f"flann {args.command}" if args.command else "flann"
        parser.exit(2, f"error: {prog}: unrecognized arguments: {one_line(' '.join(extra))} "
                       f"(see {prog} --help)\n")
    if args.command is None:
        parser.print_usage(sys.stderr)
        print(f"error: flann: no command given: one of {', '.join(COMMANDS)} (see flann --help)", file=sys.stderr)
        return 2
    _one_line_warnings()
    try:
        command = _load(args.command)
        if _interrupted:   # swallowed while the command's modules imported
            raise KeyboardInterrupt
        with guarding_inputs():   # no output of this command overwrites one of its inputs
            code = int(command.run(args) or 0)
        sys.stdout.flush()  # a closed pipe shows here, not at interpreter exit
        return code
    except BrokenPipeError:
        # the reader (e.g. `| head`) stopped reading: exit quietly, as a tool killed by
        # SIGPIPE would (128 + 13); stdout goes to devnull so the final flush cannot fail
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except FlannError as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr)
        return 2
    except OSError as exc:
        # the file system refused what a command checks no further (a file where a build step
        # makes its directory, a full disk): the path and the reason, as the shell says them
        where = "".join(f"{name}: " for name in (exc.filename, exc.filename2) if name is not None)
        print(f"error: {one_line(where + (exc.strerror or str(exc)))}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
