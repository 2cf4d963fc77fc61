"""``flann calibrate``: one family design, many sensors -- train, quantise, check, certify.

Per recording (:func:`calibrate_one`, no HDL simulation: the design was verified once and
the bit-true twin of the family design stands for it):

1. read the recordings, train a FLANN with the design's terms (:func:`train_for_design`:
   the family's training call, with more ridge until the weights fit the design's formats);
2. quantise into the design's memory words and check with the design's twin over every
   input code: |twin - float model| against the error bound of the formats;
3. hardware error on the recording (the twin at the recording's input codes) against the
   physical limit: half an input LSB divided by the local slope dv/dx, worst over the stroke;
4. run the diagnosis (:func:`flann.diagnose.diagnose`) for warnings, on a budget
   (:func:`diagnosis_sample`: at most ``DIAGNOSIS_POINTS`` bin means of consecutive rows of
   one pass; the diagnosis' cost is its nonlinear fits, a fixed number per candidate effect,
   and averaging keeps its power for effects that vary over more than a bin);
5. write ``OUTDIR/<sensor>/``: model.json, weights.hex, weights.mem, weights.bmm and
   certificate.html, all or nothing.

A family design with temperature (``hardware/family_thermal``) takes multi-temperature
recordings instead (:func:`calibrate_one_thermal`, :mod:`.thermal`): the same steps with the
two-input model, a verdict at each temperature and the drift figure.

:func:`calibrate_batch` runs recordings over a process pool; a bad recording becomes a
``failed`` row with its reason and the batch goes on; ``summary.csv`` is written last.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
import os
import signal
import stat
import sys
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from functools import lru_cache, partial
from pathlib import Path

import numpy as np

from .. import __version__
from ..diagnose import diagnose
from ..diagnose.data import reduce_points
from ..errors import FlannError, Terminated
from ..fileio import atomic_directory, atomic_write_text, child, remove_output_directory, safe_name
from ..golden.family import REACH_FACTOR, own_reach_mm, ridge_ladder
from ..golden.metrics import raw_output_mm
from ..golden.train import fit_auto, fit_lstsq
from ..golden.model import text_sha256
from ..hardware.accuracy import adc_codes, physical_limit_mm
from ..hardware.fixed.cost import fixed_point_cost
from ..hardware.family.build import train_model
from ..hardware.family.render import design_hash
from ..hardware.design import as_design
from ..hardware.registry import FAMILY, FAMILY_THERMAL
from ..hardware.family.spec import FamilySpec, FitError, member_spec, outside_input
from ..hardware.family.twin import FlannFamilyMem, FlannFamilyTop
from ..physics.sensor import load_sensor
from ..pool import run_batch
from ..golden.screen import ready_for_fit
from ..recordings import Recordings, read_recordings, recording_sensors
from ..hardware.family import images
from .certificate import render_certificate, render_certificate_thermal, render_rejection
from .spec import ProductionSpec
from .thermal import check_sensor_thermal
from .traceability import Station, Traceability, traceability
from .verdict import FAIL, Verdict, judge, rejected, require_positions, uncertainty

# The diagnosis sees at most this many points (bin means).  On 2,000-point sweeps without a
# sensor file, about a quarter of the CPU of every point (bench/bench_line_rate.py's sensors),
# the same effects named on the simulated sensors tried (docs/production.md); fewer points save
# little, the number of fits dominates.
DIAGNOSIS_POINTS = 250
SUMMARY = "summary.csv"
SUMMARY_FIELDS = ("sensor", "status", "reason", "max_error_mm", "ratio_to_limit", "limit_mm",
                  "raw_max_error_mm", "twin_vs_float_lsb", "recording",
                  # the verdict against the spec and the traceability (production/verdict.py,
                  # production/traceability.py)
                  "verdict", "reasons", "tolerance", "max_error_pct_fs", "diagnosis",
                  "design_sha256", "model_sha256", "calibrated_at", "station", "operator",
                  "temperature_c",
                  # a family design with temperature: the hardware's drift (empty otherwise)
                  "drift_ppm_fs_per_c",
                  # what the verdict judged: its range and its max error there (max_error_mm
                  # stays the whole recording's; max_error_pct_fs is over judged_over)
                  "judged_over", "judged_max_error_mm",
                  # the sensor's own design's reach (its own train --terms auto at the design's
                  # converter; a one-input family), and every warning of the sensor's calibration
                  "own_design_max_error_mm", "warnings")


@dataclass
class Result:
    sensor: str
    recording: str
    status: str = "failed"
    reason: str = ""
    max_error_mm: float | None = None
    limit_mm: float | None = None
    ratio_to_limit: float | None = None
    raw_max_error_mm: float | None = None
    twin_vs_float_lsb: float | None = None
    warnings: list = field(default_factory=list)
    verdict: Verdict | None = None
    trace: Traceability | None = None
    diagnosis: str = ""
    design_sha256: str = ""
    model_sha256: str = ""
    written: bool = False   # OUTDIR/<sensor>/ was written by this run (_write_sensor)
    drift_ppm_fs_per_c: float | None = None  # a family design with temperature
    own_reach_mm: float | None = None   # what the sensor's own design reaches (a one-input family)
    costs_accuracy: str = ""   # the warning when the family design costs this sensor accuracy

    @property
    def kept_model_sha256(self) -> str:
        """The model's sha256 where its model.json is kept (a passed sensor); a failed or
        rejected sensor's row and certificate name none, as its folder holds no model."""
        return self.model_sha256 if self.verdict is not None and self.verdict.shipped else ""

    def fail(self, reason: str) -> None:
        """Mark failed; the reason goes into a CSV cell and one stderr line: printable, one line."""
        self.status = "failed"
        self.reason = "".join(c if c.isprintable() else repr(c)[1:-1] for c in " ".join(str(reason).split()))

    def row(self) -> dict:
        def f(x, nd=6):
            return "" if x is None else f"{x:.{nd}g}"
        return {"sensor": self.sensor, "status": self.status, "reason": self.reason,
                "max_error_mm": f(self.max_error_mm), "ratio_to_limit": f(self.ratio_to_limit, 4),
                "limit_mm": f(self.limit_mm), "raw_max_error_mm": f(self.raw_max_error_mm),
                "twin_vs_float_lsb": f(self.twin_vs_float_lsb, 4), "recording": self.recording,
                **self.verdict_cells(), "drift_ppm_fs_per_c": f(self.drift_ppm_fs_per_c, 4),
                "own_design_max_error_mm": f(self.own_reach_mm), "warnings": "; ".join(self.warnings)}

    def verdict_cells(self) -> dict:
        """The verdict and traceability columns (a row without a verdict was never judged:
        the batch was interrupted first)."""
        v = self.verdict
        t = self.trace
        reasons = v.reasons if v is not None else (f"rejected: {self.reason}",)
        return {"verdict": v.verdict if v is not None else FAIL,
                "reasons": "; ".join(reasons),
                "tolerance": v.tolerance if v is not None else "",
                "max_error_pct_fs": "" if v is None or v.max_error_pct_fs is None
                else f"{v.max_error_pct_fs:.4g}",
                "diagnosis": self.diagnosis, "design_sha256": self.design_sha256,
                "model_sha256": self.kept_model_sha256,
                "calibrated_at": t.calibrated_at if t is not None else "",
                "station": t.station if t is not None else "",
                "operator": t.operator if t is not None else "",
                "temperature_c": "" if t is None or t.temperature_c is None
                else f"{t.temperature_c:.4g}",
                "judged_over": v.range_text if v is not None else "",
                "judged_max_error_mm": "" if v is None or v.max_error_mm is None
                else f"{v.max_error_mm:.6g}"}


