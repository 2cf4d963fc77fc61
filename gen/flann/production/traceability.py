"""Who, where, when and at what temperature a sensor was calibrated, and which sensor it is.

Each field comes from, in this order: the recording's own ``#`` comment lines
(``# station: B2``, ``# operator = J. Smith``, ``# serial: SN-0042``, ``# fixture: F7``,
``# temperature_c: 23.1``), then the batch's flags (``--station``, ``--operator``,
``--fixture``, ``--temperature-c``).  The serial is the ``--serial-column`` value of the
first data row when that flag is given, else the sensor's ID in a file of several sensors,
else the comment, else the file name's stem.  The
calibration temperature falls back to the mean of the recording's ``temperature_c`` column.
``calibrated_at`` is the local time with its UTC offset (ISO 8601), taken per sensor.
The displacement reference standard and its calibration due date come from the flags
(``--reference-standard``, ``--reference-due``); the certificate number is
``PREFIX-YYYYMMDD-HHMMSS-xxxxxxxx`` (``--certificate-prefix``, the calibration time and the
first 8 hex digits of the recording's sha256, with the sensor's ID in a file of several): a
sensor calibrated again gets a new number.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
import re
from dataclasses import dataclass
from datetime import date, datetime
from pathlib import Path

import numpy as np

from ..errors import FlannError

FIELDS = ("serial", "station", "operator", "fixture", "temperature_c")
_COMMENT = re.compile(r"^\s*([A-Za-z_ ]+?)\s*[:=]\s*(.+?)\s*$")
_ALIASES = {"serial": "serial", "serial_number": "serial", "sn": "serial", "station": "station",
            "operator": "operator", "fixture": "fixture", "temperature_c": "temperature_c",
            "temperature": "temperature_c", "calibration_temperature_c": "temperature_c"}


@dataclass(frozen=True)
class Station:
    """The batch's flags (every one optional)."""

    station: str = ""
    operator: str = ""
    fixture: str = ""
    temperature_c: float | None = None
    serial_column: str = ""
    certificate_prefix: str = "FLANN"
    reference_standard: str = ""
    reference_due: date | None = None


@dataclass(frozen=True)
class Traceability:
    serial: str
    serial_from: str            # "file name", "comment", "column 'sn'"
    station: str
    operator: str
    fixture: str
    temperature_c: float | None
    temperature_from: str       # "comment", "flag", "recording's temperature_c column (mean)"
    calibrated_at: str          # ISO 8601 with offset
    certificate_number: str = ""
    reference_standard: str = ""
    reference_due: date | None = None

    def reference_text(self) -> str:
        return self.reference_standard or "not stated (give --reference-standard)"

    def due_text(self) -> str:
        return self.reference_due.isoformat() if self.reference_due else "not stated (give --reference-due)"

    def temperature_text(self) -> str:
        if self.temperature_c is None:
            return "not stated"
        return f"{self.temperature_c:.1f} degC ({self.temperature_from})"


def certificate_number(prefix: str, calibrated_at: str, key: str) -> str:
    """``PREFIX-YYYYMMDD-HHMMSS-xxxxxxxx``: the calibration time and 8 hex digits of ``key``
    (the recording's sha256, else its name)."""
    stamp = re.sub(r"[^0-9T]", "", calibrated_at[:19]).replace("T", "-")
    tail = key[:8] if re.fullmatch(r"[0-9a-f]{8,}", key) else hashlib.sha256(key.encode()).hexdigest()[:8]
    return f"{prefix}-{stamp}-{tail}"


def parse_due(text: str, today: date | None = None) -> date:
    """``--reference-due``: an ISO date (YYYY-MM-DD) not yet past; a standard past its
    calibration due date cannot make a certificate traceable."""
    try:
        due = date.fromisoformat(text.strip())
    except ValueError:
        raise FlannError(f"--reference-due {text!r}: expected a date YYYY-MM-DD") from None
    today = today or date.today()
    if due < today:
        raise FlannError(f"--reference-due {due.isoformat()}: the reference standard's calibration expired "
                         f"(today is {today.isoformat()}); recalibrate it before certifying sensors")
    return due


