"""The family datapath's verification: its cocotb bench loads sensors' weight images through the
cfg port, two at least, one over the other (a load must be seen to change the outputs), and
compares every code with the twin; the sweep of its mapped netlist with an image loaded."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import FlannError
from ...verify import plots
from ...verify.images import checked_images, image_model, kept_images, loaded_image
from ...verify.netlist import top_sweep
from ...verify.plugin import Verification
from ...verify.results import SimResult, summary
from ...verify.runner import BenchResult, run_cocotb
from ..design import Design, as_design
from .images import check_image
from .spec import member_spec
from .twin import FlannFamilyTop


FAMILY_BENCH = "test_flann_family_top"  # flann gen --family designs (weights in memory)


def run_family_bench(design, images: list[dict], build_dir, *, seed: int = 1,
                     backend: str | None = None) -> BenchResult:
    """The family ``design`` (or the directory it names) with sensors' weight images ({name, hex}) loaded
    through its cfg_* port, each over every input code against that sensor's twin."""
    design = as_design(design)
    cfg = {"design": str(design.directory), "images": images}
    return run_cocotb(design.files, design.top, FAMILY_BENCH, Path(build_dir) / "family", cfg, name="family",
                      seed=seed, backend=backend)


def _two_images(design: Design, loaded: list, given: bool) -> list:
    """The family bench loads two images, the second over the first, so that a load is seen to
    change the outputs: one image given goes second, after an image the design keeps (one that
    differs from it where the design keeps one)."""
    if given and len(loaded) == 1:
        (image, words), = loaded
        kept = sorted(checked_images(design, kept_images(design), len(words)), key=lambda k: k[1] == words)
        if kept:
            # named by the design's folder: the summary shows it is the design's own, not one given
            im, first = kept[0]
            return [({**im, "name": f"{design.directory.name}/{im['name']}"}, first), *loaded]
    if len(loaded) < 2:
        held = f"got {len(loaded)} --image and the design keeps none" if given else f"the design keeps {len(loaded)}"
        raise FlannError(f"{design.directory}: the {design.datapath.name} bench loads two weight images through the "
                         f"cfg port, one over the other (a load must be seen to change the outputs); {held}: pass "
                         "--image A.hex --image B.hex (written by flann calibrate)")
    return loaded


def bench(design: Design, build_dir, *, seed=1, images=None, **_) -> SimResult:
    loaded = _two_images(design, checked_images(design, images or kept_images(design), design.spec.mem_depth),
                         bool(images))
    images = [im for im, _words in loaded]
    res = run_family_bench(design, images, build_dir, seed=seed)
    rec = res.records.get("family_every_code", {})
    curve = None
    if rec.get("outputs"):
        codes = np.asarray(rec["codes"], dtype=np.int64)
        ss = [plots.series(im["name"], codes, rec["outputs"][im["name"]],
                           FlannFamilyTop(design.spec, words).process(codes)[0])
              for im, words in loaded if len(rec["outputs"].get(im["name"], ())) == codes.size]
        curve = plots.curve([{"title": None, "series": ss}], ref=plots.TWIN, simulator="GHDL") if ss else None
    codes = len(rec.get("codes", [])) * len(rec.get("outputs", {}))
    benches = {"family": {"tests": res.tests, "failures": res.failures, "failed": res.failed_tests,
                          "seconds": round(res.seconds, 1)}}
    per_image = {im["name"]: _image_error_mm(design, im, words) for im, words in loaded}
    known = [e for e in per_image.values() if e is not None]
    s = summary(design, codes, rec.get("mismatches"), max(known) if known else None, benches,
                 res.ok and bool(rec), design.manifest["output_lsb_mm"])
    s["images"] = [im["name"] for im in images]
    # the HDL equals the twin (mismatches): the twin against the model each image was made from
    s["image_max_err_mm"] = {n: None if e is None else round(e, 6) for n, e in per_image.items()}
    s["sweep"] = {"engine": "ghdl", "backend": "ghdl", "shards": 1, "codes_per_s": None}
    return SimResult(s, curve, design.spec, bool(s["all_passed"]))


def _image_error_mm(design: Design, image: dict, words: list[int]) -> float | None:
    """max |twin - float model| (mm) over every input code of the design holding ``image``,
    against the model it was made from (:func:`~flann.verify.images.image_model`; None when
    that is not known), as the fixed datapath's sweep measures it."""
    model = image_model(image)
    if model is None:
        return None
    fam = design.spec
    codes = np.arange(fam.spec.code_min, fam.spec.code_max + 1, dtype=np.int64)
    out = FlannFamilyTop(fam, words).process(codes)[0]
    ref = member_spec(fam, model).float_reference(codes)
    return float(np.max(np.abs(out * fam.spec.output_lsb_mm - ref)))


def netlist(design: Design, image=None):
    words = loaded_image(design, design.spec.mem_depth, image)
    return top_sweep(design, FlannFamilyTop(design.spec, words).process, image=tuple(words),
                     cfg_addr_bits=design.spec.addr_bits)


VERIFICATION = Verification(bench=bench, netlist=netlist, loads_images=True, check_words=check_image)

__all__ = ["VERIFICATION", "bench", "netlist", "run_family_bench"]