def train_for_design(rec, fam: FamilySpec):
    """(model, member spec): the least ridge, from the design's own up, whose weights fit the
    design's formats."""
    last = None
    for ridge in ridge_ladder(fam.ridge):
        model = train_model(rec, fam.terms, ridge)
        try:
            return model, member_spec(fam, model, text_sha256(model.to_json()))
        except FitError as exc:
            last = exc
    raise last


@dataclass(frozen=True)
class OwnDesign:
    """The structure of a sensor's own design (``--terms auto``'s choice at the family design's
    converter), chosen once per batch on its first readable recording: every sensor of a
    family is then fitted with it in one least-squares solve, not a cross-validation each."""

    terms: int
    norm: str
    ridge: float
    chosen_on: str


def _own_cost(fam: FamilySpec):
    s = fam.spec
    return lambda m: fixed_point_cost(m, (s.input_bits, s.input_lsb_v))


def own_design_for(rec, fam: FamilySpec, name: str) -> OwnDesign:
    """The own design's structure, chosen by ``--terms auto`` on ``rec`` (the expensive step, once)."""
    _model, choice = fit_auto(rec.voltage_v, rec.displacement_mm, cost=_own_cost(fam))
    return OwnDesign(int(choice.terms), str(choice.norm), float(choice.ridge), name)