def now_iso() -> str:
    """Local time with its UTC offset, to the second (ISO 8601)."""
    return datetime.now().astimezone().isoformat(timespec="seconds")


def comment_fields(comments) -> dict[str, str]:
    """``key: value`` / ``key = value`` comment lines naming a traceability field."""
    out: dict[str, str] = {}
    for c in comments or ():
        m = _COMMENT.match(c)
        if m:
            key = _ALIASES.get(m.group(1).strip().lower().replace(" ", "_"))
            if key and key not in out:
                out[key] = m.group(2)
    return out


def serial_from_column(path, column: str) -> str:
    """The value of ``column`` in the first data row of a recordings CSV."""
    text = Path(path).read_text(encoding="utf-8-sig", errors="replace")
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if len(lines) < 2:
        raise FlannError(f"{path}: no data row to read the serial column {column!r} from")
    dialect = max(",;\t", key=lines[0].count)
    rows = list(csv.reader(io.StringIO("\n".join(lines[:2])), delimiter=dialect))
    header = [h.strip() for h in rows[0]]
    if column not in header:
        raise FlannError(f"{path}: no column {column!r} for the serial (header: {', '.join(header)})")
    value = rows[1][header.index(column)].strip() if len(rows[1]) > header.index(column) else ""
    if not value:
        raise FlannError(f"{path}: serial column {column!r} is empty in the first data row")
    return value


def traceability(path, rec, station: Station, sensor_id: str | None = None) -> Traceability:
    """The identification and traceability of one recording (``rec`` None: unreadable file,
    only flags and the file name are known; ``sensor_id``: one sensor of a file of several)."""
    path = Path(path)
    found = comment_fields(rec.comments if rec is not None else ())
    serial, serial_from = path.stem, "file name"
    key = getattr(rec, "sha256", "") or path.name
    if sensor_id is not None:   # the file's sha256 is every sensor's in it: the ID tells them apart
        key = hashlib.sha256(f"{key}\0{sensor_id}".encode()).hexdigest()
    if station.serial_column:
        serial, serial_from = serial_from_column(path, station.serial_column), \
            f"column {station.serial_column!r}"
    elif sensor_id is not None:   # a comment line of a file of several names none of them
        serial, serial_from = sensor_id, "sensor column"
    elif "serial" in found:
        serial, serial_from = found["serial"], "comment line"
    temp, temp_from = None, ""
    if "temperature_c" in found:
        try:
            temp, temp_from = float(found["temperature_c"].split()[0]), "recording's comment line"
        except ValueError:
            raise FlannError(f"{path}: comment temperature_c {found['temperature_c']!r} is not "
                             "a number") from None
    elif station.temperature_c is not None:
        temp, temp_from = float(station.temperature_c), "--temperature-c"
    elif rec is not None and rec.temperature_c is not None:
        t = np.asarray(rec.temperature_c, dtype=float)
        temp = float(np.mean(t))
        temp_from = (f"mean of the recording's temperature_c column, "
                     f"{float(np.min(t)):.1f}..{float(np.max(t)):.1f} degC")
    if temp is not None and not math.isfinite(temp):
        raise FlannError(f"{path}: calibration temperature {temp} is not finite")
    return Traceability(serial=serial, serial_from=serial_from,
                        station=found.get("station", station.station),
                        operator=found.get("operator", station.operator),
                        fixture=found.get("fixture", station.fixture),
                        temperature_c=temp, temperature_from=temp_from,
                        calibrated_at=(at := now_iso()),
                        certificate_number=certificate_number(station.certificate_prefix, at, key),
                        reference_standard=station.reference_standard, reference_due=station.reference_due)


__all__ = ["certificate_number", "parse_due", "Station", "Traceability", "traceability", "comment_fields", "serial_from_column",
           "now_iso", "FIELDS"]
