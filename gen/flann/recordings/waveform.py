"""Waveform recordings: the sampled excitation and secondaries of an LVDT (docs/waveforms.md).

Format: a CSV with the columns ``time_s,exc_v,sec_a_v,sec_b_v,displacement_mm`` and the
optional ``temperature_c``; ``exc_v`` is optional on read (a bench that records only the
secondaries).  It is read by the recordings reader (:mod:`flann.recordings.csvio`): the same
comments, units (``sec_a (mV)``, a unit line under the header), separators, decimal commas,
encodings and bounds.  ``flann simulate --waveforms`` writes it; a bench that records with a
DAQ writes the same file.

Public API:

* :class:`Waveforms` (frozen dataclass of equal-length float arrays; ``exc_v`` and
  ``temperature_c`` may be ``None``), ``sample_rate_hz``, ``len()``.
* :func:`is_waveform_csv` (path): its header names time and both secondaries;
  :func:`carrier_hz` (Waveforms): the carrier's frequency.
* :func:`read_waveforms` (path) / :func:`parse_waveforms` (text, source) -> Waveforms.
* :func:`format_waveforms` / :func:`write_waveforms` (path, waveforms, comments).
"""

from __future__ import annotations

import csv
import io
import math
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import RecordingsError, one_line
from ..fileio import atomic_write_text
from ..inputs import read_bytes
from .csvio import _EXCEL_SEP, _WITH_UNIT, MAX_LINE_CHARS, QUANTITIES, _cells, _sniff_separator, parse_recordings

# the voltage channels: canonical column -> the names a header may give it (with a unit)
CHANNELS: dict[str, tuple[str, ...]] = {
    "exc_v": ("exc", "excitation", "primary", "drive"),
    "sec_a_v": ("sec a", "secondary a", "seca", "sec1", "secondary 1", "a"),
    "sec_b_v": ("sec b", "secondary b", "secb", "sec2", "secondary 2", "b"),
}
COLUMNS = ("time_s", "exc_v", "sec_a_v", "sec_b_v", "displacement_mm", "temperature_c")
REQUIRED = ("time_s", "sec_a_v", "sec_b_v", "displacement_mm")
_VOLT_UNITS = QUANTITIES["voltage_v"][1]
# a column name the recordings reader does not know: the channels not read in a pass
_HIDDEN = "wave-hidden-{}"


@dataclass(frozen=True)
class Waveforms:
    """Sampled waveforms, one row per sample, in volts, seconds, mm and degC."""

    time_s: np.ndarray
    sec_a_v: np.ndarray
    sec_b_v: np.ndarray
    displacement_mm: np.ndarray
    exc_v: np.ndarray | None = None
    temperature_c: np.ndarray | None = None
    source: str = "<memory>"
    comments: tuple[str, ...] = field(default_factory=tuple)
    recognised: str = ""   # how a file not in the canonical form was read ("" when it was)

    def __len__(self) -> int:
        return int(self.time_s.size)

    @property
    def sample_rate_hz(self) -> float:
        """Samples per second: the sample steps between the first and the last time over their
        duration (each step counted in whole median steps, so that a gap counts its samples);
        the median step alone is only as fine as the times' last digit (a 390.625 ns step written
        to the nanosecond reads as 390 or 391)."""
        step = np.diff(self.time_s)
        steps = float(np.sum(np.maximum(1.0, np.round(step / float(np.median(step))))))
        return steps / float(self.time_s[-1] - self.time_s[0])

    def columns(self) -> dict[str, np.ndarray]:
        out = {c: getattr(self, c) for c in COLUMNS}
        return {c: v for c, v in out.items() if v is not None}


def _channel_of(cell: str) -> tuple[str, str] | None:
    """(channel, unit text) for a header cell naming a voltage channel, else None; the unit
    is '' when the header gives none (it may be on a unit line below)."""
    h = " ".join(cell.strip().strip('"').strip("'").split()).lower()
    if h in CHANNELS:
        return h, "v"
    candidates = [(h, "")] + [(m["q"].strip(), m["u"].strip()) for m in
                              (rx.match(h) for rx in _WITH_UNIT) if m]
    for q, u in candidates:
        q = q.replace("_", " ")
        for col, names in CHANNELS.items():
            if q in names and (u in _VOLT_UNITS or u == ""):
                return col, u
    return None