def first_own_design(sources, fam: FamilySpec) -> OwnDesign | None:
    """:func:`own_design_for` on the first recording that reads and passes the screens (None:
    none does; each sensor then chooses its own).  ``sources``: :class:`Source` or paths."""
    for src in sources:
        src = src if isinstance(src, Source) else Source(Path(src))
        if special_file(src.path):
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                rec = read_recordings(src.path, announce=False, sensor=src.sensor_id)
                if outside_input(fam, rec.voltage_v):
                    continue
                rec, _said = ready_for_fit(rec)
                return own_design_for(rec, fam, src.name)
        except (FlannError, ValueError, ArithmeticError, np.linalg.LinAlgError):
            continue
    return None


def reach_flag(rec, fam: FamilySpec, max_error_mm: float,
               own: OwnDesign | None = None) -> tuple[float, str | None]:
    """(what the sensor's own design reaches on its recording, the flag or None): its own fit
    (the batch's :class:`OwnDesign` structure, else its own ``--terms auto`` choice) at the
    design's converter, asked at the voltages that converter hands on (as the hardware is),
    against the hardware's ``max_error_mm``."""
    s = fam.spec

    def received(v):
        return adc_codes(s, v) * s.input_lsb_v

    if own is None:
        reach, own_terms = own_reach_mm(rec.voltage_v, rec.displacement_mm, cost=_own_cost(fam), received=received)
        how = f"{own_terms} terms"
    else:
        model = fit_lstsq(rec.voltage_v, rec.displacement_mm, own.terms, norm=own.norm, ridge=own.ridge)
        reach = float(np.max(np.abs(model.predict(received(rec.voltage_v)) - rec.displacement_mm)))
        own_terms, how = own.terms, f"{own.terms} terms as chosen on {own.chosen_on}"
    if max_error_mm <= REACH_FACTOR * reach:
        return reach, None
    return reach, (f"hardware max error {max_error_mm:.4g} mm is {max_error_mm / reach:.2f} x what this "
                   f"sensor's own design reaches ({reach:.4g} mm, {how}, at the design's "
                   f"{s.input_bits}-bit input; flagged above {REACH_FACTOR:g} x): the family design costs it accuracy")


def check_sensor(rec, fam: FamilySpec) -> dict:
    """Train, quantise and check one sensor's recordings against the family design's twin."""
    require_positions(rec.displacement_mm, fam.terms)
    model, spec = train_for_design(rec, fam)
    words = FlannFamilyMem.encode(fam, spec)
    twin = FlannFamilyTop(fam, words)
    s = fam.spec
    codes = twin.all_codes()
    out, sat = twin.process(codes)
    q, lsb = s.output_lsb_mm, s.input_lsb_v
    inside = (codes >= spec.clamp_lo) & (codes <= spec.clamp_hi)
    ref = model.predict(codes * lsb) / q
    twin_err = float(np.max(np.abs(out - ref)[inside]))
    bound = float(spec.analysis["bound_total_lsb"])
    # the recording through the hardware: ADC code of each voltage, the twin's output
    v, x = rec.voltage_v, rec.displacement_mm
    rc = adc_codes(s, v)
    hw_mm = out[rc - s.code_min] * q
    err = hw_mm - x
    raw_err = raw_output_mm(v, x) - x
    limit = physical_limit_mm(model, v, lsb)
    return {"model": model, "spec": spec, "words": words, "codes": codes, "out": out, "sat": sat,
            "twin_err_lsb": twin_err, "bound_lsb": bound, "hw_err_mm": err, "raw_err_mm": raw_err,
            "limit_mm": limit, "rec": rec}


def polarity_warning(rec, fam: FamilySpec) -> str:
    """'' when the sensor's output rises with displacement as the design's sensor's does, else
    why not: the weights invert either slope, so a reversed output calibrates and measures
    right, but on a line that builds one kind of sensor it is a wiring fault (secondaries or
    the excitation swapped) that a replaced unit would not share."""
    m = fam.spec.model
    lo, hi = sorted(m.voltage_range_v)
    x_lo, x_hi = m.predict(np.array([lo, hi]))
    design_rises = bool(x_hi > x_lo)   # x(v) rises where v(x) does
    rises = float(np.polyfit(rec.displacement_mm, rec.voltage_v, 1)[0]) > 0
    if rises == design_rises:
        return ""
    return (f"the output {'rises' if rises else 'falls'} with displacement where the design's sensor's "
            f"{'rises' if design_rises else 'falls'}: a reversed output (secondaries or excitation swapped?); "
            "calibrated as it is")


