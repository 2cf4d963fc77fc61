"""The diagnosis as passes, each returning a new frozen result (see docs/diagnose.md):

shape (rectified output, fold-back, passes) -> rails -> calibration (ideal simulation,
outliers, the least-squares family) -> shape term (its complexity) -> selection (named
effects) -> report (findings, kept apart from the arrays the plot draws).

No pass changes what an earlier one returned: a family with another shape term or other
data is a new family (:meth:`PhysicsFamily.with_terms`, :meth:`PhysicsFamily.with_data`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import RecordingsError
from ..physics.effects import EFFECTS
from ..physics.sensor import default_sensor
from ..recordings import Recordings, converter_step, monotonic_span
from . import data as D
from .calibrate import Calibration as IdealCalibration
from .calibrate import calibrate, initial_origin
from .confound import (UNSPLIT, Confounding, Separation, equivalent_sets, separations,
                       with_mixtures, with_shape_alternative, with_undecided)
from .explain import explain
from .model import NEUTRAL_EXTRA, Data, PhysicsFamily
from .select import Fit, Selection, Trial, evidence_chain, forward_select

# the travel is "centred on 0 mm" when |min + max| <= this fraction of the span
CENTRED = 0.1


@dataclass(frozen=True)
class EffectReport:
    name: str
    explanation: str
    params: dict
    rms_v_after: float
    delta_bic: float
    cv_t: float
    alternatives: list[str] = field(default_factory=list)
    # why delta_bic and cv_t are not computable ("" when they are)
    evidence_note: str = ""


@dataclass(frozen=True)
class Alternative:
    """A set of effects that explains the recordings as well as the chosen one: its effects
    (sentences and parameters from its own fit), its BIC relative to the choice, its RMS,
    and where its fitted curve differs most from the choice's."""

    effects: list[EffectReport]
    delta_bic: float
    rms_v: float
    differs_most_at_mm: float
    difference_v: float
    note: str = ""        # why it is listed beside the choice, when not for its BIC alone

    @property
    def named(self) -> list[str]:
        return [e.name for e in self.effects]


@dataclass(frozen=True)
class PlotArrays:
    """What the residual plot draws (kept points only): not findings."""

    x: np.ndarray = field(repr=False)
    direction: np.ndarray | None = field(repr=False)
    resid_before: np.ndarray = field(repr=False)
    resid_after: np.ndarray = field(repr=False)
    outlier_mask: np.ndarray = field(repr=False)
    # each alternative's fitted curve minus the choice's, at every point
    alternative_diffs: tuple[np.ndarray, ...] = field(repr=False, default=())


@dataclass(frozen=True)
class Diagnosis:
    source: str
    n: int
    n_used: int
    passes_text: str
    calibration_text: str
    notes: list[str]
    baseline_rms: float
    baseline_params: dict
    noise_v: float
    regions: list[dict]
    time_spans: list[tuple[float, float, float]]
    time_unit: str
    outliers: list[dict]
    effects: list[EffectReport]
    final_rms: float
    untestable: dict[str, str]
    shape_description: dict = field(default_factory=dict)
    noise_method: str = ""
    noise_regions: list = field(default_factory=list)
    ideal_rms: float = math.nan
    # other sets of effects that explain the recordings as well as ``effects`` (the choice),
    # ranked by BIC; empty when the evidence decides
    alternatives: list[Alternative] = field(default_factory=list)
    alternatives_margin: float = math.nan
    # the measurements that would tell the choice from each alternative
    separate_by: list[Separation] = field(default_factory=list)
    # the candidates tried in each round of the selection (the report names the closest)
    trials: list[list[Trial]] = field(repr=False, default_factory=list)
    plot: PlotArrays | None = field(repr=False, default=None)
    # how a long recording was reduced to means before the diagnosis ({} when it was not)
    reduced: dict = field(default_factory=dict)

    @property
    def named(self) -> list[str]:
        return [e.name for e in self.effects]

    @property
    def explanations(self) -> list[list[str]]:
        """Every set that explains the recordings equally well, the choice first ([] when
        the evidence decides)."""
        if not self.alternatives:
            return []
        return [self.named] + [a.named for a in self.alternatives]

    @property
    def shared(self) -> list[str]:
        """The effects every equally good explanation names."""
        return [e for e in self.named if all(e in a.named for a in self.alternatives)]

    @property
    def improvement(self) -> float:
        return self.baseline_rms / self.final_rms if self.final_rms > 0 else math.inf


