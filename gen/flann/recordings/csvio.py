"""Recordings: the project's CSV format, read and validated once for every command.

Format (see README "Recordings format"): a header line; required columns
``displacement_mm`` and ``voltage_v``; optional ``direction`` (+1 increasing, -1
decreasing), ``time_s``, ``temperature_c``, ``excitation_hz``.  Lines starting with ``#``
are comments (provenance).  Other columns are ignored with a warning.

Files as spreadsheets and loggers export them are read too: a UTF-8 byte-order mark, CRLF
line ends, a semicolon, tab or whitespace separator (sniffed from the header; Excel's
``sep=`` first line) with decimal commas (quoted in a comma-separated file), Latin-1 text,
and headers that carry their unit (``Displacement (mm)``, ``x_mm``, ``U / mV``,
``Voltage (mV)``, ``displacement_in``...): values are converted to the canonical unit and
what was recognised is said in one line on stderr.  Error messages give the *file* line.
Two columns of one quantity in different units (``displacement_mm`` and ``displacement_in``)
are read as one: the canonical unit is used, the other must agree with it.

Bounds (one ``error:`` line when exceeded, before anything is computed): at most
:data:`MAX_ROWS` data rows and :data:`MAX_LINE_CHARS` characters per line; every value,
after conversion to its canonical unit, finite and within :data:`VALUE_RANGE` (a number
that overflows when converted, or a subnormal one, would turn a fit into NaN); displacement
and voltage vary by more than :data:`MIN_RELATIVE_SPAN` of their size when they vary at
all (a degenerate span is rounding, not signal); a last line
without a line end that is shorter than every other line's cells looks cut off (a file
copied while being written) and is refused as such.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
import re
import sys
import unicodedata
import warnings
from array import array
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import RecordingsError, one_line
from ..fileio import atomic_write_text, note_input
from ..inputs import input_error

REQUIRED = ("displacement_mm", "voltage_v")
OPTIONAL = ("direction", "time_s", "temperature_c", "excitation_hz")

# canonical column -> (names of the quantity, {unit: factor to the canonical unit}).
# A header is "<name>_<unit>", "<name> (<unit>)", "<name> [<unit>]", "<name> / <unit>" (ISO
# style), "<name>, <unit>" or "<name> <unit>", any case; units may be spelled out.
QUANTITIES: dict[str, tuple[tuple[str, ...], dict[str, float]]] = {
    "displacement_mm": (("displacement", "position", "x", "disp", "pos", "travel", "stroke",
                         "distance", "dist",
                         # German, French, Spanish, Italian, Portuguese (accents folded)
                         "weg", "verschiebung", "auslenkung", "hub", "wegstrecke",
                         "deplacement", "course", "desplazamiento", "posicion", "recorrido",
                         "carrera", "spostamento", "posizione", "corsa", "deslocamento",
                         "posicao", "curso"),
                        {"mm": 1.0, "millimeter": 1.0, "millimeters": 1.0, "millimetre": 1.0,
                         "millimetres": 1.0, "um": 1e-3, "µm": 1e-3, "micron": 1e-3, "microns": 1e-3,
                         "cm": 10.0, "m": 1000.0, "in": 25.4, "in.": 25.4, "inch": 25.4,
                         "inches": 25.4, "mil": 0.0254}),
    "voltage_v": (("voltage", "volt", "v", "u", "vout", "output", "output voltage", "lvdt output",
                   "signal", "sensor output", "lvdt voltage", "lvdt",
                   "spannung", "ausgangsspannung", "ausgang", "tension", "tension de sortie",
                   "sortie", "voltaje", "salida", "tensione", "uscita", "tensao", "saida"),
                  {"v": 1.0, "volt": 1.0, "volts": 1.0, "mv": 1e-3, "millivolt": 1e-3,
                   "millivolts": 1e-3, "uv": 1e-6, "µv": 1e-6}),
    "direction": (("direction", "dir", "richtung", "sens", "direccion", "sentido", "direzione",
                   "verso", "direcao"), {"": 1.0}),
    "time_s": (("time", "t", "zeit", "temps", "tiempo", "tempo"), {"s": 1.0, "ms": 1e-3, "min": 60.0}),
    "temperature_c": (("temperature", "temp", "temperatur", "temperatura"),
                      {"c": 1.0, "°c": 1.0, "degc": 1.0}),
    "excitation_hz": (("excitation", "frequency", "freq", "frequenz", "frequence", "frecuencia",
                       "frequenza", "frequencia"), {"hz": 1.0, "khz": 1e3}),
}
# A sensor column (a rig that records several LVDTs in one file): its values are names, not
# numbers; ``--sensor ID`` selects one
SENSOR_NAMES = ("sensor", "sensor id", "sensor_id", "sensorid", "sensor no", "sensor nr", "sensor sn",
                "serial", "serial no", "serial number", "sn", "s/n", "lvdt id", "lvdt_id",
                "channel", "device", "unit id", "sensor name", "fuhler", "capteur", "sensore")
# The two secondary amplitudes (the raw form a bench records): voltage_v is their ratio
# (A - B) / (A + B), the ratiometric LVDT output, unless the difference is asked for
SECONDARY_NAMES = {"a": ("a", "va", "v a", "v_a", "secondary a", "sec a", "amplitude a", "amp a", "vsa",
                         "ua", "u a", "vs1", "secondary 1", "sec 1", "s1", "amplitude 1", "v1"),
                   "b": ("b", "vb", "v b", "v_b", "secondary b", "sec b", "amplitude b", "amp b", "vsb",
                         "ub", "u b", "vs2", "secondary 2", "sec 2", "s2", "amplitude 2", "v2")}
AB_FORMS = ("ratio", "difference")
# lines above the header a title or metadata block may take (the header is the first line
# that names both required columns)
MAX_PREAMBLE_LINES = 64
_WITH_UNIT = (re.compile(r"^(?P<q>.+?)\s*[(\[]\s*(?P<u>[^)\]]*?)\s*[)\]]$"),
              re.compile(r"^(?P<q>[^_]+(?:_[^_]+)*?)_(?P<u>[^_\s]+)$"),
              re.compile(r"^(?P<q>.+?)\s*[/,]\s*(?P<u>[^/,]+)$"),
              re.compile(r"^(?P<q>.+)\s+(?P<u>\S+)$"))
# a direction column as loggers write it, in words
DIRECTION_WORDS = {"+": "1", "-": "-1", "up": "1", "down": "-1", "fwd": "1", "rev": "-1",
                   "forward": "1", "reverse": "-1", "backward": "-1", "inc": "1", "dec": "-1",
                   "increasing": "1", "decreasing": "-1"}
_WORDLIKE_UNITS = {"in", "in.", "m", "mil"}
SEPARATORS = {";": "semicolon", "\t": "tab", ",": "comma", " ": "whitespace"}
_WS_HEADER = re.compile(r"[^\s(\[]+(?:\s*[(\[][^)\]]*[)\]])?")
# Resource bounds.  Rows are parsed into Python lists before they become arrays: ~120 bytes
# a row at the peak, so MAX_ROWS keeps reading (and training) well under 1 GB
# (bench/recordings_memory.py); longer sweeps are averaged or decimated first.
MAX_ROWS = 1_000_000
MAX_LINE_CHARS = 65_536
# |value| in canonical units (mm, V, s, degC, Hz): 0 or within these
VALUE_RANGE = (1e-30, 1e12)
_EXCEL_SEP = re.compile(r'^\s*"?sep=(?P<sep>[;\t,])"?\s*$', re.IGNORECASE)


def accepted_names() -> str:
    """The header forms understood, for error messages (one line)."""
    def units(col):
        return ", ".join(u for u in QUANTITIES[col][1] if u.isascii())
    d_names = "/".join(QUANTITIES["displacement_mm"][0][:5])
    v_names = "/".join(QUANTITIES["voltage_v"][0][:4])
    return (f"displacement_mm, x_mm, position_mm, 'Displacement (mm)' ({d_names}, unit "
            f"{units('displacement_mm')}); voltage_v, voltage_mv, 'Voltage (V)' ({v_names}, "
            f"unit {units('voltage_v')}); optional {', '.join(OPTIONAL)}")


def _fold(name: str) -> str:
    """A header cell as names are compared: lower case, single spaces, accents dropped
    ('Déplacement' is 'deplacement', 'Tensão' 'tensao'; the degree sign and micro stay)."""
    h = " ".join(name.strip().strip('"').strip("'").split()).lower()
    if h.isascii():
        return h
    return "".join(c for c in unicodedata.normalize("NFKD", h)
                   if not unicodedata.combining(c)).replace("μ", "µ")


def recognise_header(name: str) -> tuple[str, float] | None:
    """(canonical column, factor) for a header cell, or None when it is not understood."""
    h = _fold(name)
    if h in QUANTITIES:
        return h, 1.0
    candidates = [(h, "")] + [(m["q"].strip(), m["u"].strip()) for m in
                              (rx.match(h) for rx in _WITH_UNIT) if m]
    for q, u in candidates:
        q = q.replace("_", " ")
        for col, (names, units) in QUANTITIES.items():
            if q in names and u in units:
                return col, units[u]
    # a bare unit ("mm", "[V]", "mV") names the quantity when it can only be one of the two
    # ("in", "m", "mil" alone are as likely words or indices as units)
    unit = h.strip("()[] ")
    for col in REQUIRED:
        if unit in QUANTITIES[col][1] and unit not in _WORDLIKE_UNITS:
            return col, QUANTITIES[col][1][unit]
    return None


@dataclass(frozen=True)
class Recordings:
    """Columns as float arrays of equal length; optional ones are ``None`` when absent.

    ``lines`` holds the file line of each row (for messages; ``None`` when not from a file).
    """

    displacement_mm: np.ndarray
    voltage_v: np.ndarray
    direction: np.ndarray | None = None
    time_s: np.ndarray | None = None
    temperature_c: np.ndarray | None = None
    excitation_hz: np.ndarray | None = None
    source: str = "<memory>"
    sha256: str = ""
    comments: tuple[str, ...] = field(default_factory=tuple)
    lines: np.ndarray | None = field(default=None, repr=False)
    recognised: str = ""
    sensor_id: str = ""

    def __len__(self) -> int:
        return int(self.voltage_v.size)

    def columns(self) -> dict[str, np.ndarray]:
        out = {name: getattr(self, name) for name in REQUIRED + OPTIONAL}
        return {k: v for k, v in out.items() if v is not None}

    def line_of(self, row: int) -> str:
        """'line N' (file line) of 0-based data row ``row``, or 'row N' (1-based) without a file."""
        if self.lines is None:
            return f"row {row + 1}"
        return f"line {int(self.lines[row])}"

    def subset(self, mask_or_index) -> "Recordings":
        """Rows selected by a boolean mask or index array (same columns)."""
        kw = {name: (None if arr is None else np.asarray(arr)[mask_or_index])
              for name, arr in ((n, getattr(self, n)) for n in REQUIRED + OPTIONAL)}
        lines = None if self.lines is None else np.asarray(self.lines)[mask_or_index]
        return Recordings(**kw, source=self.source, sha256=self.sha256, comments=self.comments,
                          lines=lines, recognised=self.recognised, sensor_id=self.sensor_id)


# a number as written in ASCII (the decimal comma is already a point here); inf/nan pass to
# be refused as "not finite" below
_ASCII_NUMBER = re.compile(r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
                           r"|inf|infinity|nan)\Z", re.IGNORECASE)


def _parse_float(text: str, column: str, where: str, source: str, factor: float = 1.0) -> float:
    """A cell as a number in the canonical unit (x ``factor``), finite and in VALUE_RANGE."""
    # float() also takes '1_0', full-width and other Unicode digits: a cell a logger or
    # spreadsheet never writes, so it is refused rather than read as some other number
    if not _ASCII_NUMBER.match(text):
        raise RecordingsError(
            f"{source}: {where}, column '{column}': '{text[:40]}' is not a number "
            "(ASCII digits, sign, '.' or decimal comma, exponent)")
    value = float(text)   # the pattern is a subset of what float() reads
    if not math.isfinite(value):
        raise RecordingsError(f"{source}: {where}, column '{column}': value {text} is not finite")
    if value == 0 and _NONZERO_MANTISSA.match(text.split("e")[0].split("E")[0]):
        raise RecordingsError(   # '1e-400': below every double, read as 0 by float()
            f"{source}: {where}, column '{column}': value {text[:40]} is outside what flann computes "
            f"with (0 or {VALUE_RANGE[0]:g} <= |value| <= {VALUE_RANGE[1]:g})")
    value *= factor
    lo, hi = VALUE_RANGE
    if value != 0 and not lo <= abs(value) <= hi:
        unit = f" (x {factor:g} to the canonical unit)" if factor != 1.0 else ""
        raise RecordingsError(
            f"{source}: {where}, column '{column}': value {text[:40]}{unit} is outside what flann "
            f"computes with (0 or {lo:g} <= |value| <= {hi:g})")
    return value


# '30,000', '-5.185': a mark before exactly three digits, after one to three without a leading
# zero, is a decimal mark or a thousands separator; the rest of the file tells which
_GROUPED = re.compile(r"[+-]?[1-9][0-9]{0,2}[.,][0-9]{3}\Z")


class _DecimalMarks:
    """The decimal mark of a file, settled once every cell has been seen.

    A cell with one comma and no point, or one point and no comma, that cannot be a thousands
    group ('1,5', '0.250', '1234,5', '4.', '1,5E-1') proves its mark a decimal mark.  A grouped
    cell is read as a decimal first and settled by :meth:`settle`: a thousands separator when
    only the other mark is proven, a decimal mark when only its own is; with no proof a point
    stays the decimal point it always is in CSV and a comma is a decimal comma in a semicolon
    file (a decimal-comma spreadsheet's export); any other case is refused, naming the cell.
    """

    def __init__(self):
        self.proof: dict[str, tuple[int, str] | None] = {",": None, ".": None}
        self.first: dict[str, tuple[int, str, str] | None] = {",": None, ".": None}
        self.rows: dict[tuple[str, str], array] = {}   # (mark, column) -> row indices
        self.decimal_comma = False
        self.thousands: dict[str, tuple[int, str, float]] = {}

    def see(self, cell: str, column: str, row: int, line_no: int, name: str) -> str:
        """The cell with its mark as a point (what float() reads)."""
        if "," in cell and "." in cell:
            return cell   # '1.234,5', '1,234.5': refused as not a number
        mark = "," if "," in cell else "."
        if cell.count(mark) != 1:
            return cell
        if _GROUPED.match(cell):
            self.rows.setdefault((mark, column), array("q")).append(row)
            if self.first[mark] is None:
                self.first[mark] = (line_no, name, cell)
        else:
            self.decimal_comma |= mark == ","
            if self.proof[mark] is None:
                self.proof[mark] = (line_no, cell)
        return cell.replace(",", ".")

    def settle(self, data: dict[str, list[float]], factors: dict[str, float], sep: str,
               source: str) -> None:
        """Grouped cells read with a thousands separator where the file proves it one (values
        in ``data`` rewritten); refused where nothing tells."""
        for mark, other in ((",", "."), (".", ",")):
            if self.first[mark] is None:
                continue
            line_no, name, cell = self.first[mark]
            own, theirs = self.proof[mark], self.proof[other]
            if theirs and not own:
                for (m, column), rows in self.rows.items():
                    if m != mark:
                        continue
                    for r in rows:   # read as 'a.bbb': the whole number 'abbb' is 1000 times that
                        data[column][r] = round(data[column][r] / factors[column] * 1000) * factors[column]
                self.thousands[mark] = (line_no, cell, float(cell.replace(mark, "")))
                continue
            if own and not theirs:
                self.decimal_comma |= mark == ","
                continue
            if own and theirs:
                why = (f"the file uses both as decimal marks (line {own[0]} '{own[1]}', line {theirs[0]} "
                       f"'{theirs[1]}')")
            elif self.first[other] is not None:
                why = (f"'{other}' is also followed by three digits (line {self.first[other][0]} "
                       f"'{self.first[other][2]}') and no number shows which is the decimal mark")
            elif mark == "." or sep == ";":
                self.decimal_comma |= mark == ","
                continue
            else:
                why = "no other number in the file shows which is the decimal mark"
            raise RecordingsError(
                f"{source}: line {line_no}, column '{name}': '{cell}' is ambiguous: '{mark}' before three "
                f"digits is a decimal mark or a thousands separator, and {why}; export the numbers "
                "without thousands separators")

    def note(self) -> str:
        return "".join(f", '{m}' as thousands separator (line {n} '{c}' read as {v:g})"
                       for m, (n, c, v) in self.thousands.items())


def _sniff_separator(header_line: str) -> str:
    counts = {sep: header_line.count(sep) for sep in SEPARATORS}
    for sep in (";", "\t"):   # a header holding these is not comma-separated
        if counts[sep]:
            return sep
    if not counts[","] and len(header_line.split()) > 1:
        return " "   # columns aligned with spaces (a .txt/.dat export): names without spaces
    return ","


def _cells(line: str, sep: str) -> list[str]:
    if sep == " ":
        return line.split()
    try:
        return next(csv.reader([line], delimiter=sep))
    except csv.Error as exc:   # a NUL byte, a quote left open over the field-size limit...
        raise RecordingsError(f"not CSV ({exc})") from None


def _check_line(source: str, line_no: int, line: str) -> None:
    if len(line) > MAX_LINE_CHARS:
        raise RecordingsError(f"{source}: line {line_no} is {len(line):,} characters long "
                              f"(at most {MAX_LINE_CHARS:,}): not a recordings line")


def _unit_row(body, sep: str, width: int) -> list[str] | None:
    """The line under the header when it holds units ("mm", "V", "[mV]") instead of numbers."""
    if len(body) < 2:
        return None
    cells = [c.strip().strip("()[]").strip() for c in _cells(body[1][1], sep)]
    if len(cells) != width or not any(cells):
        return None
    known = {u for _names, units in QUANTITIES.values() for u in units if u}
    if all(not c or c.lower() in known for c in cells):
        return cells
    return None


def recognise_extra(name: str) -> tuple[str, float] | None:
    """('sensor', 1) for a sensor column, ('a' or 'b', factor to volts) for a secondary
    amplitude column, or None."""
    h = _fold(name)
    if h.replace("_", " ") in SENSOR_NAMES or h in SENSOR_NAMES:
        return "sensor", 1.0
    units = QUANTITIES["voltage_v"][1]
    candidates = [(h, "v")] + [(m["q"].strip(), m["u"].strip()) for m in
                               (rx.match(h) for rx in _WITH_UNIT) if m]
    for q, u in candidates:
        q = q.replace("_", " ")
        for side, names in SECONDARY_NAMES.items():
            if (q in names or q.replace(" ", "") in names) and u in units:
                return side, units[u]
    return None


@dataclass(frozen=True)
class _Extras:
    """Columns beside the quantities: the sensor column, the two secondary amplitudes
    (index, factor to volts)."""

    sensor: int | None = None
    a: tuple[int, float] | None = None
    b: tuple[int, float] | None = None


def _extras(header: list[str]) -> _Extras:
    found: dict[str, tuple[int, float]] = {}
    for i, h in enumerate(header):
        if recognise_header(h) is None and (hit := recognise_extra(h)) is not None:
            found.setdefault(hit[0], (i, hit[1]))
    a, b = found.get("a"), found.get("b")
    if a is None or b is None:
        a = b = None
    return _Extras(sensor=found["sensor"][0] if "sensor" in found else None, a=a, b=b)


def _header_map(header: list[str], required, source: str, line_no: int | None = None,
                extras: _Extras | None = None):
    """{canonical column: (index, factor)}, notes on conversions, unknown headers."""
    extras = extras or _Extras()
    taken = {i for i in (extras.sensor, extras.a and extras.a[0], extras.b and extras.b[0]) if i is not None}
    found: dict[str, tuple[int, float]] = {}
    also: dict[str, tuple[int, float]] = {}   # a second column of the same quantity
    notes, unknown = [], []
    for i, h in enumerate(header):
        hit = recognise_header(h)
        if i in taken:
            continue
        if hit is None:
            if h:   # an unnamed column (a trailing separator) holds nothing to warn about
                unknown.append(h)
            continue
        col, factor = hit
        if col in found:
            j, other = found[col]
            if factor == other:   # the same quantity twice in the same unit: which one?
                raise RecordingsError(
                    f"{source}: duplicate column(s) {col} ('{header[j]}' and '{h}')")
            if col in also:
                raise RecordingsError(f"{source}: {col} given three times ('{header[j]}', "
                                      f"'{header[also[col][0]]}', '{h}')")
            if factor == 1.0:   # the canonical unit is the one used; the other is checked
                also[col] = (j, other)
                found[col] = (i, factor)
            else:
                also[col] = (i, factor)
            continue
        found[col] = (i, factor)
    for col, (i, factor) in found.items():
        h = header[i]
        if h != col:
            notes.append(f"'{h}' as {col}" + (f" (x {factor:g})" if factor != 1.0 else ""))
    missing = [c for c in required if c not in found and not (c == "voltage_v" and extras.a)]
    if missing:
        what = f"; not understood: {', '.join(repr(u) for u in unknown)}" if unknown else ""
        where = f"line {line_no}: " if line_no is not None else ""
        raise RecordingsError(
            f"{source}: {where}missing column(s) {', '.join(missing)} (header has: {', '.join(header)}"
            f"{what}); accepted: {accepted_names()}, or two secondary amplitudes A and B"
        )
    return found, also, notes, unknown


def _agree(source: str, header, col: str, used, other, a, b, lines) -> str:
    """The note for a quantity given twice: ``b`` (other unit) must agree with ``a`` within
    the rounding of the coarser of the two (1e-3 of the span, at least 1e-9)."""
    tol = max(1e-3 * float(np.ptp(a)), 1e-6 * float(np.max(np.abs(a))), 1e-9)
    diff = np.abs(a - b)
    k = int(np.argmax(diff))
    if diff[k] > tol:
        raise RecordingsError(
            f"{source}: line {lines[k]}: '{header[used]}' and '{header[other]}' give the same quantity "
            f"but disagree ({a[k]:.6g} vs {b[k]:.6g} in {col}'s unit, more than {tol:.3g})")
    unit = col.rsplit("_", 1)[-1]
    return f"'{header[other]}' agrees with '{header[used]}' (within {float(diff[k]):.2g} {unit}), " \
           f"{col} from '{header[used]}'"


# a column whose values differ by less than this fraction of their size varies only in the
# last digits of a double: no signal, and a fit's normalisation would divide by rounding noise
MIN_RELATIVE_SPAN = 1e-9


def _check_span(source: str, column: str, a) -> None:
    if a is None or a.size < 2:
        return
    span, size = float(np.ptp(a)), float(np.max(np.abs(a)))
    if 0 < span <= MIN_RELATIVE_SPAN * size:
        unit = column.rsplit("_", 1)[-1].replace("v", "V")
        raise RecordingsError(
            f"{source}: column '{column}' varies by only {span:.3g} {unit} around {size:.6g} {unit} "
            f"(less than {MIN_RELATIVE_SPAN:g} of its size): no usable signal, only rounding")


def _looks_cut(source: str, line_no: int, last: list[str], width: int, shortest: int | None) -> None:
    """The last line, without a line end: fewer cells than the header, or a last cell shorter
    than that column's on every other line, means it was cut off mid-line (a copy of a file
    still being written): said as such, not as whatever its numbers imply."""
    if len(last) == width and (shortest is None or len(last[-1].strip()) >= shortest):
        return
    raise RecordingsError(
        f"{source}: line {line_no}: the last line looks cut off (no line end, and it is shorter than "
        "every other line): copied while being written? complete it or delete that line")


_LINE_END = re.compile(r"\r\n|\r|\n")
# a written number whose mantissa is not zero ('1e-400' underflows to 0.0 in float())
_NONZERO_MANTISSA = re.compile(r"[+-]?[0-9.]*[1-9]")


def split_lines(text: str) -> list[str]:
    """Lines ended by LF, CRLF or a lone CR only: str.splitlines() also splits at NEL (byte
    0x85 of a Latin-1 file, an ellipsis in Windows-1252), form feeds and separators, which a
    spreadsheet's cell may hold."""
    lines = _LINE_END.split(text)
    if lines and lines[-1] == "":
        lines.pop()
    return lines