def diagnosis_sample(rec, points: int | None) -> tuple[Recordings, str]:
    """The recording the diagnosis sees, and one sentence saying how it was reduced: at most
    about ``points`` means, as ``flann diagnose --max-points`` takes them
    (:func:`flann.diagnose.data.reduce_points`: a mean never spans a turn of direction; many
    short sweeps share their positions' means).  ``points`` None or 0, or a short recording:
    every row."""
    small, how = reduce_points(rec, points)
    return small, how or f"every one of the {len(rec)} points"


def _diagnosis(rec, sensor, points: int | None):
    """The diagnosis' findings as sentences (for the certificate), what it was run on, the
    effects it named and the sets of effects it could not tell apart."""
    small, basis = diagnosis_sample(rec, points)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            dg = diagnose(small, sensor=sensor)
        except FlannError as exc:
            return [f"diagnosis not possible: {exc}"], basis, (), ()
    # what every equally good explanation names is a finding; the rest is one of the sets
    found = [f"{e.name}: {e.explanation}" for e in dg.effects if e.name in dg.shared]
    found += list(dg.notes)
    if dg.outliers:
        found.append(f"{len(dg.outliers)} outlier point(s)")
    found += [f"warning: {w.message}" for w in caught]
    named = tuple(dg.shared)
    groups = tuple(tuple(g) for g in dg.explanations)
    return found, basis, named, groups


def diagnosis_cell(named, groups) -> str:
    """The summary's diagnosis column: the named effects, or the sets that fit equally."""
    if groups:  # sorted: the same sets read the same in every row (best first is in the JSON)
        return "confounded: " + " | ".join(sorted("+".join(sorted(g)) or "nothing" for g in groups))
    return "; ".join(named) or "none"


@lru_cache(maxsize=4)
def _sensor(toml: str):
    """The --sensor description, read once per process (a Sensor does not pickle)."""
    return load_sensor(toml)


def sensor_name(path, sensor_id: str | None = None) -> str:
    """The sensor's name and folder under OUTDIR: the recording's stem, and for one sensor of a
    file of several its ID (``<stem>_<ID>``), sanitised (never ``..``, a hidden name or a path;
    see :func:`flann.fileio.safe_name`)."""
    stem = Path(path).stem
    return safe_name(stem if sensor_id is None else f"{stem}_{sensor_id}")


@dataclass(frozen=True)
class Source:
    """One sensor of a batch: its recordings file and, in a file of several sensors (a sensor
    column), its ID."""

    path: Path
    sensor_id: str | None = None

    @property
    def name(self) -> str:
        return sensor_name(self.path, self.sensor_id)

    @property
    def recording(self) -> str:
        """The summary's recording cell: the file, and the ID read from it."""
        return str(self.path) if self.sensor_id is None else f"{self.path} (sensor {self.sensor_id})"


def batch_sources(paths) -> list[Source]:
    """Each file one sensor, a file whose sensor column holds several IDs that many, in the
    order the IDs first appear; a file that cannot be listed stays one source (its
    calibration says why)."""
    out = []
    for p in map(Path, paths):
        ids: list[str] = []
        if not special_file(p):
            try:
                ids = recording_sensors(p)
            except (FlannError, OSError):
                ids = []
        out += [Source(p, i) for i in ids] if len(ids) > 1 else [Source(p)]
    return out


def _start(path: Path, dhash: str, spec: ProductionSpec | None, max_error_mm: float | None,
           station: Station | None, sensor_id: str | None = None) -> tuple[Result, ProductionSpec, Station]:
    """A sensor's summary row, and the spec (``--max-error-mm`` alone when none is given) and
    station it is judged and recorded with."""
    src = Source(path, sensor_id)
    res = Result(sensor=src.name, recording=src.recording, design_sha256=dhash)
    if spec is None:
        spec = ProductionSpec(max_error_mm=max_error_mm, source="--max-error-mm" if max_error_mm else "")
    return res, spec, station or Station()


@contextmanager
def _concluded(res: Result, seen: dict, path: Path, out_dir, fam, dhash: str, spec: ProductionSpec,
               station: Station, sensor_id: str | None = None):
    """Around one sensor's calibration: its verdict becomes the row's status; bad input or the
    numerics of a pathological file reject it (``seen["rec"]``: the recording, once read)."""
    try:
        yield
    except FlannError as exc:
        _reject(res, str(exc), path, seen.get("rec"), out_dir, fam, dhash, spec, station, sensor_id)
        return
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        _reject(res, f"{exc.__class__.__name__}: {exc}", path, seen.get("rec"), out_dir, fam, dhash, spec, station,
                sensor_id)
        return
    if res.verdict.shipped:
        res.status, res.reason = "ok", ""
    else:
        res.fail("; ".join(r for r in res.verdict.reasons if not r.startswith("marginal")))


