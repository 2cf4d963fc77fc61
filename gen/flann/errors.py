"""User-facing errors.

Every layer raises :class:`FlannError` (or a subclass) for bad input; the CLI turns it
into one line on stderr and exit code 2.  Messages name the file/field and what is allowed.
"""


def one_line(text) -> str:
    """``text`` as one printable line: a newline, NUL or other control character (from a
    hostile file name or cell) is shown escaped (``\\n``, ``\\x00``), never printed raw."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(text))


class Terminated(KeyboardInterrupt):
    """SIGTERM (``timeout``, a job scheduler, systemd): unwound as Ctrl-C is, so temporary
    directories, half-written files and a batch's summary are dealt with the same way."""


class FlannError(Exception):
    """Bad input from the user: reported as one line, exit code 2."""


class RecordingsError(FlannError):
    """A recordings CSV that cannot be used."""


class ModelFileError(FlannError):
    """A model.json that cannot be read or is of another format."""


class SpecError(FlannError):
    """A fixed-point / generator option that cannot be honoured."""


class SensorError(FlannError):
    """A sensor description (TOML) that is invalid."""