def count_line_ends(text: str) -> int:
    return text.count("\n") + text.count("\r") - text.count("\r\n")


def _find_header(body: list[tuple[int, str]], required, source: str) -> tuple[int, str | None]:
    """(index in ``body`` of the header line, the separator named by a ``sep=`` line or None).

    The header is the first line, among the first :data:`MAX_PREAMBLE_LINES`, that names every
    required column (a title or a block of metadata may stand above it); when none does, the
    first line, which the error then names."""
    for k, (_n, line) in enumerate(body[:MAX_PREAMBLE_LINES]):
        if len(line) > MAX_LINE_CHARS:
            break
        m = _EXCEL_SEP.match(line)
        if m:   # Excel's "sep=;" line names the separator; the header follows it
            return k + 1, m.group("sep")
        sep = _sniff_separator(line)
        try:
            cells = [h.strip() for h in _cells(line, sep)]
        except RecordingsError:
            continue
        if sep == " ":
            cells = _WS_HEADER.findall(line)
        try:
            units = _unit_row(body[k:], sep, len(cells))
        except RecordingsError:
            units = None
        if units is not None:   # names on this line, their units on the next
            cells = [f"{h} ({u})" if u else h for h, u in zip(cells, units)]
        hits = {hit[0] for hit in map(recognise_header, cells) if hit}
        ex = _extras(cells)
        if all(c in hits or (c == "voltage_v" and ex.a) for c in required):
            return k, None
    return 0, None