def calibrate_one(path, out_dir, fam: FamilySpec, dhash: str, sensor_toml=None,
                  max_error_mm: float | None = None, diagnosis_points: int | None = DIAGNOSIS_POINTS,
                  spec: ProductionSpec | None = None, station: Station | None = None,
                  own: OwnDesign | None = None, sensor_id: str | None = None) -> Result:
    """One recording -> OUTDIR/<sensor>/ (all files or none) and its summary row; a sensor
    that fails its spec or is rejected gets a certificate saying why and no weights.  ``own``:
    the batch's own-design structure for the reach judgement (None: chosen for this sensor);
    ``sensor_id``: the sensor of that ID in a file of several."""
    path = Path(path)
    res, spec, station = _start(path, dhash, spec, max_error_mm, station, sensor_id)
    seen: dict = {}
    with _concluded(res, seen, path, out_dir, fam, dhash, spec, station, sensor_id):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            rec = seen["rec"] = read_recordings(path, sensor=sensor_id)
            why = outside_input(fam, rec.voltage_v)
            if why:   # before the screen: readings beyond the converter are not glitches
                raise FitError(why)
            rec, said = ready_for_fit(rec)
            if said:   # the glitch is the reading's, not the sensor's: neither fitted nor judged
                warnings.warn(said)
            chk = check_sensor(rec, fam)
        res.warnings += [str(w.message) for w in caught]
        res.twin_vs_float_lsb = chk["twin_err_lsb"]
        res.max_error_mm = float(np.max(np.abs(chk["hw_err_mm"])))
        res.raw_max_error_mm = float(np.max(np.abs(chk["raw_err_mm"])))
        res.limit_mm = float(np.max(chk["limit_mm"]))
        res.ratio_to_limit = res.max_error_mm / res.limit_mm if res.limit_mm > 0 else math.inf
        if chk["twin_err_lsb"] > max(1.0, chk["bound_lsb"]):
            raise FlannError(f"twin differs from the float model by {chk['twin_err_lsb']:.3g} LSB, more than "
                             f"the bound {chk['bound_lsb']:.3g} LSB")
        res.trace = traceability(path, rec, station, sensor_id)
        res.model_sha256 = text_sha256(chk["model"].to_json())
        res.own_reach_mm, res.costs_accuracy = reach_flag(rec, fam, res.max_error_mm, own)
        if res.costs_accuracy:
            res.warnings.append(res.costs_accuracy)
        reversed_output = polarity_warning(rec, fam)
        if reversed_output:
            res.warnings.append(reversed_output)
        sensor = None if sensor_toml is None else _sensor(str(sensor_toml))
        findings, basis, named, groups = _diagnosis(rec, sensor, diagnosis_points)
        res.diagnosis = diagnosis_cell(named, groups)
        dxdv = chk["limit_mm"] / (0.5 * fam.spec.input_lsb_v)
        unc = uncertainty(rec, dxdv, fam.terms, fam.spec.output_lsb_mm)
        res.verdict = judge(spec, rec.displacement_mm, chk["hw_err_mm"], res.ratio_to_limit,
                            named, groups, unc.expanded_mm)
        extra = {"spec": spec, "verdict": res.verdict, "trace": res.trace, "uncertainty": unc,
                 "confounded": groups}
        _write_sensor(child(out_dir, res.sensor), res, chk, fam, dhash, findings, basis, extra)
    return res