# -- pass results ---------------------------------------------------------------------------

@dataclass(frozen=True)
class ShapeResult:
    """The recordings as diagnosed: detector kind, fold-back trimmed, passes found."""

    source: str
    n_all: int
    sensor: object                # the simulated sensor (no effects), detector kind set
    known: bool                   # geometry and origin from a sensor file
    notes: tuple[str, ...]
    tip: float | None             # null of a rectified (V-shaped) output
    rows: np.ndarray              # rows of the recordings kept
    data: Data
    passes: D.Passes


@dataclass(frozen=True)
class RailsResult:
    rails: tuple[dict, ...]
    on_rail: np.ndarray
    off: np.ndarray               # indices of the points off the rails
    passes_off: D.Passes


@dataclass(frozen=True)
class CalibrationResult:
    ideal: IdealCalibration
    centred: bool
    family: PhysicsFamily         # no shape term chosen yet
    noise_v: float                # noise of the calibration's residual (off the rails)
    out_mask: np.ndarray          # isolated outliers
    skip: np.ndarray              # outliers and rail points: left out of the fits
    fit_idx: np.ndarray
    notes: tuple[str, ...]


@dataclass(frozen=True)
class ShapeTermResult:
    family: PhysicsFamily         # with the chosen number of shape terms
    terms: int
    cv_table: dict


@dataclass(frozen=True)
class SelectionResult:
    """The chosen effects (``order``, with the fit after each and its evidence) and the
    equally good explanations; ``final`` is the chosen set's fit."""

    selection: Selection
    order: tuple[str, ...]
    cumulative: tuple[Fit, ...]
    deltas: tuple[float, ...]
    cvts: tuple[float, ...]
    alternatives: dict
    confounding: Confounding
    final: Fit


def _param(value, stderr, unit, magnitude: bool = True, unsplit: str = "") -> dict:
    """A fitted parameter.  A magnitude (a length, a gain, an effect's size; not a position
    or a phase, which may sit near zero) whose uncertainty exceeds its value is not
    determined by the recordings: marked ``determined: False``.  So is any parameter of an
    effect whose share of the misfit the recordings do not fix (``unsplit`` says why)."""
    se = float(stderr)
    out = {"value": float(value), "stderr": se if math.isfinite(se) else None, "unit": unit}
    if unsplit:
        out["determined"] = False
        out["why"] = unsplit
    elif magnitude and math.isfinite(se) and se > abs(float(value)):
        out["determined"] = False
    return out


# -- the passes ----------------------------------------------------------------------------

