"""``flann gen --family REC_OR_MODEL...``: models of the family's sensors -> one design.

A recordings CSV is trained here (:func:`train_model`, the one training call of the family
flow, also used by ``flann calibrate``); a model.json is used as it is.
"""

from __future__ import annotations

import warnings
from pathlib import Path

from ...errors import FlannError
from ...golden.model import MAX_TERMS, FlannModel, load_model
from ...golden.family import DEFAULT_RIDGE, family_terms
from ...golden.forward import screens
from ...golden.screen import ready_for_fit
from ...golden.train import fit_lstsq
from ..fixed.cost import fixed_point_cost
from ..options import default
from ...recordings import prepare_for_fit, read_recordings
from ...fileio import safe_name
from .images import MODEL_FILE
from .render import write
from .spec import DEFAULT_MARGIN, derive_family

DEFAULT_TERMS = "auto"  # chosen for the worst member, like train --terms auto (FIXED_TERMS: no recordings)
MIN_TERMS = 2    # a family's weight memory holds the term v and at least one harmonic
FIXED_TERMS = 15  # a CSV's terms when --terms auto has no recordings to choose from, and calibrate's fallback
NORMALISATION = "half"  # v_n in [-0.5, 0.5]: the periodic terms need not join the two ends


def train_model(rec, terms: int = FIXED_TERMS, ridge: float = DEFAULT_RIDGE, training: dict | None = None) -> FlannModel:
    """Least-squares FLANN of ``terms`` terms on recordings ready for the fit
    (:func:`flann.golden.screen.ready_for_fit`: a glitch among repeats is the screen's)."""
    rec = prepare_for_fit(rec, can_trim=False, lone_glitches=screens(rec.displacement_mm))
    info = {"data_file": Path(rec.source).name, "data_sha256": rec.sha256, **(training or {})}
    return fit_lstsq(rec.voltage_v, rec.displacement_mm, terms, norm=NORMALISATION, ridge=ridge, training=info)


def read_csvs(sources) -> dict:
    """{place in ``sources``: Recordings} of every recordings CSV that reads, each read once
    (one that does not is read again, and reported, when the members are loaded)."""
    out = {}
    for k, p in enumerate(sources):
        if Path(p).suffix.lower() == ".csv":
            try:
                out[k] = read_recordings(p)
            except FlannError:
                continue
    return out


def ready_members(sources, read: dict) -> dict:
    """{place in ``sources``: the recordings ready for a fit} of the CSVs in ``read`` (their
    :func:`read_csvs`): validated and gross outliers left out, each with one warning line
    (:func:`flann.golden.screen.ready_for_fit`); one that is not ready is left out here and
    reported with every other bad member when the members are loaded."""
    out = {}
    for k, raw in read.items():
        try:
            rec, said = ready_for_fit(raw)
        except FlannError:
            continue
        if said:
            warnings.warn(said, stacklevel=2)
        out[k] = rec
    return out


def auto_terms(sources, options: dict, margin: float = DEFAULT_MARGIN, ready: dict | None = None):
    """(terms, ridge, per-member choices) for the recordings among ``sources`` (``ready``: their
    :func:`ready_members`), chosen like ``flann train --terms auto`` at the design's converter
    (:func:`flann.golden.family.family_terms`); (None, the default ridge, []) when every member
    is a model.json (their terms are used as they are)."""
    if ready is None:
        ready = ready_members(sources, read_csvs(sources))
    members = [(Path(sources[k]).stem, rec.voltage_v, rec.displacement_mm) for k, rec in ready.items()]
    if not members:
        return None, DEFAULT_RIDGE, []
    adc = (options.get("input_bits", default("input_bits")), options.get("input_lsb_v"))
    return family_terms(members, norm=NORMALISATION, margin=margin, cost=lambda m: fixed_point_cost(m, adc))


def load_member(path, terms: int = FIXED_TERMS, rec=None, ridge: float = DEFAULT_RIDGE) -> FlannModel:
    """A model.json as it is, or a recordings CSV (``rec``: already ready for the fit,
    :func:`ready_members`) trained with ``terms`` terms at ``ridge``."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        return load_model(path)
    if path.suffix.lower() == ".csv":
        return train_model(ready_for_fit(read_recordings(path))[0] if rec is None else rec, terms, ridge)
    raise FlannError(f"{path}: a family member is a recordings .csv or a model .json")


def check_terms(terms: int) -> None:
    """A family's term count (per temperature order with temperature): what a model file holds."""
    if not MIN_TERMS <= int(terms) <= MAX_TERMS:
        raise FlannError(f"--terms {terms}: must be {MIN_TERMS}..{MAX_TERMS}")


def generate_family(sources, out_dir, *, terms: int | str = DEFAULT_TERMS, margin: float = DEFAULT_MARGIN,
                    **options) -> dict:
    """Size one design for every source and write it (nothing written if any step fails)."""
    if not sources:
        raise FlannError("--family needs at least one recordings CSV or model.json")
    choices, ready, ridge = [], ready_members(sources, read_csvs(sources)), DEFAULT_RIDGE
    if terms == "auto":
        terms, ridge, choices = auto_terms(sources, options, margin, ready)
        terms = FIXED_TERMS if terms is None else max(MIN_TERMS, terms)
    check_terms(terms)
    models, bad = [], []
    for k, p in enumerate(sources):   # every member is tried: the user learns of all bad files at once
        try:
            models.append(load_member(p, terms, ready.get(k), ridge))
        except FlannError as exc:
            bad.append(str(exc))
    if bad:
        raise FlannError(f"{len(bad)} of {len(sources)} family members cannot be used "
                         "(nothing written): " + "; ".join(bad))
    names = member_names(sources)
    fam = derive_family(models, names=names, margin=margin, ridge=ridge, **options)
    man = write(fam, out_dir, fam.spec.model, init_name=names[0], members=dict(zip(names, models)))
    if choices:
        man = {**man, "terms_chosen": [vars(c) for c in choices]}
    return man


def member_names(sources) -> list[str]:
    """Each member's name as flann calibrate names the sensor (the file's stem, made safe for a
    file name); a model calibrate wrote by its sensor's folder; members of one name told apart
    by their place."""
    paths = [Path(p) for p in sources]
    names = [safe_name(p.parent.name if p.name == MODEL_FILE and p.parent.name else p.stem) for p in paths]
    if len(set(names)) < len(names):
        names = [f"{k + 1}_{n}" for k, n in enumerate(names)]
    return names


__all__ = ["check_terms", "member_names", "generate_family", "MIN_TERMS", "train_model", "load_member", "read_csvs", "DEFAULT_TERMS", "FIXED_TERMS", "NORMALISATION"]
