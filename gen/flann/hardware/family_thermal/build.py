"""``flann gen --family`` on recordings at several temperatures (or two-input models).

A recordings CSV whose ``temperature_c`` column holds 2 or more temperatures makes the family
a temperature-compensated one (:func:`is_thermal_family`); each is trained here with the
design's temperature normalisation (:func:`fit_sensor`, also used by ``flann calibrate``).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ...errors import FlannError, SpecError
from ...golden.family import DEFAULT_RIDGE, family_thermal_terms
from ...golden.model import text_sha256
from ...golden.thermal import FORMAT, ThermalModel, load_any_model, temperature_groups
from ...golden.thermal_train import fit_thermal
from ...recordings import prepare_for_fit, read_recordings
from ..family.build import FIXED_TERMS, NORMALISATION, check_terms, member_names, read_csvs
from ..family.spec import DEFAULT_MARGIN
from ..options import default
from .render import write
from .spec import DEFAULT_ORDERS, TempNorm, derive_family_thermal, temp_norm

# terms per temperature order: chosen for the worst member like a plain family's
# (golden/family.family_thermal_terms); FIXED_TERMS when no member is a recording
DEFAULT_TERMS = "auto"
MIN_ROWS = 4   # readings per temperature for it to count as a calibration temperature


def calibration_temperatures(rec) -> np.ndarray:
    """The temperatures (degC) a recording holds at least MIN_ROWS readings at."""
    if rec.temperature_c is None:
        return np.zeros(0)
    levels, labels = temperature_groups(rec.temperature_c)
    return np.asarray([t for g, t in enumerate(levels) if np.count_nonzero(labels == g) >= MIN_ROWS])


def is_thermal_family(sources) -> bool:
    """A member is a two-input model or a recording at 2 or more temperatures."""
    for p in sources:
        p = Path(p)
        try:
            if p.suffix.lower() == ".json" and isinstance(load_any_model(p), ThermalModel):
                return True
            if p.suffix.lower() == ".csv" and calibration_temperatures(read_recordings(p)).size >= 2:
                return True
        except FlannError:
            continue  # reported when the members are loaded
    return False


def _prepared(rec):
    """(v, T, x): the fit's checks (span, duplicates, fold-back) at each temperature on its own."""
    levels, labels = temperature_groups(rec.temperature_c)
    parts = [prepare_for_fit(rec.subset(labels == g), can_trim=False) for g in range(levels.size)
             if np.count_nonzero(labels == g) >= MIN_ROWS]
    cat = np.concatenate
    return (cat([p.voltage_v for p in parts]), cat([p.temperature_c for p in parts]),
            cat([p.displacement_mm for p in parts]))


def fit_sensor(rec, temp: TempNorm, terms: int, orders: int, ridge: float = DEFAULT_RIDGE,
               training: dict | None = None) -> ThermalModel:
    """x = sum_j t_n^j f_j(v) by least squares on every reading, t_n the design's."""
    temps = calibration_temperatures(rec)
    if temps.size < orders:
        raise FlannError(f"{rec.source}: recordings at {temps.size} temperature(s) "
                         f"({', '.join(f'{t:g}' for t in temps) or 'no temperature_c column'}); the design's "
                         f"{orders} temperature orders need {orders} or more (4 or more readings each)")
    v, t, x = _prepared(rec)
    return fit_thermal(v, t, x, (terms,) * orders, norm=NORMALISATION, ridge=ridge, correct_input=False,
                       temperature_norm=(temp.offset_c, temp.scale_c),
                       training={"form": "x = sum_j t_n^j f_j(v) (flann gen --family, temperature)",
                                 "temperatures_c": [float(round(a, 6)) for a in temps],
                                 "data_file": Path(rec.source).name, "data_sha256": rec.sha256, **(training or {})})


def auto_terms(sources, temp: TempNorm, orders: int, margin: float, read: dict | None = None):
    """(terms, ridge, [(index in ``sources``, its choice)]) for the recordings among ``sources``
    (``read``: their :func:`~flann.hardware.family.build.read_csvs`;
    :func:`flann.golden.family.family_thermal_terms`); (None, the default ridge, []) when none
    is one."""
    members, where = [], []
    for k, rec in (read_csvs(sources) if read is None else read).items():
        try:
            if calibration_temperatures(rec).size < orders:
                continue   # reported with every other bad member when the members are loaded
            members.append((Path(sources[k]).stem, *_prepared(rec)))
            where.append(k)
        except FlannError:
            continue
    if not members:
        return None, DEFAULT_RIDGE, []
    terms, ridge, choices = family_thermal_terms(members, orders=orders,
                                                 temperature_norm=(temp.offset_c, temp.scale_c),
                                                 norm=NORMALISATION, margin=margin)
    return terms, ridge, list(zip(where, choices))