def calibrate_one_thermal(path, out_dir, fam, dhash: str, sensor_toml=None, max_error_mm: float | None = None,
                          diagnosis_points: int | None = DIAGNOSIS_POINTS, spec: ProductionSpec | None = None,
                          station: Station | None = None, sensor_id: str | None = None) -> Result:
    """One multi-temperature recording for a family design with temperature (``fam`` its
    FamilyThermalSpec): the image, verdicts at each temperature and overall, the drift
    (``sensor_id``: :func:`calibrate_one`)."""
    path = Path(path)
    res, spec, station = _start(path, dhash, spec, max_error_mm, station, sensor_id)
    seen: dict = {}
    with _concluded(res, seen, path, out_dir, fam, dhash, spec, station, sensor_id):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            rec = seen["rec"] = read_recordings(path, sensor=sensor_id)
            if rec.temperature_c is None:
                raise FlannError(f"{path}: no temperature_c column; the design compensates temperature "
                                 f"({fam.orders} orders): calibrate at {fam.orders} or more temperatures")
            chk = check_sensor_thermal(rec, fam, ridge_ladder(fam.fam.ridge))
        res.warnings += [str(w.message) for w in caught]
        err, x = chk["hw_err_mm"], np.asarray(rec.displacement_mm, dtype=float)
        res.twin_vs_float_lsb = chk["twin_err_lsb"]
        res.max_error_mm = float(np.max(np.abs(err)))
        res.raw_max_error_mm = float(np.max(np.abs(chk["raw_err_mm"])))
        res.limit_mm = float(np.max(chk["limit_mm"]))
        res.ratio_to_limit = res.max_error_mm / res.limit_mm if res.limit_mm > 0 else math.inf
        res.drift_ppm_fs_per_c = chk["drift_ppm_fs_per_c"]
        if chk["twin_err_lsb"] > max(1.0, chk["bound_lsb"]):
            raise FlannError(f"twin differs from the float model by {chk['twin_err_lsb']:.3g} LSB, more than "
                             f"the bound {chk['bound_lsb']:.3g} LSB")
        res.trace = traceability(path, rec, station, sensor_id)
        res.model_sha256 = text_sha256(chk["model"].to_json())
        sensor = None if sensor_toml is None else _sensor(str(sensor_toml))
        findings, basis, named, groups = _diagnosis(rec, sensor, diagnosis_points)
        res.diagnosis = diagnosis_cell(named, groups)
        # per temperature: its uncertainty (noise of its own readings) and its verdict
        per, worst_u = [], None
        lsb = fam.input_lsb_v
        for g, temp in enumerate(chk["temperatures_c"]):
            rows = chk["labels"] == g
            sub = rec.subset(rows)
            lim = chk["limit_mm"][rows]
            u = uncertainty(sub, lim / (0.5 * lsb), fam.fam.terms, fam.output_lsb_mm)
            ratio = float(np.max(np.abs(err[rows])) / np.max(lim)) if np.max(lim) > 0 else math.inf
            per.append((temp, judge(spec, x[rows], err[rows], ratio, named, groups, u.expanded_mm), u))
            worst_u = u if worst_u is None or u.expanded_mm > worst_u.expanded_mm else worst_u
        res.verdict = judge(spec, x, err, res.ratio_to_limit, named, groups, worst_u.expanded_mm)
        extra = {"spec": spec, "verdict": res.verdict, "trace": res.trace, "uncertainty": worst_u,
                 "confounded": groups, "per_temperature": per}
        _write_sensor_thermal(child(out_dir, res.sensor), res, chk, fam, dhash, findings, basis, extra)
    return res


def _write_sensor_thermal(dest: Path, res: Result, chk: dict, fam, dhash: str, findings, basis: str,
                          extra: dict) -> None:
    """A passed sensor: its two-input model, its image (every order's memory in turn) and the
    certificate; a failed one: only the certificate."""
    model_json, mhash = chk["model"].to_json(), res.kept_model_sha256
    head = images.provenance_header(f"flann {__version__} calibrate", res.sensor, dhash, mhash, fam.image_words,
                                    f"address 0 first: order j's memory at j x {fam.fam.mem_depth} (cfg_addr)")
    html = render_certificate_thermal(res, chk, fam, dhash, mhash, findings, basis, **extra)
    with atomic_directory(dest, _is_sensor_output, "sensor calibration") as tmp:
        (tmp / "certificate.html").write_text(html, newline="")
        if res.verdict.shipped:
            (tmp / images.MODEL_FILE).write_text(model_json, newline="")
            (tmp / images.IMAGE_FILE).write_text(images.hex_text(chk["words"], head), newline="")
    res.written = True


def _reject(res: Result, reason: str, path: Path, rec, out_dir, fam, dhash, spec, station,
            sensor_id: str | None = None) -> None:
    """A sensor that could not be calibrated: FAIL with the reason, and a certificate that
    says so (when even that cannot be written, the summary row still does)."""
    res.fail(reason)
    res.verdict = rejected(spec, res.reason)
    # figures measured before the rejection describe no calibration the row stands for
    res.max_error_mm = res.limit_mm = res.ratio_to_limit = res.raw_max_error_mm = None
    res.twin_vs_float_lsb = res.drift_ppm_fs_per_c = None
    try:
        res.trace = traceability(path, rec, station, sensor_id)
    except FlannError:
        res.trace = traceability(path, None, replace(station, serial_column=""), sensor_id)
    try:
        sha = rec.sha256 if rec is not None else hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        sha = ""
    try:
        html = render_rejection(res, fam, dhash, spec, sha)
        with atomic_directory(child(out_dir, res.sensor), _is_sensor_output, "sensor calibration") as tmp:
            (tmp / "certificate.html").write_text(html, newline="")
        res.written = True
    except (FlannError, OSError) as exc:
        res.warnings.append(f"no certificate written: {exc}")