def parse_recordings(text: str, source: str = "<memory>",
                     required: tuple[str, ...] = REQUIRED, encoding_note: str = "",
                     sensor: str | None = None, ab: str = "ratio") -> Recordings:
    """Parse CSV text.  ``required=("voltage_v",)`` lets ``displacement_mm`` be absent
    (then ``None``): only for commands that do not need it (``flann predict``).

    ``sensor``: the rows of that ID in the file's sensor column (a file of several sensors is
    refused without it).  ``ab``: two secondary amplitude columns A, B (and no voltage column)
    become ``voltage_v`` = (A - B) / (A + B) ("ratio") or A - B ("difference")."""
    if ab not in AB_FORMS:
        raise RecordingsError(f"the secondaries' form must be one of {', '.join(AB_FORMS)}, not {ab!r}")
    # the bound first, on the text: the lists below cost ~100 bytes a row
    if count_line_ends(text) - text.count("\n#") > MAX_ROWS + MAX_PREAMBLE_LINES + 2:
        raise RecordingsError(f"{source}: more than {MAX_ROWS:,} data rows, more than flann reads: "
                              "average or decimate the recording first")
    sha = hashlib.sha256(text.encode()).hexdigest()
    notes = [encoding_note] if encoding_note else []
    if text.startswith("\ufeff"):
        text = text[1:]
        notes.append("UTF-8 byte-order mark")
    comments, body = [], []   # body: (file line number, text)
    for line_no, line in enumerate(split_lines(text), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            comments.append(stripped.lstrip("#").strip())
            continue
        body.append((line_no, line))
    if not body:
        raise RecordingsError(f"{source}: no header line (expected columns {', '.join(REQUIRED)})")
    start, excel = _find_header(body, required, source)
    if start:   # a title or metadata above the header: kept as provenance, said
        above = body[:start]
        if excel is None or start > 1:
            notes.append(f"header on line {body[start][0] if start < len(body) else above[-1][0]} "
                         f"below {len([a for a in above if not _EXCEL_SEP.match(a[1])])} title/metadata line(s)")
        comments += [" ".join(line.split()) for _n, line in above if not _EXCEL_SEP.match(line)]
        body = body[start:]
        if not body:
            raise RecordingsError(f"{source}: no header line after line {above[-1][0]}")
    sep = excel or _sniff_separator(body[0][1])
    for n, line in body[:2]:   # the header and a possible unit line, before they are split
        _check_line(source, n, line)
    try:
        header = [h.strip() for h in _cells(body[0][1], sep)]
        units = _unit_row(body, sep, len(header))
    except RecordingsError as exc:
        raise RecordingsError(f"{source}: line {body[0][0]}: {exc}") from None
    if sep == " ":   # "Displacement (mm) Voltage (V)": a unit in brackets belongs to the name before
        header = _WS_HEADER.findall(body[0][1])
        units = _unit_row(body, sep, len(header))
    if units is not None:   # loggers: names on one line, units on the next
        header = [f"{h} ({u})" if u and recognise_header(h) is None and recognise_extra(h) is None else h
                  for h, u in zip(header, units)]
        body = body[:1] + body[2:]
    extras = _extras(header)
    kinds = {hit[0] for hit in map(recognise_header, header) if hit}
    if extras.a is not None and "time_s" in kinds and "displacement_mm" not in kinds:
        raise _waveform(source, f"'{header[extras.a[0]]}', '{header[extras.b[0]]}'")
    found, also, col_notes, unknown = _header_map(header, required, source, body[0][0], extras)
    if unknown:
        warnings.warn(f"{source}: ignoring unknown column(s) {', '.join(unknown)}", stacklevel=2)
    secondaries = extras.a is not None and "voltage_v" not in found
    if extras.a is not None and not secondaries:
        col_notes.append(f"'{header[extras.a[0]]}' and '{header[extras.b[0]]}' not used (voltage_v given)")
    wanted = [c for c in REQUIRED + OPTIONAL if c in found]
    columns = {c: found[c] for c in wanted} | {"+" + c: also[c] for c in also}
    if secondaries:
        columns |= {"_a": extras.a, "_b": extras.b}
    data: dict[str, list[float]] = {c: [] for c in columns}
    line_numbers: list[int] = []
    marks = _DecimalMarks()
    sensor_col, ids_seen = extras.sensor, {}
    if sensor == _LIST and sensor_col is None:   # no sensor column: no IDs to list, no rows to read
        _sensor_choice(source, header, sensor_col, ids_seen, sensor)
    # one pass, row by row (no list of split rows: ~100 bytes a row less at the peak)
    cut_candidate = not text.endswith(("\n", "\r")) and len(body) > 3
    shortest_last = None   # the shortest last cell of a full row so far (for a cut-off last line)
    width = len(header)
    for k, (line_no, line) in enumerate(body[1:], start=2):
        _check_line(source, line_no, line)
        try:
            row = _cells(line, sep)
        except RecordingsError as exc:
            raise RecordingsError(f"{source}: line {line_no}: {exc}") from None
        if not any(cell.strip() for cell in row):
            continue
        if cut_candidate and k == len(body):
            _looks_cut(source, line_no, row, width, shortest_last)
        where = f"line {line_no}"
        if len(row) != width:
            raise RecordingsError(
                f"{source}: {where} has {len(row)} cells, header (line {body[0][0]}) has {width}"
            )
        n_last = len(row[-1].strip())
        shortest_last = n_last if shortest_last is None else min(shortest_last, n_last)
        if sensor_col is not None:
            sid = row[sensor_col].strip()
            if sid not in ids_seen:
                if len(ids_seen) >= MAX_SENSORS:
                    raise RecordingsError(f"{source}: {where}: more than {MAX_SENSORS} sensor IDs in column "
                                          f"'{header[sensor_col]}': not a sensor column")
                ids_seen[sid] = line_no
            if sensor is not None and sid != sensor:
                continue
        for c, (i, factor) in columns.items():
            cell = row[i].strip()
            if c == "direction":
                if cell and cell.lower() not in DIRECTION_WORDS and not _ASCII_NUMBER.match(cell):
                    raise RecordingsError(f"{source}: {where}, column {header[i]!r}: {cell[:40]!r} is not a "
                                          f"direction (+1, -1 or a word: {', '.join(sorted(DIRECTION_WORDS))})")
                cell = DIRECTION_WORDS.get(cell.lower(), cell)
            # a comma inside a cell is a decimal comma (in a comma-separated file only when
            # quoted, "1,5") or, in '30,000', maybe a thousands separator: settled below.  Once
            # a mark is proven decimal, only cells with it before three last digits need a look.
            if "," in cell or "." in cell:
                mark = "," if "," in cell else "."
                if cell[-4:-3] == mark or marks.proof[mark] is None:
                    cell = marks.see(cell, c, len(data[c]), line_no, header[i])
                elif mark == "," and "." not in cell and cell.count(",") == 1:
                    cell = cell.replace(",", ".")
            data[c].append(_parse_float(cell, header[i], where, source, factor))
        line_numbers.append(line_no)
    if len(line_numbers) > MAX_ROWS:
        raise RecordingsError(f"{source}: {len(line_numbers):,} data rows, more than flann reads ({MAX_ROWS:,}): "
                              "average or decimate the recording first")
    sensor_note = _sensor_choice(source, header, sensor_col, ids_seen, sensor)
    if sensor_note:
        notes.append(sensor_note)
    first = "_a" if secondaries else "voltage_v"
    if not data[first]:
        raise RecordingsError(f"{source}: no data rows")
    marks.settle(data, {c: factor for c, (_i, factor) in columns.items()}, sep, source)
    arrays = {c: np.asarray(v, dtype=float) for c, v in data.items()}
    del data
    lines = np.asarray(line_numbers, dtype=np.int64)
    if secondaries:
        a_v, b_v = arrays.pop("_a"), arrays.pop("_b")
        names = f"'{header[extras.a[0]]}', '{header[extras.b[0]]}'"
        if "time_s" in arrays and (np.any(a_v < 0) or np.any(b_v < 0)):
            # amplitudes are never negative: these are the secondaries' samples over time
            raise _waveform(source, names)
        arrays["voltage_v"] = _from_secondaries(source, a_v, b_v, lines, ab)
        col_notes.append("voltage_v = " + ("(A - B)/(A + B), the ratiometric output," if ab == "ratio"
                                            else "A - B") + f" of the secondary amplitudes {names}")
    for c in REQUIRED:
        _check_span(source, c, arrays.get(c))
    for c in also:
        col_notes.append(_agree(source, header, c, found[c][0], also[c][0], arrays[c], arrays.pop("+" + c), lines))
    if "direction" in arrays:
        bad = ~np.isin(arrays["direction"], (-1.0, 1.0))
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise RecordingsError(
                f"{source}: line {lines[k]}, column 'direction': {arrays['direction'][k]:g} "
                "is not +1 or -1 (or up/down, forward/reverse)"
            )
    if sep != "," or marks.decimal_comma or marks.thousands:
        notes.append(f"{SEPARATORS[sep]}-separated" + (" with decimal comma" if marks.decimal_comma else "")
                     + marks.note())
    notes += col_notes
    arrays.setdefault("displacement_mm", None)
    return Recordings(**arrays, source=source, sha256=sha, comments=tuple(comments), lines=lines,
                      recognised=", ".join(notes), sensor_id=sensor or (next(iter(ids_seen)) if ids_seen else ""))


_LIST = "\x00"   # the sensor asked for by sensor_ids: every ID, no rows
# more distinct values than this in a sensor column: not sensor IDs (a logger's row counter)
MAX_SENSORS = 10_000


def sensor_ids(source: str, text: str) -> list[str]:
    """The sensor IDs of a recording's sensor column, in the order they first appear ([] when
    it has no sensor column)."""
    try:
        parse_recordings(text, source, sensor=_LIST)
    except MultipleSensors as exc:
        return list(exc.ids)
    return []   # not reached: the listing always ends in MultipleSensors


class MultipleSensors(RecordingsError):
    """A file of several sensors read without choosing one."""

    def __init__(self, message: str, ids: tuple[str, ...]):
        super().__init__(message)
        self.ids = ids


def _sensor_choice(source, header, col, ids_seen: dict, sensor: str | None) -> str:
    """The note on the sensor read ('' without a sensor column); refused: several sensors and
    none chosen, or the chosen one absent."""
    if sensor == _LIST:
        raise MultipleSensors(f"{source}: sensors {', '.join(ids_seen)}", tuple(ids_seen))
    if sensor is not None and col is None:
        raise RecordingsError(f"{source}: --sensor {sensor}: the file has no sensor column "
                              f"(header: {', '.join(header)}; accepted: {', '.join(SENSOR_NAMES[:3])}, ...)")
    if col is None:
        return ""
    ids = tuple(ids_seen)
    shown = ", ".join(ids[:12]) + (f", ... ({len(ids)} in all)" if len(ids) > 12 else "")
    if sensor is None:
        if len(ids) > 1:
            raise MultipleSensors(
                f"{source}: column '{header[col]}' holds {len(ids)} sensors ({shown}): one model is one "
                "sensor; give --sensor ID (flann calibrate takes each as a sensor of its own)", ids)
        return f"sensor {ids[0]} (column '{header[col]}')" if ids else ""
    if sensor not in ids_seen:
        raise RecordingsError(f"{source}: --sensor {sensor}: no such ID in column '{header[col]}' "
                              f"(it holds {shown})")
    return f"sensor {sensor} of {len(ids)} (column '{header[col]}', line {ids_seen[sensor]} on)"


def _waveform(source: str, names: str) -> RecordingsError:
    return RecordingsError(
        f"{source}: a waveform recording (time_s with sampled secondary voltages {names}): its "
        "amplitudes come from demodulating it, the conditioner flow's work (docs/recordings.md, "
        "'Waveform recordings'), not from reading it as positions and voltages")


def _from_secondaries(source: str, a, b, lines, ab: str):
    if ab == "difference":
        return a - b
    total = a + b
    bad = np.flatnonzero(~(np.abs(total) > 0))
    if bad.size:
        k = int(bad[0])
        raise RecordingsError(f"{source}: line {lines[k]}: the secondary amplitudes sum to 0, no ratio "
                              "(A - B)/(A + B); read them as the difference A - B (--ab difference)")
    return (a - b) / total


# the bytes a recording may take before it is refused unread: MAX_ROWS rows of a few columns
# (~60 bytes a row in the widest exports seen) and a margin
MAX_RECORDING_BYTES = 256 << 20
_CHUNK = 1 << 20


def read_recording_bytes(path: str | Path) -> bytes:
    """The bytes of a recordings file, bounded before they are held: at most
    :data:`MAX_RECORDING_BYTES`, :data:`MAX_ROWS` line ends (LF, CRLF or a lone CR) and no
    stretch longer than a line may be (``/dev/zero``, ``/dev/urandom``, a binary file end in one
    line, without reading them whole)."""
    path = Path(path)
    try:
        fh = open(path, "rb")
    except OSError as exc:
        raise input_error(path, exc, RecordingsError, "a CSV file") from None
    parts, total, ends, run = [], 0, 0, 0
    longest = 4 * MAX_LINE_CHARS   # a line of MAX_LINE_CHARS characters, four bytes each at most
    with fh:
        while True:
            try:
                chunk = fh.read(_CHUNK)
            except OSError as exc:
                raise input_error(path, exc, RecordingsError, "a CSV file") from None
            if not chunk:
                break
            total += len(chunk)
            if total > MAX_RECORDING_BYTES:
                raise RecordingsError(f"{path}: larger than {MAX_RECORDING_BYTES >> 20} MB, more than a "
                                      f"recording flann reads ({MAX_ROWS:,} rows): average or decimate it first")
            # LF, CRLF and a lone CR each end a line (a CRLF split by the chunk counts twice)
            ends += chunk.count(b"\n") + chunk.count(b"\r") - chunk.count(b"\r\n")
            if ends > MAX_ROWS + MAX_PREAMBLE_LINES + 2 + total // _CHUNK:
                raise RecordingsError(f"{path}: more than {MAX_ROWS:,} lines, more than flann reads: "
                                      "average or decimate the recording first")
            last = max(chunk.rfind(b"\n"), chunk.rfind(b"\r"))
            run = run + len(chunk) if last < 0 else len(chunk) - last - 1
            if run > longest:
                raise RecordingsError(f"{path}: {run:,} bytes without a line end (a line holds at most "
                                      f"{MAX_LINE_CHARS:,} characters): not a recordings file")
            parts.append(chunk)
    note_input(path)
    return b"".join(parts)


def decode_recording(raw: bytes, path) -> tuple[str, str]:
    """(text, how it was decoded: '' for UTF-8)."""
    try:
        return raw.decode("utf-8"), ""
    except UnicodeDecodeError:
        if b"\x00" in raw:
            raise RecordingsError(f"{path}: binary or UTF-16 file, expected CSV text "
                                  "(export as CSV UTF-8)") from None
        return raw.decode("latin-1"), "Latin-1 text"   # spreadsheets on Windows


def read_recordings(path: str | Path, required: tuple[str, ...] = REQUIRED,
                    announce: bool = True, sensor: str | None = None, ab: str = "ratio") -> Recordings:
    """Read a recordings file; when it is not in the canonical form, one stderr line says
    how it was read (``announce``).  ``sensor``, ``ab``: :func:`parse_recordings`."""
    path = Path(path)
    text, note = decode_recording(read_recording_bytes(path), path)
    rec = parse_recordings(text, source=str(path), required=required, encoding_note=note,
                           sensor=sensor, ab=ab)
    if announce and rec.recognised:
        print(one_line(f"{path}: read {rec.recognised}"), file=sys.stderr)
    return rec


def recording_sensors(path: str | Path) -> list[str]:
    """The sensor IDs in a recordings file's sensor column ([] without one)."""
    text, _note = decode_recording(read_recording_bytes(path), path)
    return sensor_ids(str(path), text)


def format_recordings(rec: Recordings, comments: tuple[str, ...] | list[str] = (),
                      extra: dict[str, np.ndarray] | None = None) -> str:
    """CSV text of ``rec`` (+ extra columns), with ``# `` comment lines first."""
    cols = rec.columns()
    if extra:
        cols.update(extra)
    out = io.StringIO()
    for c in comments:
        # a comment of several lines (a sensor name holding a line break) stays comment lines:
        # a bare second line would read as the header
        for part in split_lines(str(c)) or [""]:
            out.write(f"# {part}\n")
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(list(cols))
    for i in range(len(rec)):
        writer.writerow([_fmt(cols[c][i], c) for c in cols])
    return out.getvalue()


def _fmt(value: float, column: str) -> str:
    if column == "direction":
        return f"{int(value):+d}"
    return f"{float(value):.9g}"


def write_recordings(path: str | Path, rec: Recordings, comments=(), extra=None) -> None:
    atomic_write_text(path, format_recordings(rec, comments, extra))