def _quote(cell: str, sep: str) -> str:
    if sep == " " or (sep not in cell and '"' not in cell):
        return cell
    return '"' + cell.replace('"', '""') + '"'


def _header_at(lines: list[str]) -> int:
    """Index of the header line: the first that is not blank, a comment or Excel's ``sep=``."""
    for i, line in enumerate(lines):
        stripped = line.strip()
        if not stripped or stripped.startswith("#") or _EXCEL_SEP.match(line):
            continue
        return i
    raise RecordingsError("no header line (expected columns " + ",".join(COLUMNS) + ")")


def parse_waveforms(text: str, source: str = "<memory>", encoding_note: str = "") -> Waveforms:
    """Parse waveform CSV text.  Each voltage channel is read by the recordings reader as
    its ``voltage_v`` (the header cell renamed, the other channels hidden from it), so every
    cell is read, converted and bounded by that one reader."""
    if text.startswith("\ufeff"):
        text = text[1:]
    lines = text.split("\n")
    try:
        at = _header_at(lines)
    except RecordingsError as exc:
        raise RecordingsError(f"{source}: {exc}") from None
    excel = next((_EXCEL_SEP.match(line) for line in lines[:at] if _EXCEL_SEP.match(line)), None)
    header_line = lines[at].rstrip("\r")
    sep = excel.group("sep") if excel else _sniff_separator(header_line)
    try:
        cells = [c.strip() for c in _cells(header_line, sep)]
    except RecordingsError as exc:
        raise RecordingsError(f"{source}: line {at + 1}: {exc}") from None
    found: dict[str, tuple[int, str]] = {}
    for i, cell in enumerate(cells):
        hit = _channel_of(cell)
        if hit is None:
            continue
        if hit[0] in found:
            raise RecordingsError(f"{source}: duplicate column {hit[0]} ('{cells[found[hit[0]][0]]}' "
                                  f"and '{cell}')")
        found[hit[0]] = (i, hit[1])
    missing = [c for c in ("sec_a_v", "sec_b_v") if c not in found]
    if missing:
        raise RecordingsError(f"{source}: missing column(s) {', '.join(missing)} (header has: "
                              f"{', '.join(cells)}); a waveform recording has "
                              + ",".join(COLUMNS[:-1]) + " (temperature_c optional)")
    read = {}
    for k, channel in enumerate(c for c in ("sec_a_v", "sec_b_v", "exc_v") if c in found):
        renamed = list(cells)
        for other, (i, _u) in found.items():
            renamed[i] = _HIDDEN.format(i)
        i, unit = found[channel]
        renamed[i] = f"voltage ({unit})" if unit else "voltage"
        if k:   # the other columns were read in the first pass
            renamed = [c if j == i else _HIDDEN.format(j) for j, c in enumerate(renamed)]
        lines[at] = sep.join(_quote(c, sep) for c in renamed) if sep != " " else " ".join(renamed)
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            rec = parse_recordings("\n".join(lines), source=source,
                                   required=("voltage_v",) if k else ("voltage_v", "displacement_mm"),
                                   encoding_note=encoding_note)
        if not k:   # the reader's warnings, but for the channels it was told to skip
            for w in seen:
                text = str(w.message)
                if "ignoring unknown column" in text:
                    names = [c for c in text.split("column(s) ", 1)[1].split(", ")
                             if not c.startswith(_HIDDEN.format(""))]
                    if names:
                        warnings.warn(f"{source}: ignoring unknown column(s) {', '.join(names)}", stacklevel=2)
                else:
                    warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        read[channel] = rec
    first = read["sec_a_v"]
    if first.time_s is None:
        raise RecordingsError(f"{source}: missing column time_s (the sample times of a waveform recording)")
    t = first.time_s
    if t.size < 2:
        raise RecordingsError(f"{source}: {t.size} sample(s): a waveform needs at least 2")
    step = np.diff(t)
    if not np.all(step > 0):
        k = int(np.flatnonzero(step <= 0)[0]) + 1
        raise RecordingsError(f"{source}: {first.line_of(k)}: time_s {t[k]:.9g} s does not follow "
                              f"{t[k - 1]:.9g} s: the sample times must increase")
    return Waveforms(time_s=t, sec_a_v=first.voltage_v, sec_b_v=read["sec_b_v"].voltage_v,
                     displacement_mm=first.displacement_mm,
                     exc_v=read["exc_v"].voltage_v if "exc_v" in read else None,
                     temperature_c=first.temperature_c, source=source, comments=first.comments,
                     recognised=_notes(first.recognised, cells, found))