def _is_sensor_output(directory: Path) -> bool:
    return (directory / "certificate.html").is_file()


def _write_sensor(dest: Path, res: Result, chk: dict, fam: FamilySpec, dhash: str, findings, basis: str,
                  extra: dict) -> None:
    """A passed sensor: its model, weight images and certificate; a failed one: only the
    certificate (no weights a loader could pick up)."""
    model, words = chk["model"], chk["words"]
    model_json, mhash = model.to_json(), res.kept_model_sha256
    head = images.provenance_header(f"flann {__version__} calibrate", res.sensor, dhash, mhash, fam.mem_depth)
    html = render_certificate(res, chk, fam, dhash, mhash, findings, basis, **extra)
    with atomic_directory(dest, _is_sensor_output, "sensor calibration") as tmp:
        (tmp / "certificate.html").write_text(html, newline="")
        if res.verdict.shipped:
            (tmp / images.MODEL_FILE).write_text(model_json, newline="")
            (tmp / images.IMAGE_FILE).write_text(images.hex_text(words, head), newline="")
            (tmp / "weights.mem").write_text(images.mem_text(words, head), newline="")
            (tmp / "weights.bmm").write_text(images.bmm_text(fam, head), newline="")
    res.written = True


# ------------------------------------------------------------------------------------------
def _progress(done: int, total: int, failed: int, t0: float) -> None:
    width = 30
    k = int(width * done / max(1, total))
    rate = done / max(1e-9, time.monotonic() - t0) * 60
    sys.stderr.write(f"\r[{'#' * k}{'.' * (width - k)}] {done}/{total} sensors, {failed} failed, "
                     f"{rate:.0f}/min")
    sys.stderr.flush()