def _range_of(sources, read: dict) -> tuple[float, float]:
    """The calibrated temperature range: every member's temperatures (``read``: the CSVs')."""
    lo, hi = np.inf, -np.inf
    for k, p in enumerate(sources):
        p = Path(p)
        try:
            if p.suffix.lower() == ".csv":
                if k not in read:
                    continue   # does not read: reported when the members are loaded
                t = calibration_temperatures(read[k])
            elif p.suffix.lower() == ".json":
                m = load_any_model(p)
                t = np.asarray(m.temperature_range_c if isinstance(m, ThermalModel) else [])
            else:
                continue
        except FlannError:
            continue
        if t.size:
            lo, hi = min(lo, float(t.min())), max(hi, float(t.max()))
    if not lo < hi:
        raise FlannError("--family with temperature: the members hold no two calibration temperatures")
    return lo, hi


def load_member(path, temp: TempNorm, terms: int, orders: int,
                training: dict | None = None, rec=None, ridge: float = DEFAULT_RIDGE) -> tuple[ThermalModel, str]:
    """(model, model file text): a two-input model.json as it is, or a recordings CSV
    (``rec``: already read) trained at ``ridge``."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        m = load_any_model(path)
        if not isinstance(m, ThermalModel):
            raise FlannError(f"{path}: a one-input model; a family with temperature takes two-input models "
                             f"({FORMAT}) or recordings at several temperatures")
        return m, path.read_bytes().decode("utf-8")
    if path.suffix.lower() == ".csv":
        m = fit_sensor(read_recordings(path) if rec is None else rec, temp, terms, orders, ridge, training=training)
        return m, m.to_json()
    raise FlannError(f"{path}: a family member is a recordings .csv or a model .json")


def generate_family_thermal(sources, out_dir, *, terms=DEFAULT_TERMS, margin: float = DEFAULT_MARGIN,
                            orders: int = DEFAULT_ORDERS, temp_bits: int = default("temp_bits"),
                            temp_lsb_c: float = default("temp_lsb_c"),
                            **options) -> dict:
    """Size one design for every source and write it (nothing written if any step fails)."""
    if not sources:
        raise FlannError("--family needs at least one recordings CSV or model.json")
    if terms != "auto":
        check_terms(terms)
    read = read_csvs(sources)
    try:
        temp = temp_norm(_range_of(sources, read), temp_bits, temp_lsb_c)
    except SpecError as exc:
        raise FlannError(str(exc)) from None
    choices, ridge = [], DEFAULT_RIDGE
    if terms == "auto":
        terms, ridge, choices = auto_terms(sources, temp, orders, margin, read)
        terms = FIXED_TERMS if terms is None else terms
    terms = int(terms)
    # each trained member's model records what sharing the count costs it
    chosen = {k: {"terms_chosen_by": "flann gen --family --terms auto", "own_terms": c.own_terms,
                  "own_cv_rms_error_mm": c.own_rms_mm, "family_terms": terms,
                  "family_cv_rms_error_mm": c.family_rms_mm} for k, c in choices}
    loaded, bad = [], []
    for k, p in enumerate(sources):
        try:
            loaded.append(load_member(p, temp, terms, orders, chosen.get(k), read.get(k), ridge))
        except FlannError as exc:
            bad.append(str(exc))
    if bad:
        raise FlannError(f"{len(bad)} of {len(sources)} family members cannot be used (nothing written): "
                         + "; ".join(bad))
    names = member_names(sources)
    models = [m for m, _ in loaded]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            spec = derive_family_thermal(models, temp, names=names, margin=margin, ridge=ridge, **options)
        except SpecError as exc:
            raise FlannError(f"--family: {exc}") from None
    init_text = loaded[0][1]
    sha = text_sha256(init_text)
    man = write(spec, out_dir, init_text, sha, init_name=names[0], members=dict(zip(names, models)))
    if choices:
        man = {**man, "terms_chosen": [vars(c) for _p, c in choices]}
    return man


__all__ = ["generate_family_thermal", "fit_sensor", "auto_terms", "DEFAULT_TERMS", "is_thermal_family",
           "calibration_temperatures", "MIN_ROWS"]