def _notes(first: str, cells: list[str], found: dict[str, tuple[int, str]]) -> str:
    """The reader's notes in the channels' names: its 'voltage' is the channel of that pass."""
    notes = [n for n in first.split(", ") if n and "voltage" not in n]
    for channel, (i, unit) in found.items():
        if cells[i] != channel:
            factor = _VOLT_UNITS.get(unit or "v", 1.0)
            notes.append(f"'{cells[i]}' as {channel}" + (f" (x {factor:g})" if factor != 1.0 else ""))
    return ", ".join(notes)


def is_waveform_csv(path) -> bool:
    """True when the file's header has a ``time_s`` column and both secondaries."""
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            # bounded: a device that never ends (/dev/zero) has no line end to stop at
            head = [fh.readline(MAX_LINE_CHARS + 1) for _ in range(64)]
        line = head[_header_at(head)]
    except (OSError, RecordingsError):
        return False
    cells = [c.strip().strip('"').lower() for c in line.replace(";", ",").replace("\t", ",").split(",")]
    channels = {hit[0] for hit in map(_channel_of, cells) if hit}
    has_time = any(c == "time_s" or c.startswith("time") for c in cells)
    return has_time and {"sec_a_v", "sec_b_v"} <= channels


def carrier_hz(wave: Waveforms) -> float:
    """The carrier: the strongest line of the excitation (of A + B without it), interpolated
    between FFT bins."""
    v = wave.exc_v if wave.exc_v is not None else wave.sec_a_v + wave.sec_b_v
    fs = wave.sample_rate_hz
    spec = np.abs(np.fft.rfft(v - np.mean(v)))
    k = int(np.argmax(spec[1:])) + 1
    if 1 <= k < spec.size - 1:   # parabolic interpolation of the log spectrum
        lo, mid, hi = np.log(spec[k - 1:k + 2] + 1e-300)
        den = lo - 2 * mid + hi
        k = k + (0.5 * (lo - hi) / den if den != 0 else 0.0)
    return float(k * fs / v.size)


def read_waveforms(path: str | Path, announce: bool = True) -> Waveforms:
    """Read a waveform recording; like every recording, a file not in the canonical form is
    read as spreadsheets and loggers write it, and one stderr line says how (``announce``)."""
    path = Path(path)
    raw = read_bytes(path, RecordingsError, "a waveform CSV file")
    note = ""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        if b"\x00" in raw:
            raise RecordingsError(f"{path}: binary or UTF-16 file, expected CSV text") from None
        text, note = raw.decode("latin-1"), "Latin-1 text"
    wave = parse_waveforms(text, source=str(path), encoding_note=note)
    if announce and wave.recognised:
        print(one_line(f"{path}: read {wave.recognised}"), file=sys.stderr)
    return wave


def format_waveforms(wave: Waveforms, comments: tuple[str, ...] | list[str] = ()) -> str:
    """CSV text of ``wave`` in the canonical column order, ``# `` comment lines first."""
    cols = wave.columns()
    out = io.StringIO()
    for c in comments:
        out.write(f"# {c}\n")
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(list(cols))
    table = np.column_stack([np.asarray(v, dtype=float) for v in cols.values()])
    for row in table:
        writer.writerow([f"{v:.9g}" for v in row])
    return out.getvalue()


def write_waveforms(path: str | Path, wave: Waveforms, comments=()) -> None:
    if not all(math.isfinite(float(np.max(np.abs(v)))) for v in wave.columns().values()):
        raise RecordingsError(f"{path}: a waveform value is not finite; nothing written")
    atomic_write_text(path, format_waveforms(wave, comments))