def shape_pass(rec: Recordings, sensor=None) -> ShapeResult:
    """Rectified output (V shape through the null), fold-back beyond the stroke, passes."""
    x_all = np.asarray(rec.displacement_mm, dtype=float)
    y_all = np.asarray(rec.voltage_v, dtype=float)
    d_given = None if rec.direction is None else np.asarray(rec.direction, dtype=float)
    D.check_inputs(x_all, y_all, d_given, rec.source)
    notes: list[str] = []
    known = sensor is not None
    sensor = (sensor or default_sensor()).replace(effects={})

    passes_all = D.find_passes(x_all, d_given)
    raw_noise = D.estimate_noise(x_all, y_all, passes_all)
    tip = D.detect_v_shape(x_all, y_all, raw_noise)
    keep = np.ones(x_all.size, bool)
    if tip is not None:
        msg = (f"the output is rectified (unsigned, V-shaped through the null at about "
               f"{tip:.3g} mm): an amplitude demodulator without phase sensitivity; "
               "diagnosing against an amplitude-demodulated simulation")
        notes.append(msg)
        if sensor.demodulator_kind != "amplitude":
            warnings.warn(f"{rec.source}: {msg}", stacklevel=3)
            sensor = sensor.replace(demodulator_kind="amplitude")
    elif sensor.demodulator_kind == "amplitude":
        notes.append("the sensor file says amplitude demodulator but the output changes sign; "
                     "diagnosing it as phase-sensitive")
        sensor = sensor.replace(demodulator_kind="phase_sensitive")
    if tip is None:
        span = monotonic_span(rec)
        if span.foldback:
            if not span.trimmable:
                raise RecordingsError(f"{span.message}; diagnose cannot judge a curve that "
                                      "turns back inside its stroke")
            keep = span.mask.copy()
            if keep.sum() < D.MIN_POINTS or np.unique(x_all[keep]).size < 4:
                raise RecordingsError(f"{span.message}; the monotonic span leaves only "
                                      f"{int(keep.sum())} points, too few to diagnose")
            msg = (f"{span.message}; trimmed to the monotonic span "
                   f"{x_all[keep].min():g}..{x_all[keep].max():g} mm "
                   f"({int((~keep).sum())} points dropped)")
            warnings.warn(msg, stacklevel=3)
            notes.append(msg.split(": ", 1)[-1])
    passes = D.find_passes(x_all[keep], None if d_given is None else d_given[keep])
    data = Data(x=x_all[keep], y=y_all[keep], direction=passes.direction,
                temperature_c=None if rec.temperature_c is None
                else np.asarray(rec.temperature_c, float)[keep],
                time_s=None if rec.time_s is None else np.asarray(rec.time_s, float)[keep])
    return ShapeResult(source=rec.source, n_all=int(x_all.size), sensor=sensor, known=known,
                       notes=tuple(notes), tip=tip, rows=np.flatnonzero(keep), data=data,
                       passes=passes)


def rails_pass(shape: ShapeResult) -> RailsResult:
    """Rails read off the data: flat runs at the extremes (none on a rectified output)."""
    x, y, direction = shape.data.x, shape.data.y, shape.data.direction
    rails = D.find_rails(x, y, shape.passes) if shape.tip is None else []
    on_rail = np.zeros(x.size, bool)
    for r in rails:
        on_rail |= r["mask"]
    off = np.flatnonzero(~on_rail)
    if rails and (off.size < D.MIN_POINTS or np.unique(x[off]).size < 4):
        # the simulation is calibrated to the readings between the rails: a step between
        # two levels leaves none (or too few) to calibrate it to
        levels = " and ".join(f"{r['level_v']:+.4g} V" for r in rails)
        raise RecordingsError(
            f"{shape.source}: {int(on_rail.sum())} of {x.size} readings sit on flat levels at "
            f"the ends of the travel ({levels}) and only {off.size} at "
            f"{np.unique(x[off]).size} displacement(s) lie between them; diagnose needs at "
            f"least {D.MIN_POINTS} at 4 displacements on the curve between the rails "
            "(a step has no curve to compare with a simulation)")
    passes_off = D.find_passes(x[off], None if direction is None else direction[off])
    return RailsResult(tuple(rails), on_rail, off, passes_off)


def calibration_pass(shape: ShapeResult, rails: RailsResult, progress=None) -> CalibrationResult:
    """The ideal simulation calibrated off the rails; isolated outliers; the fit family."""
    if progress:
        progress("calibrating the ideal simulation")
    x, y, off = shape.data.x, shape.data.y, rails.off
    known = shape.known
    # A travel centred on 0 mm says where the null should be: a null elsewhere is a
    # zero_shift.  A travel starting at 0 (or anywhere else) leaves the null to calibration.
    lo_x, hi_x = float(np.min(x)), float(np.max(x))
    centred = (not known) and abs(lo_x + hi_x) <= CENTRED * (hi_x - lo_x)
    origin0 = initial_origin(x[off], y[off], shape.tip)
    cal = calibrate(shape.sensor, x[off], y[off], origin_known=known or centred,
                    geometry_known=known, origin0=origin0, progress=progress)
    gsj = D.estimate_noise(x[off], cal.resid, rails.passes_off)
    out_off = D.find_outliers(x[off], cal.resid, rails.passes_off, gsj)
    if out_off.sum() > max(1, 0.02 * off.size):
        # many "glitches" are not glitches: keep them (they are structure or noise)
        out_off = np.zeros_like(out_off)
    out_mask = np.zeros(x.size, bool)
    out_mask[off[out_off]] = True
    skip = out_mask | rails.on_rail
    family = PhysicsFamily(cal.sensor, shape.data, origin_known=known or centred,
                           shape=cal.shape, gain0=cal.gain,
                           origin0=0.0 if centred else cal.origin_mm, scale=cal.scale,
                           origin_from_travel=centred)
    notes = []
    if cal.scale != 1.0:
        notes.append(f"the recorded displacement is scaled by {cal.scale:.4g} to match the "
                     "simulated sensor (recorded in other units than mm, or a sensor of "
                     "another size); effect parameters in mm are given in recorded units")
    if centred:
        notes.append(f"the travel ({lo_x:g}..{hi_x:g} mm) is centred on 0 mm, so the null is "
                     "expected at 0 mm: a null elsewhere is tested as zero_shift")
    return CalibrationResult(ideal=cal, centred=centred, family=family, noise_v=gsj,
                             out_mask=out_mask, skip=skip, fit_idx=np.flatnonzero(~skip),
                             notes=tuple(notes))