def special_file(path: Path) -> str:
    """'' for a regular file or a missing one (the reader says so), else what it is."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return ""
    if stat.S_ISREG(mode):
        return ""
    return ("a FIFO (named pipe)" if stat.S_ISFIFO(mode) else "a directory" if stat.S_ISDIR(mode)
            else "a character device" if stat.S_ISCHR(mode) else "a block device" if stat.S_ISBLK(mode)
            else "a socket" if stat.S_ISSOCK(mode) else "not a regular file")


def _calibrate_item(item, one=calibrate_one, **kw) -> Result:
    return one(item[1].path, sensor_id=item[1].sensor_id, **kw)


def calibrate_batch(paths, out_dir, design_dir, *, jobs: int | None = None, sensor_toml=None,
                    max_error_mm: float | None = None, progress: bool | None = None,
                    diagnosis_points: int | None = DIAGNOSIS_POINTS,
                    spec: ProductionSpec | None = None, station: Station | None = None) -> list[Result]:
    """Every sensor -> its folder and row; summary.csv last.  Never stops at a bad recording.
    A file whose sensor column holds several IDs is that many sensors (:func:`batch_sources`).

    Ctrl-C stops the batch promptly (:func:`flann.pool.run_batch`): the sensors already
    running finish, the rest are ``interrupted`` rows, summary.csv is written, and then
    KeyboardInterrupt goes on up (exit 130)."""
    design = as_design(design_dir)  # the manifest's own datapath, its fields checked
    dp = design.datapath
    if dp not in (FAMILY, FAMILY_THERMAL):
        raise FlannError(f"{design_dir}: a {dp.name} design; flann calibrate writes weight images "
                         "for a family design (flann gen --family)")
    fam = design.with_twin().spec
    if diagnosis_points is not None and diagnosis_points < 0:
        raise FlannError(f"--diagnosis-points {diagnosis_points}: must be >= 0 (0 = every point)")
    if sensor_toml is not None:  # a bad sensor file stops the batch before it starts
        _sensor(str(sensor_toml))
    dhash = design_hash(design_dir)
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise FlannError(f"{out_dir}: exists and is not a directory (OUTDIR)")
    if out_dir.resolve().is_relative_to(Path(design_dir).resolve()):
        # certificates inside the design would be deleted when it is generated again
        raise FlannError(f"-o {out_dir}: inside the design directory {design_dir}; write the calibration "
                         "beside the design, not into it")
    paths = [Path(p) for p in paths]
    if not paths:
        raise FlannError("no recordings given")
    summary = summary_path(out_dir).resolve()
    clobbered = next((p for p in paths if p.resolve() == summary), None)
    if clobbered is not None:   # refused before any sensor is calibrated, not when the summary is written
        raise FlannError(f"{clobbered}: is the batch summary this run writes ({SUMMARY} in -o {out_dir}); "
                         "move the recording or write the calibration elsewhere")
    if jobs is not None and jobs < 1:
        raise FlannError(f"-j {jobs}: must be >= 1")
    jobs = jobs or os.cpu_count() or 1
    if progress is None:
        progress = sys.stderr.isatty()
    if spec is None:
        spec = ProductionSpec(max_error_mm=max_error_mm, source="--max-error-mm" if max_error_mm else "")
    results: dict[int, Result] = {}
    seen: dict[str, int] = {}
    todo = []
    sources = batch_sources(paths)

    def refused(src: Source, why: str) -> Result:
        """A rejected row with the reason and no certificate: the batch goes on."""
        res = Result(sensor=src.name, recording=src.recording, design_sha256=dhash)
        res.fail(why)
        res.verdict = rejected(spec, res.reason)
        return res

    for i, src in enumerate(sources):
        name, p = src.name, src.path
        # these cannot have a folder of their own (it is the summary's name, or the folder of
        # an earlier recording, also on a file system that ignores case)
        clash = (f"sensor name {name!r} is the batch summary's file name; rename the recording"
                 if name.casefold() == SUMMARY else
                 f"sensor name {name!r} already used by {sources[seen[name.casefold()]].recording} (one "
                 "folder per name, letter case ignored); rename this recording"
                 if name.casefold() in seen else "")
        kind = special_file(p)
        if kind:   # opening a FIFO nobody writes would block its worker for good
            results[i] = refused(src, f"{p}: is {kind}; flann reads recordings from regular files")
        elif clash:
            results[i] = refused(src, clash)
        else:
            seen[name.casefold()] = i
            todo.append(i)
    t0 = time.monotonic()
    failed = sum(1 for r in results.values() if r.status != "ok")

    def record(item, res: Result) -> None:
        nonlocal failed
        results[item[0]] = res
        if not res.written:   # an earlier run's files must not outlive this run's verdict
            remove_output_directory(child(out_dir, res.sensor), _is_sensor_output)
        if res.status != "ok":
            failed += 1
        if progress:
            _progress(len(results), len(sources), failed, t0)

    if dp is FAMILY_THERMAL:
        one, extra = calibrate_one_thermal, {}
    else:   # the reach judgement's structure, chosen once for the batch
        one, extra = calibrate_one, {"own": first_own_design([sources[i] for i in todo], fam)}
    fn = partial(_calibrate_item, one=one, out_dir=out_dir, fam=fam, dhash=dhash, sensor_toml=sensor_toml,
                 max_error_mm=max_error_mm, diagnosis_points=diagnosis_points, spec=spec, station=station, **extra)
    stopped_by = run_batch(fn, [(i, sources[i]) for i in todo], jobs, record,
                           lambda item, why: record(item, refused(item[1], why)))
    if progress:
        sys.stderr.write("\n")
    for i in todo:
        if i not in results:
            # not calibrated by this run: an earlier run's certificate must not stand beside it
            remove_output_directory(child(out_dir, sources[i].name), _is_sensor_output)
            results[i] = Result(sensor=sources[i].name, recording=sources[i].recording, status="interrupted",
                                reason="not calibrated: the batch was interrupted "
                                       f"({'SIGTERM' if stopped_by == signal.SIGTERM else 'Ctrl-C'})")
    ordered = [results[i] for i in range(len(sources))]
    write_summary(summary_path(out_dir), ordered)
    if stopped_by == signal.SIGTERM:
        raise Terminated
    if stopped_by:
        raise KeyboardInterrupt
    return ordered


def summary_path(out_dir) -> Path:
    """OUTDIR/summary.csv, joined as a path (``-o out/`` must not print ``out//summary.csv``)."""
    return Path(out_dir) / SUMMARY


def write_summary(path, results) -> None:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=SUMMARY_FIELDS, lineterminator="\n")
    w.writeheader()
    for r in results:
        w.writerow(r.row())
    atomic_write_text(path, buf.getvalue())


__all__ = ["OwnDesign", "Source", "batch_sources", "sensor_name", "first_own_design", "own_design_for", "reach_flag", "calibrate_batch", "calibrate_one", "calibrate_one_thermal", "check_sensor", "train_for_design",
           "diagnosis_sample", "write_summary", "summary_path", "Result", "SUMMARY", "SUMMARY_FIELDS",
           "DIAGNOSIS_POINTS"]
