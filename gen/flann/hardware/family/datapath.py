"""The family datapath (``flann gen --family``: weights in a memory) behind the :class:`Datapath` interface."""

from __future__ import annotations

import warnings

from ...errors import FlannError, SpecError
from ...golden.model import load_model
from ..datapath import NUMBER, Datapath, Field, _int, _num
from ..fixed.datapath import DATAPATH as FIXED
from ..options import GenOptions
from . import render
from .build import DEFAULT_TERMS, generate_family
from .spec import DEFAULT_MARGIN, check_against, family_from_dict, member_spec
from .twin import FlannFamilyTop


def generate(sources, out_dir, options: GenOptions | None = None, *, terms: int | str = DEFAULT_TERMS,
             margin: float = DEFAULT_MARGIN) -> dict:
    return generate_family(sources, out_dir, terms=terms, margin=margin, **(options or GenOptions()).to_kwargs())


def rebuild(model, man: dict, where="design"):
    """The FamilySpec of the manifest's ``family`` entry with the memory's initial model."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fam = family_from_dict(man["family"], load_model(model))
        check_against(fam, man)
        return fam, {}
    except SpecError as exc:
        raise FlannError(f"{where}: {exc}") from None


def eval_spec(model, man: dict, directory):
    """``model`` (any sensor of the family) as the design computes it with that sensor's
    weight image loaded; FitError (one line) when it is outside the family."""
    fam, _ = rebuild(DATAPATH.model_path(directory, man), man, directory)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return member_spec(fam, load_model(model))
    except SpecError as exc:
        raise FlannError(f"{model}: does not fit the family design {directory}: {exc}") from None


def estimate(man: dict) -> dict:
    return dict(man["analysis"]["estimate"])


def summary(man: dict) -> list[str]:
    fam = man["family"]
    mem = fam["memory"]
    ridge = f", ridge {fam['ridge']:g}" if "ridge" in fam else ""
    return [f"  family of {len(fam['members'])} sensor(s), margin {fam['margin']:g}, {fam['terms']} terms{ridge}",
            f"  {man['input_bits']}-bit input x {man['input_lsb_v']} V -> {man['output_bits']}-bit output x "
            f"{man['output_lsb_mm']} mm; {man['cycles_per_sample']} cycles/sample",
            f"  weight memory {mem['used_words']} of {mem['depth']} x {mem['data_bits']}-bit words "
            f"(cfg_addr {mem['addr_bits']} bits); estimate {man['analysis']['estimate']}",
            *choice_lines(man)]


def choice_lines(man: dict) -> list[str]:
    """One line per member of ``--terms auto``: its own design against its share of the family's."""
    terms = man["family"]["terms"]

    def held(c, who):
        rms, top = c[f"{who}_rms_mm"], c.get(f"{who}_max_mm")
        return f"held-out RMS {rms:.4g} mm" + ("" if top is None else f", max {top:.4g} mm")

    def ratio(c):
        said = f"{c['family_rms_mm'] / c['own_rms_mm']:.2f}x"
        if c.get("own_max_mm") and c.get("family_max_mm") is not None:
            said += f", {c['family_max_mm'] / c['own_max_mm']:.2f}x"
        return said
    return [f"  {c['name']}: own design {c['own_terms']} terms ({held(c, 'own')}"
            + (f", {c['own_cost']:.0f} LUT4-eq." if c["own_cost"] is not None else "")
            + f"); in the family {terms} terms, {held(c, 'family')} ({ratio(c)} its own)"
            for c in man.get("terms_chosen", [])]


FIELDS = (
    _num("output_lsb_mm", 0), Field("family", (dict,)), _num("family.margin", 0),
    Field("family.members", (list,)), Field("family.options", (dict,)), _int("family.terms", 2),
    Field("family.ridge", NUMBER, 0, optional=True),
    Field("family.widths", (dict,)),
    *(_int(f"family.widths.{k}") for k in ("weight_bits", "lin_width", "lin_bits", "product_bits", "acc_bits")),
    Field("images", (list,), optional=True), Field("family.memory", (dict,)), _int("family.memory.depth"), _int("family.memory.addr_bits"),
    _int("family.memory.data_bits"), _int("family.memory.used_words"),
    _int("analysis.estimate.luts", 0), _int("analysis.estimate.ffs", 0), _int("analysis.estimate.brams", 0),
)

DATAPATH = Datapath(
    name=render.DATAPATH, top=render.TOP, about="one design for a family of sensors, weights in a memory",
    generate=generate, rebuild=rebuild, twin=FlannFamilyTop, estimate=estimate, fields=FIELDS,
    lacks="flann explore sizes one sensor's design from its model; a family design is sized by "
          "its members (flann gen --family): explore one of them, e.g. DIR/init_model.json",
    summary=summary, eval_spec=eval_spec,
    number_format=FIXED.number_format,  # the fixed blocks, weights from a memory
)

__all__ = ["DATAPATH"]