def shape_term_pass(shape: ShapeResult, calib: CalibrationResult,
                    progress=None) -> ShapeTermResult:
    """The smooth shape term (model-form error of the physics model): its range and its
    number of terms, by cross-validation without effects."""
    if progress:
        progress("choosing the smooth shape term")
    fam = calib.family
    core = (shape.data.x[calib.fit_idx] - fam.origin0) * fam.scale
    fam = fam.with_shape_range(float(np.max(np.abs(core))),
                               rectified=shape.sensor.demodulator_kind == "amplitude")
    k_shape, cv_table, _, tied = fam.choose_terms([], calib.fit_idx)
    return ShapeTermResult(family=fam.with_terms(k_shape, tied), terms=k_shape,
                           cv_table=cv_table)


def selection_pass(shape: ShapeResult, rails: RailsResult, calib: CalibrationResult,
                   term: ShapeTermResult, progress=None) -> SelectionResult:
    """Name the missing physics: forward selection by BIC and cross-validation."""
    family = term.family
    candidates = tuple(c for c in family.candidates
                       if not (rails.rails and c == "adc_clipping"))
    # readings on a converter's grid with less noise than one step are not dithered
    step_v = converter_step(shape.data.y[rails.off])
    sel = forward_select(family, candidates, calib.fit_idx, progress=progress,
                         resolution_v=step_v if step_v > calib.noise_v else 0.0)
    order = [s.name for s in sel.steps]
    cumulative = [s.fit for s in sel.steps]
    deltas = [s.delta_bic for s in sel.steps]
    cvts = [s.cv_t for s in sel.steps]
    if sel.dropped:  # recompute the cumulative chain in the surviving order
        cumulative, deltas = [], []
        prev = sel.baseline
        for k in range(len(order)):
            f = family.fit(order[:k + 1], calib.fit_idx, start=prev)
            cumulative.append(f)
            deltas.append(f.bic - prev.bic)
            prev = f
        cumulative[-1] = sel.final
    if progress:
        progress("testing for equally good explanations")
    conf = equivalent_sets(family, sel, candidates, calib.fit_idx, tuple(order))
    conf = with_shape_alternative(family, sel, calib.fit_idx, conf, candidates)
    conf = with_undecided(family, sel, calib.fit_idx, conf, candidates)
    conf = with_mixtures(family, calib.fit_idx, conf)
    final = sel.final
    if conf.confounded or set(conf.sets[0]) != set(order):
        # the choice is forward selection's set when it is among the equally good ones
        # (confound.equivalent_sets); otherwise the best (a larger set far ahead of it, too),
        # its figures those of the choice built one effect at a time
        final = conf.fits[0]
        if set(conf.sets[0]) != set(order):
            first = {t.name: t.delta_bic for t in (sel.trials[0] if sel.trials else [])}
            order = sorted(conf.sets[0], key=lambda e: (
                order.index(e) if e in order else len(order), first.get(e, math.inf)))
            if progress:
                progress(f"the evidence for {'+'.join(order)}")
            cumulative, deltas, cvts = evidence_chain(family, order, calib.fit_idx,
                                                      sel.baseline, final)
    return SelectionResult(selection=sel, order=tuple(order), cumulative=tuple(cumulative),
                           deltas=tuple(deltas), cvts=tuple(cvts),
                           alternatives={s.name: s.alternatives for s in sel.steps},
                           confounding=conf, final=final)


