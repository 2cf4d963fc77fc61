"""A verdict on a result, judged against named references: one line, and the same as the
``verdict`` field of a command's JSON.

A verdict is made of checks, each a figure against a reference (the straight line through
the same data, the float model, the physical limit, a specification).  It is ``bad`` when a
check fails, ``good`` when every check was judged and passed, ``not judged`` when nothing
could be (no reference).  A bad verdict names each cause and its remedy; ``--strict`` turns it
into exit 1 (:func:`exit_code`).  (Production certificates judge against a specification with
their own PASS/FAIL: :mod:`flann.production.verdict`.)
"""

from __future__ import annotations

from dataclasses import dataclass

GOOD, BAD, NOT_JUDGED = "good", "bad", "not judged"
# the hardware may lose this much of the float model's accuracy (max error, drift) before
# it is said to lose the compensation
HARDWARE_FACTOR = 1.5
# errors below this (mm) are float rounding: a line the recordings fit exactly is no worse
EXACT_MM = 1e-9


@dataclass(frozen=True)
class Check:
    """One figure against its reference: ``ok`` None when it could not be judged."""

    name: str
    ok: bool | None
    text: str
    remedy: str = ""

    def to_json(self) -> dict:
        return {"name": self.name, "ok": self.ok, "text": self.text, "remedy": self.remedy}


@dataclass(frozen=True)
class Verdict:
    status: str                 # good | bad | not judged
    checks: tuple[Check, ...]

    @property
    def bad(self) -> bool:
        return self.status == BAD

    def line(self) -> str:
        """'verdict: BAD: <cause>; remedy: <remedy>' or 'verdict: GOOD: <checks>'."""
        failed = [c for c in self.checks if c.ok is False]
        shown = failed or [c for c in self.checks if c.ok is not None] or list(self.checks)
        parts = "; ".join(c.text + (f" (remedy: {c.remedy})" if c.remedy and c.ok is False else "")
                          for c in shown)
        return f"verdict: {self.status.upper()}: {parts}"

    def to_json(self) -> dict:
        return {"status": self.status, "line": self.line(), "checks": [c.to_json() for c in self.checks]}


def combine(*checks: Check) -> Verdict:
    checks = tuple(c for c in checks if c is not None)
    if any(c.ok is False for c in checks):
        return Verdict(BAD, checks)
    if checks and all(c.ok is True for c in checks):
        return Verdict(GOOD, checks)
    if any(c.ok is True for c in checks):
        return Verdict(GOOD, checks)
    return Verdict(NOT_JUDGED, checks)


def against_line(model_mm: float, line_mm: float, what: str = "max error") -> Check:
    """The compensated error against the straight line through the same readings: worse is bad."""
    ok = model_mm < line_mm or model_mm <= EXACT_MM   # an exact line: both at rounding level
    text = (f"compensated {what} {model_mm:.4g} mm {'below' if ok else 'above'} the straight line's "
            f"{line_mm:.4g} mm on the same readings")
    if not ok:
        text = "compensated worse than the straight line: " + text
    return Check("against_straight_line", ok, text,
                 "" if ok else "train with --terms auto (the default), or check the recording's usable "
                               "stroke (flann diagnose)")


def hardware_against_float(hw_mm: float, float_mm: float, what: str = "max error", unit: str = "mm",
                           remedy: str = "") -> Check:
    """The hardware's figure against the float model's: more than HARDWARE_FACTOR times is bad."""
    limit = HARDWARE_FACTOR * abs(float_mm)
    ok = abs(hw_mm) <= limit or abs(hw_mm) <= 1e-12
    text = (f"hardware {what} {hw_mm:.4g} {unit} {'within' if ok else 'beyond'} {HARDWARE_FACTOR:g}x the "
            f"float model's {float_mm:.4g} {unit}")
    if not ok:
        text = "hardware loses the compensation: " + text
    return Check(f"hardware_vs_float_{what.replace(' ', '_')}", ok, text,
                 "" if ok else (remedy or "generate with wider --input-bits / output widths"))


def against_limit(max_mm: float, limit_mm: float) -> Check:
    """Informational: how far the error is above the converter's physical limit (not judged)."""
    return Check("physical_limit", None, f"max error {max_mm:.4g} mm is {max_mm / limit_mm:.3g}x the "
                                         f"physical limit {limit_mm:.3g} mm" if limit_mm > 0 else
                 f"max error {max_mm:.4g} mm")


def no_specification() -> Check:
    return Check("specification", None, "no specification: not judged against one",
                 "give the tolerance (--spec)")


def exit_code(verdict: Verdict | None, strict: bool) -> int:
    """1 under --strict when the verdict is bad, else 0."""
    return 1 if strict and verdict is not None and verdict.bad else 0


__all__ = ["BAD", "Check", "GOOD", "HARDWARE_FACTOR", "NOT_JUDGED", "Verdict", "against_limit", "against_line",
           "combine", "exit_code", "hardware_against_float", "no_specification"]
