"""Recordings: the project's CSV format, read and validated once for every command.

Format (see README "Recordings format"): a header line; required columns
``displacement_mm`` and ``voltage_v``; optional ``direction`` (+1 increasing, -1
decreasing), ``time_s``, ``temperature_c``, ``excitation_hz``.  Lines starting with ``#``
are comments (provenance).  Other columns are ignored with a warning.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import RecordingsError
from ..fileio import atomic_write_text

REQUIRED = ("displacement_mm", "voltage_v")
OPTIONAL = ("direction", "time_s", "temperature_c", "excitation_hz")


@dataclass(frozen=True)
class Recordings:
    """Columns as float arrays of equal length; optional ones are ``None`` when absent."""

    displacement_mm: np.ndarray
    voltage_v: np.ndarray
    direction: np.ndarray | None = None
    time_s: np.ndarray | None = None
    temperature_c: np.ndarray | None = None
    excitation_hz: np.ndarray | None = None
    source: str = "<memory>"
    sha256: str = ""
    comments: tuple[str, ...] = field(default_factory=tuple)

    def __len__(self) -> int:
        return int(self.voltage_v.size)

    def columns(self) -> dict[str, np.ndarray]:
        out = {name: getattr(self, name) for name in REQUIRED + OPTIONAL}
        return {k: v for k, v in out.items() if v is not None}

    def subset(self, mask_or_index) -> "Recordings":
        """Rows selected by a boolean mask or index array (same columns)."""
        kw = {name: (None if arr is None else np.asarray(arr)[mask_or_index])
              for name, arr in ((n, getattr(self, n)) for n in REQUIRED + OPTIONAL)}
        return Recordings(**kw, source=self.source, sha256=self.sha256, comments=self.comments)


def _parse_float(text: str, column: str, row: int, source: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise RecordingsError(
            f"{source}: row {row}, column '{column}': '{text}' is not a number"
        ) from None
    if not math.isfinite(value):
        raise RecordingsError(f"{source}: row {row}, column '{column}': value {text} is not finite")
    return value


def parse_recordings(text: str, source: str = "<memory>",
                     required: tuple[str, ...] = REQUIRED) -> Recordings:
    """Parse CSV text.  ``required=("voltage_v",)`` lets ``displacement_mm`` be absent
    (then ``None``): only for commands that do not need it (``flann predict``)."""
    comments = []
    lines = []
    for line in text.splitlines():
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            comments.append(stripped.lstrip("#").strip())
            continue
        lines.append(line)
    if not lines:
        raise RecordingsError(f"{source}: no header line (expected columns {', '.join(REQUIRED)})")
    reader = csv.reader(io.StringIO("\n".join(lines)))
    header = [h.strip() for h in next(reader)]
    missing = [c for c in required if c not in header]
    if missing:
        raise RecordingsError(
            f"{source}: missing column(s) {', '.join(missing)} (header has: {', '.join(header)})"
        )
    dupes = sorted({h for h in header if header.count(h) > 1})
    if dupes:
        raise RecordingsError(f"{source}: duplicate column(s) {', '.join(dupes)}")
    unknown = [h for h in header if h not in REQUIRED + OPTIONAL]
    if unknown:
        warnings.warn(f"{source}: ignoring unknown column(s) {', '.join(unknown)}", stacklevel=2)
    wanted = [c for c in REQUIRED + OPTIONAL if c in header]
    index = {c: header.index(c) for c in wanted}
    data: dict[str, list[float]] = {c: [] for c in wanted}
    for row_no, row in enumerate(reader, start=1):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise RecordingsError(
                f"{source}: row {row_no} has {len(row)} cells, header has {len(header)}"
            )
        for c in wanted:
            data[c].append(_parse_float(row[index[c]].strip(), c, row_no, source))
    if not data["voltage_v"]:
        raise RecordingsError(f"{source}: no data rows")
    arrays = {c: np.asarray(v, dtype=float) for c, v in data.items()}
    if "direction" in arrays:
        bad = ~np.isin(arrays["direction"], (-1.0, 1.0))
        if bad.any():
            row = int(np.flatnonzero(bad)[0]) + 1
            raise RecordingsError(
                f"{source}: row {row}, column 'direction': {arrays['direction'][row - 1]:g} "
                "is not +1 or -1"
            )
    sha = hashlib.sha256(text.encode()).hexdigest()
    arrays.setdefault("displacement_mm", None)
    return Recordings(**arrays, source=source, sha256=sha, comments=tuple(comments))


def read_recordings(path: str | Path, required: tuple[str, ...] = REQUIRED) -> Recordings:
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise RecordingsError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise RecordingsError(f"{path}: is a directory, expected a CSV file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RecordingsError(f"{path}: cannot read ({exc.__class__.__name__})") from None
    return parse_recordings(text, source=str(path), required=required)


def format_recordings(rec: Recordings, comments: tuple[str, ...] | list[str] = (),
                      extra: dict[str, np.ndarray] | None = None) -> str:
    """CSV text of ``rec`` (+ extra columns), with ``# `` comment lines first."""
    cols = rec.columns()
    if extra:
        cols.update(extra)
    out = io.StringIO()
    for c in comments:
        out.write(f"# {c}\n")
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