def report_pass(shape: ShapeResult, rails: RailsResult, calib: CalibrationResult,
                term: ShapeTermResult, chosen: SelectionResult) -> Diagnosis:
    """Findings (effects with their sentences, baseline, shape, noise, located mismatch)
    and, apart from them, the arrays the plot draws."""
    family = term.family
    data = shape.data
    x, y, direction = data.x, data.y, data.direction
    temp, time = data.temperature_c, data.time_s
    fit_idx, skip = calib.fit_idx, calib.skip
    sel = chosen.selection
    final = chosen.final
    all_idx = np.arange(x.size)
    before = y - family.predict(sel.baseline, all_idx)
    after = y - family.predict(final, all_idx)
    shape_v = family.shape_term(sel.baseline, all_idx)

    effects = []
    slope = _slope(family, final, all_idx)
    units = family.units()
    null_at = final.value("baseline.origin_mm") if not family.origin_known else 0.0
    if rails.rails:
        params = {}
        for r in rails.rails:
            params[f"rail_{r['side']}_v"] = _param(r["level_v"], r["stderr_v"], "V")
        params["readings_on_rail"] = _param(sum(r["n"] for r in rails.rails), math.nan, "")
        contrib = np.zeros(x.size)
        effects.append(EffectReport("adc_clipping",
                                    explain("adc_clipping", params, contrib, x, direction,
                                            temp, y, slope, null_at),
                                    params, final.rms, math.nan, math.nan,
                                    evidence_note=RAILS_EVIDENCE))
    conf = chosen.confounding

    def report(fit: Fit, name: str, k: int | None) -> EffectReport:
        params = _effect_params(family, fit, name, units)
        contrib = family.predict(fit, all_idx) - _without(family, fit, name, all_idx)
        sentence = explain(name, params, contrib, x, direction, temp, y, slope, null_at)
        if k is None:   # an alternative: its figures are the set's (Alternative)
            return EffectReport(name, sentence, params, fit.rms, math.nan, math.nan,
                                evidence_note="an alternative: see its set's figures")
        return EffectReport(name, sentence, params, chosen.cumulative[k].rms,
                            chosen.deltas[k],
                            chosen.cvts[k] if k < len(chosen.cvts) else math.nan,
                            alternatives=chosen.alternatives.get(name, []))

    for k, name in enumerate(chosen.order):
        effects.append(report(final, name, k))
    alternatives, diffs = [], []
    if conf.confounded:
        pred = family.predict(final, all_idx)
        notes = conf.notes[1:] or ("",) * (len(conf.sets) - 1)
        for names, d_bic, f, why in zip(conf.sets[1:], conf.delta_bic[1:], conf.fits[1:], notes):
            diff = family.predict(f, all_idx) - pred
            at = fit_idx[int(np.argmax(np.abs(diff[fit_idx])))]
            diffs.append(diff)
            alternatives.append(Alternative(
                effects=[report(f, name, None) for name in names],
                delta_bic=float(d_bic - conf.delta_bic[0]), rms_v=f.rms,
                differs_most_at_mm=float(x[at]), difference_v=float(diff[at]), note=why))

    # -- noise and located mismatch (residual of the baseline: simulation + shape) --------
    passes = shape.passes
    noise, noise_regions = D.estimate_noise_local(x, before, passes, exclude=skip)
    regions = D.locate_regions(x, before, passes, noise, exclude=skip)
    rows = shape.rows
    t_axis, t_unit = (time, "s") if time is not None else (rows.astype(float), "rows")
    time_spans = D.locate_time_spans(t_axis, before, noise, exclude=skip) if regions else []
    outliers = [{"row": int(rows[i]), "displacement_mm": float(x[i]),
                 "residual_v": float(after[i])} for i in np.flatnonzero(calib.out_mask)]

    known, centred, cal = shape.known, calib.centred, calib.ideal
    base = sel.baseline
    base_params = {"gain_ratio": _param(base.value("baseline.gain_ratio"),
                                        _se(base, "baseline.gain_ratio"), "")}
    if not family.origin_known:
        base_params["origin_mm"] = _param(base.value("baseline.origin_mm"),
                                          _se(base, "baseline.origin_mm"), "mm",
                                          magnitude=False)
    elif centred:
        base_params["origin_mm"] = _param(0.0, math.nan, "mm", magnitude=False)
    if not known:
        for f, v in cal.geometry.items():
            base_params[f] = _param(v, cal.geometry_stderr.get(f, math.nan), "mm")
        if cal.scale != 1.0:
            base_params["displacement_scale"] = _param(cal.scale, math.nan,
                                                       "sensor mm per recorded unit")
    # the shape of this sensor as fitted together with the named effects (its complexity
    # re-chosen once they are in: see PhysicsFamily.choose_terms)
    k_final = family.terms_of(final)
    basis_final = family.basis(k_final)
    # The shape as the difference between the fitted curve with every named effect switched
    # off and the ideal simulation as calibrated, less what a gain takes.  Not the shape term's
    # own size: its basis can draw much of the simulated curve, and with effects in the model
    # the fit may trade gain for shape (a temperature recording doubled gain_ratio and took a
    # 3 V term back off it, while the two curves differed by 1 mV).
    curve = _without(family, final, final.effects, fit_idx)
    ideal = family.evaluate(base.theta, base.names, fit_idx, basis=None)
    shape_f = curve - ideal
    den = float(ideal @ ideal)
    if den > 0:
        shape_f = shape_f - float(shape_f @ ideal) / den * ideal
    shape_desc = {
        "terms": int(k_final),
        "terms_without_effects": int(term.terms),
        "description": (basis_final.describe() if basis_final is not None else
                        "none: cross-validation prefers the calibrated simulation alone"),
        "rms_v": float(np.sqrt(np.mean(shape_f ** 2))) if fit_idx.size else 0.0,
        "peak_v": float(np.max(np.abs(shape_f))) if fit_idx.size else 0.0,
        "cv_rms_v_by_terms": {str(k): v for k, v in
                              final.extra.get("cv_table", term.cv_table).items()},
        "meaning": ("a smooth, odd, direction- and time-independent difference between this "
                    "sensor's curve and the simulated one: the shape of this sensor, not an "
                    "effect; rms_v and peak_v: the fitted curve with the named effects switched "
                    "off against the calibrated ideal simulation, beyond a change of gain"),
    }
    n_dir = "" if direction is None else (
        "directions " + "/".join(sorted({"+" if v > 0 else "-" for v in np.unique(direction)}))
        + (" (inferred from the order)" if passes.inferred else ""))
    passes_text = f"{len(passes.runs)} pass(es)" + (f", {n_dir}" if n_dir else "")
    cal_text = ("sensor file: geometry and origin known; gain fitted" if known else
                "paper LVDT as start; geometry, gain and "
                + ("origin fitted" if not centred else "shape fitted, null expected at 0 mm")) + \
        f", {shape.sensor.demodulator_kind.replace('_', '-')} detector"
    untestable = dict(family.untestable)
    if rails.rails:
        untestable.pop("adc_clipping", None)
    return Diagnosis(
        source=shape.source, n=shape.n_all, n_used=int(fit_idx.size),
        passes_text=passes_text, calibration_text=cal_text,
        notes=list(shape.notes) + list(calib.notes),
        baseline_rms=float(np.sqrt(np.mean(before[fit_idx] ** 2))),
        baseline_params=base_params, noise_v=float(noise), regions=regions,
        time_spans=time_spans, time_unit=t_unit, outliers=outliers, effects=effects,
        final_rms=float(np.sqrt(np.mean(after[fit_idx] ** 2))), untestable=untestable,
        shape_description=shape_desc, noise_method=D.NOISE_METHOD,
        noise_regions=noise_regions,
        ideal_rms=float(np.sqrt(np.mean((before + shape_v)[fit_idx] ** 2))),
        alternatives=alternatives,
        alternatives_margin=float(conf.margin) if conf.confounded else math.nan,
        separate_by=list(separations(conf.sets)) if conf.confounded else [],
        trials=sel.trials,
        plot=PlotArrays(x=x, direction=direction, resid_before=before, resid_after=after,
                        outlier_mask=skip, alternative_diffs=tuple(diffs)))


