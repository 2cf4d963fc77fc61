"""A family design's weight images as the benches and the netlist sweep load them: the ones the
design keeps, and any image read and checked against the design before a slow step starts."""

from __future__ import annotations

from pathlib import Path

from ..errors import FlannError
from ..golden.model import FlannModel, load_model, text_sha256
from ..hardware.family.images import MODEL_FILE, header_fields, header_model_sha256, parse_hex
from ..hardware.family.render import design_hash
from ..inputs import read_text
from ..hardware.design import Design
from .plugin import verification


def checked_image(design: Design, image: dict, words: int) -> tuple[dict, list[int]]:
    """(image, its words) read and checked against the design before anything is simulated: hex
    words of the memory's width, as many as the design's image holds (``words``), and the design
    and word count its header names (a weight image flann calibrate wrote says both)."""
    text = read_text(image["hex"], FlannError, "a weight image (.hex)")
    got = parse_hex(text, image["hex"])
    named, stated = header_fields(text)
    if stated is not None and stated != len(got):
        raise FlannError(f"{image['hex']}: {len(got)} words, its header says {stated}: the image is cut "
                         "short or was edited; write it again with flann calibrate")
    if len(got) != words:
        raise FlannError(f"{image['hex']}: {len(got)} words, {design.directory}'s weight image is {words} words "
                         "(an image of another design?)")
    found = verification(design.datapath)
    if found is not None and found.check_words is not None:   # an image the hardware would wrap with
        found.check_words(design.with_twin().spec, got, image["hex"])
    if named is not None and named != (ours := design_hash(design.directory)):
        raise FlannError(f"{image['hex']}: calibrated for another design (design sha256 {named[:12]}..., "
                         f"{design.directory} is {ours[:12]}...): calibrate the sensor for this design "
                         "(flann calibrate --design DIR)")
    return image, got


def checked_images(design: Design, images, words: int) -> list[tuple[dict, list[int]]]:
    """Each of ``images`` read and checked (:func:`checked_image`): a bad file is one line before
    the simulation, not a failed bench after it."""
    return [checked_image(design, im, words) for im in images]


def loaded_image(design: Design, words: int, image: dict | None) -> list[int]:
    """The words a netlist sweep loads through the cfg port first: ``image`` ({name, hex}: one
    the user gave), else the last image the design keeps."""
    if image is not None:
        return checked_image(design, image, words)[1]
    kept = kept_images(design)
    if not kept:
        raise FlannError(f"{design.directory}: the netlist sweep loads a weight image through the cfg port and the "
                         "design keeps none (regenerate it with flann gen --family from the recordings)")
    return checked_image(design, kept[-1], words)[1]


def kept_images(design: Design) -> list[dict]:
    """The weight images flann gen kept in the design, as {name, hex path[, model path]}."""
    return [{"name": im["name"], "hex": str(design.directory / im["hex"]),
             **({"model": str(design.directory / im["model"])} if im.get("model") else {})}
            for im in design.manifest.get("images", [])]


def image_model(image: dict) -> FlannModel | None:
    """The float model an image was made from, or None when it cannot be told: the one the
    design keeps beside it, else the ``model.json`` flann calibrate wrote beside it when its
    sha256 is the one the image's header names (another file there is not the image's)."""
    if image.get("model"):
        return load_model(image["model"])
    beside = Path(image["hex"]).parent / MODEL_FILE
    if not beside.is_file():
        return None
    named = header_model_sha256(read_text(image["hex"], FlannError, "a weight image (.hex)"))
    text = read_text(beside, FlannError, "a model (.json)")
    return load_model(beside) if named is not None and named == text_sha256(text) else None


__all__ = ["checked_image", "checked_images", "loaded_image", "kept_images", "image_model"]
