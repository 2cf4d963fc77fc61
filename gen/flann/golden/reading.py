"""One reading of a recording, shared by every command that fits or judges a model on it
(``flann train``, ``eval``, ``diagnose``, ``calibrate``, a family's members): what it holds
and which readings a fit can use, found once.

In this order, each said in one line:

* readings at a rail (the output clipped at an amplifier's limit): left out;
* turning points (the output folds back beyond the coils): the monotonic span is kept, the
  rest left out (a fold-back inside the span is refused: no inverse exists there);
* gross outliers, against the cross-validated smooth fit of the others
  (:func:`flann.golden.forward.screen_outliers`): left out with their size in noise units.
  ``outliers``: ``drop`` (left out, however many), ``keep`` (every reading used), ``refuse``
  (any outlier refuses the recording); by default left out unless more than
  :data:`REFUSE_SHARE` of the readings are outliers, which is a recording to look at.

The usable stroke is the span of displacements kept.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import FlannError
from ..recordings import MIN_FIT_POINTS, Recordings, converter_step, monotonic_span
from ..recordings.checks import check_duplicates, check_units, find_rails, sweep_direction
from .forward import OUTLIER_K, OutlierShareError, screen_outliers, screens

OUTLIER_MODES = ("drop", "keep", "refuse")
# by default, more outliers than this share is not a few glitches but a recording to look at
REFUSE_SHARE = 0.2
# with --outliers drop: the robust fit itself cannot tell beyond half
DROP_SHARE = 0.45


@dataclass(frozen=True)
class LeftOut:
    """A reading left out: its file line, why ('rail', 'fold-back', 'outlier') and, for an
    outlier, its distance from the smooth fit in noise units."""

    line: str
    why: str
    noise_units: float | None = None


@dataclass(frozen=True)
class Reading:
    """What a recording holds and what a fit uses.

    ``rec``: the readings kept; ``raw``: every reading as read; ``left_out``: the others, in
    file order; ``stroke_mm``: the usable stroke (the kept displacements' span); ``said``: one
    line for each thing done (empty when every reading is used); ``record``: entries for a
    model's training record."""

    rec: Recordings
    raw: Recordings
    left_out: tuple[LeftOut, ...]
    stroke_mm: tuple[float, float]
    said: tuple[str, ...]
    record: dict = field(default_factory=dict)
    noise_v: float | None = None

    @property
    def lines_left_out(self) -> tuple[str, ...]:
        return tuple(lo.line for lo in self.left_out)

    def within_stroke(self, x) -> np.ndarray:
        """Mask of displacements ``x`` inside the usable stroke."""
        lo, hi = self.stroke_mm
        tol = 1e-9 * max(abs(lo), abs(hi), hi - lo, 1.0)
        x = np.asarray(x, float)
        return (x >= lo - tol) & (x <= hi + tol)


def _where(rec: Recordings, rows) -> str:
    rows = list(rows)
    shown = ", ".join(rec.line_of(int(i)) for i in rows[:4])
    return shown + (f" and {len(rows) - 4} more" if len(rows) > 4 else "")


def read_usable(rec: Recordings, outliers: str | None = None, step_v: float | None = None) -> Reading:
    """The one reading of ``rec`` (module docstring); refused (FlannError) when no inverse
    exists, too few readings are left, or the outliers are more than the mode allows."""
    if outliers is not None and outliers not in OUTLIER_MODES:
        raise FlannError(f"--outliers must be one of {', '.join(OUTLIER_MODES)}, not {outliers!r}")
    raw = rec
    if len(rec) < MIN_FIT_POINTS:
        raise FlannError(f"{rec.source}: {len(rec)} point(s); need at least {MIN_FIT_POINTS} to fit a model")
    check_units(rec)
    step = converter_step(rec.voltage_v) if step_v is None else step_v
    inferred = rec.direction is None and (d := sweep_direction(rec.displacement_mm)) is not None
    checked = replace(rec, direction=d) if inferred else rec
    # a glitch among repeats is the outlier screen's to name; repeats that disagree as a whole
    # (sweeps drifted apart, two files joined) are refused here
    check_duplicates(checked, inferred=inferred,
                     lone_glitches=outliers != "keep" and screens(rec.displacement_mm))
    keep = np.ones(len(rec), bool)
    left: dict[int, LeftOut] = {}
    said: list[str] = []
    record: dict = {}
    # rails first: a clipped end is flat, not folded back, and would steer the outlier fit
    for rail in find_rails(rec):
        rows = np.flatnonzero(rail.mask & keep)
        keep &= ~rail.mask
        for i in rows:
            left[int(i)] = LeftOut(rec.line_of(int(i)), "rail")
        x = rec.displacement_mm[rows]
        said.append(f"{rec.source}: {rows.size} reading(s) at the {rail.side} rail {rail.level_v:.6g} V "
                    f"(clipped, {x.min():g}..{x.max():g} mm, {_where(rec, rows)}) left out")
        record.setdefault("rails", []).append({"side": rail.side, "level_v": rail.level_v, "readings": int(rows.size)})
    cur = checked.subset(keep)
    idx = np.flatnonzero(keep)
    span = monotonic_span(cur)
    if span.foldback:
        if not span.trimmable:
            raise FlannError(span.message + "; the fold-back is inside the span: no part of it can be "
                             "trained as one curve")
        rows = idx[~span.mask]
        keep[rows] = False
        for i in rows:
            left[int(i)] = LeftOut(rec.line_of(int(i)), "fold-back")
        kx = rec.displacement_mm[keep]
        turn = [f"{b:+g} mm" for b, side in ((kx.max(), rec.displacement_mm[rows] > kx.max()),
                                              (kx.min(), rec.displacement_mm[rows] < kx.min())) if side.any()]
        said.append(f"{rec.source}: output turns back at {' and '.join(turn)}: trained on "
                    f"{kx.min():g}..{kx.max():g} mm ({rows.size} reading(s) beyond left out: {_where(rec, rows)})")
        record["fold_back"] = span.message
    if outliers != "keep":
        cur = checked.subset(keep)
        idx = np.flatnonzero(keep)
        share = DROP_SHARE if outliers == "drop" else REFUSE_SHARE
        try:
            sc = screen_outliers(cur.displacement_mm, cur.voltage_v, cur.direction, step, max_share=share)
        except OutlierShareError as exc:
            how = ("" if outliers == "drop" else
                   " (--outliers drop leaves them out however many, --outliers keep fits every reading)")
            raise FlannError(
                f"{rec.source}: {exc.n_out} of {exc.n} readings ({100 * exc.n_out / exc.n:.0f} %) are more than "
                f"{OUTLIER_K:g} noise units from the smooth fit of the others, more than the "
                f"{100 * share:g} % that are left out as glitches{how}: worst {cur.line_of(exc.row)}, "
                f"{exc.units:.3g} noise units (noise {exc.sigma:.3g} V); flann diagnose shows the recording") from None
        if sc is not None:
            record.update({"positions_used": sc.positions, "noise_v": float(f"{sc.noise_v:.4g}"),
                           "noise_from": sc.noise_from})
            if sc.outliers:
                if outliers == "refuse":
                    i, u = sc.outliers[0]
                    raise FlannError(
                        f"{rec.source}: {len(sc.outliers)} gross outlier reading(s), first {cur.line_of(i)} "
                        f"({u:.3g} noise units) and --outliers refuse: fix or delete the reading(s), "
                        "or leave them out (--outliers drop, the default)")
                record["outliers_left_out"] = [{"line": cur.line_of(i), "noise_units": round(u, 1)}
                                               for i, u in sc.outliers]
                for i, u in sc.outliers:
                    left[int(idx[i])] = LeftOut(cur.line_of(i), "outlier", float(u))
                keep[idx[~sc.keep]] = False
                listed = ", ".join(f"{cur.line_of(i)} ({u:.3g} noise units)" for i, u in sc.outliers[:5])
                more = f" and {len(sc.outliers) - 5} more" if len(sc.outliers) > 5 else ""
                said.append(f"{rec.source}: left out {len(sc.outliers)} gross outlier reading(s) of "
                            f"{len(cur)}: {listed}{more} (noise {sc.noise_v:.3g} V, {sc.noise_from}; "
                            "--outliers keep uses them)")
        else:
            record["outliers_checked"] = False
    kept = checked.subset(keep)
    if len(kept) < MIN_FIT_POINTS:
        raise FlannError(f"{rec.source}: only {len(kept)} reading(s) left once rails, fold-back and outliers "
                         f"are left out; need at least {MIN_FIT_POINTS}")
    stroke = (float(kept.displacement_mm.min()), float(kept.displacement_mm.max()))
    record.update({"readings_used": len(kept), "usable_stroke_mm": list(stroke)})
    record.setdefault("positions_used", int(np.unique(kept.displacement_mm).size))
    return Reading(rec=kept, raw=raw, left_out=tuple(left[i] for i in sorted(left)), stroke_mm=stroke,
                   said=tuple(said), record=record,
                   noise_v=record.get("noise_v"))


def usable_or_every(rec: Recordings, outliers: str | None, otherwise: str) -> tuple[Recordings, int | None]:
    """(the readings a command reports on, how many the shared reading left out): each thing
    :func:`read_usable` did said in one warning line, as train says it.  A recording it refuses
    (except under ``--outliers refuse``) is still one a model can be applied to: every reading,
    with one warning ending in ``otherwise`` (what the command does then); None left out."""
    try:
        reading = read_usable(rec, outliers)
    except FlannError as exc:
        if outliers == "refuse":
            raise
        warnings.warn(f"{exc}; {otherwise}", stacklevel=2)
        return rec, None
    for line in reading.said:
        warnings.warn(line, stacklevel=2)
    return reading.rec, len(rec) - len(reading.rec)


__all__ = ["DROP_SHARE", "LeftOut", "OUTLIER_MODES", "REFUSE_SHARE", "Reading", "read_usable", "usable_or_every"]