def diagnose(rec: Recordings, sensor=None, progress=None,
             max_points: int | None = None) -> Diagnosis:
    """Calibrate the ideal simulation to ``rec``, locate the mismatch, name missing physics.

    ``sensor`` (a :class:`flann.physics.sensor.Sensor`) makes geometry and origin known;
    without it the paper's LVDT is the starting point and geometry, gain and origin are
    calibrated.  ``max_points``: a longer recording is diagnosed on means of its readings
    (:func:`flann.diagnose.data.reduce_points`), which the diagnosis' notes say.
    """
    n_read = len(rec)
    rec, how = D.reduce_points(rec, max_points)
    shape = shape_pass(rec, sensor)
    rails = rails_pass(shape)
    calib = calibration_pass(shape, rails, progress)
    term = shape_term_pass(shape, calib, progress)
    chosen = selection_pass(shape, rails, calib, term, progress)
    dg = report_pass(shape, rails, calib, term, chosen)
    if how:
        dg = replace(dg, notes=[how] + dg.notes,
                     reduced={"points": len(rec), "readings": n_read, "method": how})
    return dg


RAILS_EVIDENCE = ("not computable: the rails are read off flat runs of readings at the ends "
                  "of the travel, not chosen by comparing fits")


def _effect_params(family: PhysicsFamily, fit: Fit, name: str, units: dict) -> dict:
    """``name``'s fitted parameters in ``fit``, in recorded units."""
    params = {}
    # a mixture of two effects the curve confounds: one split of their sum among many that
    # fit alike (its fit ends anywhere along that valley: beside a 0.05 mm moved null, an
    # offset of -14 mV or of -208 mV with an imbalance of either sign)
    pair = fit.extra.get(UNSPLIT, ())
    unsplit = (f"the curve does not tell how {pair[0]} and {pair[1]} share the misfit"
               if name in pair else "")
    for n, v, se in zip(fit.names, fit.theta, fit.stderr):
        if n.startswith(name + "."):
            # position effects act in the simulated sensor's mm: back to recorded units
            k_unit = 1.0 / family.scale if units.get(n) == "mm" else 1.0
            params[n.split(".", 1)[1]] = _param(v * k_unit, se * k_unit, units.get(n, ""),
                                                magnitude=not n.endswith("phase_rad"),
                                                unsplit=unsplit)
    if name == "thermal_drift":
        params["reference_temperature_c"] = _param(family.t_ref, math.nan, "degC")
    return params


def _se(fit: Fit, name: str) -> float:
    return float(fit.stderr[fit.names.index(name)])


def _without(family: PhysicsFamily, fit: Fit, effects, idx) -> np.ndarray:
    """The fitted model's output with ``effects`` (a name or several) switched off (their
    parameters neutral)."""
    theta = fit.theta.copy()
    for effect in ([effects] if isinstance(effects, str) else effects):
        neutral = {**EFFECTS[effect].neutral(), **NEUTRAL_EXTRA.get(effect, {}),
                   "rail_high_v": math.inf, "rail_low_v": -math.inf}
        for i, n in enumerate(fit.names):
            if n.startswith(effect + "."):
                theta[i] = neutral[n.split(".", 1)[1]]
    return family.evaluate_like(fit, theta, idx)


def _slope(family: PhysicsFamily, fit: Fit, idx) -> np.ndarray:
    """d(fitted model)/dx, by moving the recorded displacements (a family on moved data)."""
    h = 0.01
    d = family.data
    up = family.with_data(Data(d.x + h, d.y, d.direction, d.temperature_c, d.time_s))
    dn = family.with_data(Data(d.x - h, d.y, d.direction, d.temperature_c, d.time_s))
    return (up.predict(fit, idx) - dn.predict(fit, idx)) / (2 * h)
