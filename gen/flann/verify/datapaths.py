"""``flann sim DIR`` for every datapath: the datapath names its bench, this runs it.

One entry per bench a :class:`~flann.hardware.datapath.Datapath` may name (``bench``): the
fixed datapath's sweep harness and benches (:func:`flann.verify.runner.simulate`), the float18
top-level bench, the family bench (sensors' weight images through the cfg port).  A datapath
without a bench is refused in one line saying why.  Every entry returns {"summary", "curve", "spec"}.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from ..errors import FlannError
from ..numeric.float18 import FLOAT18
from ..hardware.family.spec import member_spec
from ..hardware.family.twin import FlannFamilyTop
from ..hardware.family_thermal.twin import FlannFamilyThermalTop
from . import plots
from ..hardware.design import Design
from .float18 import run_design
from .benches import BENCH_DIR
from .images import checked_image, image_model, kept_images
from .netlist import check_rtl_netlist, compare, netlist_summary, require_sweep_driver
from .temperatures import family_thermal_temperature_codes, thermal_temperature_codes
from .runner import backend_for, choose_engine, run_family_bench, simulate as simulate_fixed, sweep_temperatures, throughput


def _summary(design: Design, codes: int, mismatches, max_err_mm, benches: dict, ok: bool, lsb=None) -> dict:
    man = design.manifest
    return {"codes_tested": codes, "mismatches": mismatches,
            "max_err_lsb": round(max_err_mm / lsb, 4) if (lsb and max_err_mm is not None) else None,
            "max_err_mm": None if max_err_mm is None else round(float(max_err_mm), 6),
            "cycles_per_sample": man["cycles_per_sample"], **throughput(man["cycles_per_sample"]),
            "benches": benches, "all_passed": ok, "latency_cycles": man["latency_cycles"],
            "output_lsb_mm": lsb, "model_sha256": man.get("model_sha256", ""), "design": str(design.directory)}


def _float18(design: Design, build_dir, *, seed=1, **_) -> dict:
    r = run_design(design, Path(build_dir), seed=seed)
    codes = r["codes"]
    hdl_mm = FLOAT18.decode_array(r["out"])
    ref = design.spec.float_reference(codes)
    inside = ~r["sat"]
    err = float(np.abs(hdl_mm - ref)[inside].max()) if inside.any() else 0.0
    ok = not r["bench_failed"] and r["mismatches"] == 0 and r["latency"] == [design.manifest["latency_cycles"]]
    secs = r["seconds"]
    benches = {"float18_top": {"tests": 1, "failures": int(r["bench_failed"]), "failed": [],
                               "seconds": round(secs, 1)}}
    s = _summary(design, int(codes.size), r["mismatches"], err, benches, ok)
    s["sweep"] = {"engine": "ghdl", "backend": "ghdl", "shards": 1,
                  "codes_per_s": round(codes.size / secs, 1) if secs > 0 else None}
    # the float18 design states no error bound (its spec has no error analysis): no bound line
    curve = plots.curve([{"title": None, "series": [plots.series("", codes, hdl_mm, ref)]}],
                        ref=plots.GOLDEN, simulator="GHDL", unit_mm=True,
                        diff_label="HDL - golden (float18 states no error bound)")
    return {"summary": s, "curve": curve, "spec": design.spec}


def _images(design: Design, images, words: int) -> list[tuple[dict, list[int]]]:
    """The weight images a family bench loads, ({name, hex}, words) each: those given (--image),
    else the ones flann gen kept in the design; each checked by :func:`~flann.verify.images.checked_image`, so a bad file is
    one line before the simulation, not a failed bench after it."""
    images = list(images or kept_images(design))
    return [checked_image(design, im, words) for im in images]


def _two_images(design: Design, loaded: list, given: bool) -> list:
    """The family bench loads two images, the second over the first, so that a load is seen to
    change the outputs: one image given goes second, after an image the design keeps (one that
    differs from it where the design keeps one)."""
    if given and len(loaded) == 1:
        (image, words), = loaded
        kept = sorted(_images(design, kept_images(design), len(words)), key=lambda k: k[1] == words)
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


def _family(design: Design, build_dir, *, seed=1, images=None, **_) -> dict:
    loaded = _two_images(design, _images(design, images, design.spec.mem_depth), bool(images))
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
    s = _summary(design, codes, rec.get("mismatches"), max(known) if known else None, benches,
                 res.ok and bool(rec), design.manifest["output_lsb_mm"])
    s["images"] = [im["name"] for im in images]
    # the HDL equals the twin (mismatches): the twin against the model each image was made from
    s["image_max_err_mm"] = {n: None if e is None else round(e, 6) for n, e in per_image.items()}
    s["sweep"] = {"engine": "ghdl", "backend": "ghdl", "shards": 1, "codes_per_s": None}
    return {"summary": s, "curve": curve, "spec": design.spec}


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


def _fixed(design: Design, build_dir, *, seed=1, engine="auto", progress=None, **_) -> dict:
    return simulate_fixed(design, build_dir, seed=seed, engine=engine, progress=progress)


def _thermal(design: Design, build_dir, *, seed=1, codes=None, engine="auto", progress=None, **_) -> dict:
    """``codes``: (lo, hi), a narrower voltage code range than every code (tests of wide inputs).
    Every sample through the VHDL under GHDL, or (engine verilator; auto when GHDL would take more
    than about a minute) through GHDL's synthesised netlist compiled by Verilator, with the VHDL
    under GHDL on a sample of it."""
    spec = design.spec
    temps, every = thermal_temperature_codes(spec)
    code_lo, code_hi = (spec.code_min, spec.code_max) if codes is None else codes
    samples = len(temps) * (code_hi - code_lo + 1)
    build_dir = Path(build_dir).resolve()
    build_dir.mkdir(parents=True, exist_ok=True)
    if codes is None and choose_engine(design, engine, samples) == "verilator":
        return _thermal_netlist(design, build_dir, temps, every, seed=seed, progress=progress)
    res, rec, backend, out_file = _thermal_vhdl(design, build_dir, temps, (code_lo, code_hi), seed=seed,
                                                progress=progress)
    benches = {"thermal_sweep": _bench_entry(res)}
    lsb = spec.output_lsb_mm
    err = rec.get("max_err_lsb")
    s = _summary(design, rec.get("samples", 0), rec.get("mismatches"), None if err is None else err * lsb,
                 benches, res.ok and bool(rec), lsb)
    s["sweep"] = _sweep_about(backend, res, samples=samples)
    _temperature_fields(s, temps, every, code_hi - code_lo + 1)
    got = _sweep_rows(out_file, samples)
    curve = None if got is None else _thermal_curve(design, *got[:3], *_against_model(spec, *got), temps,
                                                    f"GHDL, {backend}")
    return {"summary": s, "curve": curve, "spec": spec}


def _bench_entry(res) -> dict:
    return {"tests": res.tests, "failures": res.failures, "failed": res.failed_tests, "seconds": round(res.seconds, 1)}


def _temperature_fields(s: dict, temps, every: bool, voltage_codes: int) -> None:
    s["temperature_codes"] = "every" if every else temps
    s["temperature_codes_tested"] = len(temps)
    s["voltage_codes_tested"] = voltage_codes


def _thermal_vhdl(design: Design, build_dir: Path, temps, codes: tuple[int, int], *, seed=1, progress=None):
    """The thermal sweep harness under GHDL over voltage codes ``codes`` (lo, hi) at each of
    ``temps``: (bench result, its record, GHDL backend, the joined output file)."""
    spec, man = design.spec, design.manifest
    code_lo, code_hi = codes
    backend = backend_for(len(temps) * (code_hi - code_lo + 1) * man["cycles_per_sample"])
    out_file = build_dir / "thermal_sweep.txt"
    sweep = {"file": str(out_file), "code_lo": code_lo, "code_hi": code_hi}
    params = {"in_bits_g": spec.input_bits, "temp_bits_g": spec.temp_bits, "out_bits_g": spec.out_fmt.width,
              "code_lo_g": code_lo, "code_hi_g": code_hi}
    # the one sweep harness, with a temperature loop for a two-input design
    res = sweep_temperatures([*design.files, BENCH_DIR / "flann_sweep.vhd"], "test_thermal_sweep",
                             build_dir / "thermal_sweep", {"model": str(design.model), "manifest": dict(man),
                                                           "sweep": sweep},
                             params, temps, name="thermal_sweep", seed=seed, backend=backend,
                             progress=progress("sweep") if progress else None)
    return res, res.records.get("thermal_sweep", {}), backend, out_file


# the VHDL sample beside the compiled netlist: a window of voltage codes across the upper clamp
# code at the ends and the middle of the temperature codes
VHDL_SAMPLE_CODES = 64


def _thermal_netlist(design: Design, build_dir: Path, temps, every: bool, *, seed=1, progress=None) -> dict:
    spec, man = design.spec, design.manifest
    # the VHDL itself under GHDL on a sample, judged against the twin by its bench, run while
    # the netlist compiles
    hi_clamp = int(man["clamp_codes"][1])
    lo = max(spec.code_min, min(hi_clamp - VHDL_SAMPLE_CODES // 2, spec.code_max - VHDL_SAMPLE_CODES + 1))
    sample_temps = sorted({temps[0], temps[len(temps) // 2], temps[-1]})
    with ThreadPoolExecutor(1) as pool:
        vhdl = pool.submit(_thermal_vhdl, design, build_dir / "vhdl_sample", sample_temps,
                           (lo, min(spec.code_max, lo + VHDL_SAMPLE_CODES - 1)), seed=seed)
        nl = check_rtl_netlist(design, build_dir / "rtl_netlist",
                               progress=progress("sweep") if progress else None, temps=temps)
        res, rec, backend, _ = vhdl.result()
    judged = compare(nl["sweep"], nl)
    c, t, out = nl["codes"], nl["temps"], nl["data"]
    lsb = spec.output_lsb_mm
    ref, inside = _against_model(spec, c, t, out, nl["sat"])
    err = float(np.abs(out - ref)[inside].max()) * lsb if inside.any() else None
    benches = {"thermal_sweep": _bench_entry(res)}
    ok = res.ok and bool(rec) and not rec.get("mismatches") and judged["codes_tested"] > 0
    s = _summary(design, judged["codes_tested"], judged["mismatches"], err, benches, ok, lsb)
    s["sweep"] = {"engine": "verilator", "netlist": "ghdl --synth --out=verilog (repaired), Verilator",
                  "shards": nl["shards"], "seconds": round(nl["seconds"], 1),
                  "build_seconds": round(nl["build_seconds"], 1),
                  "codes_per_s": round(c.size / nl["seconds"], 1) if nl["seconds"] else None,
                  "vhdl_sample": {"codes": int(rec.get("samples", 0)), "backend": f"ghdl-{backend}",
                                  "bench_ok": res.ok, "mismatches": rec.get("mismatches")}}
    _temperature_fields(s, temps, every, spec.code_max - spec.code_min + 1)
    curve = _thermal_curve(design, c, t, out, ref, inside, temps, "Verilator, GHDL's synthesised netlist")
    return {"summary": s, "curve": curve, "spec": spec}


def _against_model(spec, c, t, out, sat):
    """(the float model in output LSBs, the samples judged against it): a saturated output is
    left out where the model itself lies beyond the output's range, as the sweep bench judges."""
    ref = spec.float_reference(c, t) / spec.output_lsb_mm
    return ref, ~(sat & (np.abs(ref) > spec.out_fmt.max_int))


def _thermal_curve(design: Design, c, t, out, ref, valid, temps, simulator: str):
    spec, man = design.spec, design.manifest
    bound = man["analysis"]["pre_rounding_lsb"] + 0.5
    return plots.two_input([{"name": "", "codes": c, "temps": t, "hdl": out, "ref": ref, "valid": valid}],
                           temps, spec.temp_lsb_c, ref=plots.GOLDEN, simulator=simulator,
                           bound={"value": bound, "label": f"±{bound:.3g} LSB (the design's error bound)"},
                           calibrated=(spec.temp_lo, spec.temp_hi))


def _sweep_about(backend: str, *runs, samples: int) -> dict:
    """The summary's ``sweep`` entry of two-input sweeps (one run per image, each of ``samples``)."""
    secs = sum(r.seconds for r in runs)
    return {"engine": "ghdl", "backend": f"ghdl-{backend}", "shards": max(r.shards for r in runs),
            "seconds": round(secs, 1), "codes_per_s": round(samples * len(runs) / secs, 1) if secs > 0 else None}


def _sweep_rows(path: Path, samples: int):
    """A two-input sweep's output file as (voltage codes, temperature codes, out, sat), or None
    when the harness did not write every sample (the bench has failed and says why)."""
    if not path.is_file():
        return None
    rows = np.loadtxt(path, dtype=np.int64, ndmin=2)
    if rows.shape != (samples, 5):
        return None
    return rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3].astype(bool)


def _family_thermal(design: Design, build_dir, *, seed=1, images=None, progress=None, **_) -> dict:
    """Each sensor's image given (--image), else the design's last member (not the memories'
    initial sensor, so the cfg port is what loads it), at every voltage code and the stated
    temperature codes: one run of the sweep harness per image."""
    spec, man = design.spec, design.manifest
    loaded = _images(design, images or kept_images(design)[-1:], spec.image_words)
    if not loaded:
        raise FlannError(f"{design.directory}: the {design.datapath.name} bench loads a sensor weight image through "
                         "the cfg port; the design holds none: pass --image A.hex (written by flann calibrate)")
    temps = family_thermal_temperature_codes(spec)
    build_dir = Path(build_dir).resolve()
    samples = len(temps) * (spec.code_max - spec.code_min + 1)
    backend = backend_for(samples * man["cycles_per_sample"])
    build_dir.mkdir(parents=True, exist_ok=True)
    bench = {"tests": 0, "failures": 0, "failed": [], "seconds": 0.0}
    total, mismatches, ok, per_image, groups, runs = 0, 0, True, {}, [], []
    for k, (image, words) in enumerate(loaded):
        tag = f"family_thermal_sweep_{k}" if len(loaded) > 1 else "family_thermal_sweep"
        out_file, image_file = build_dir / f"{tag}.txt", build_dir / f"{tag}_image.txt"
        image_file.write_text("".join(f"{a} {w >> 16} {w & 0xFFFF}\n" for a, w in enumerate(words)))
        sweep = {"file": str(out_file), "code_lo": spec.code_min, "code_hi": spec.code_max, "words": words}
        params = {"in_bits_g": spec.input_bits, "temp_bits_g": spec.temp_bits, "out_bits_g": spec.out_fmt.width,
                  "addr_bits_g": spec.cfg_addr_bits, "code_lo_g": spec.code_min, "code_hi_g": spec.code_max,
                  "image_file_g": str(image_file)}
        # the one sweep harness, its image loaded through the cfg port first
        res = sweep_temperatures([*design.files, BENCH_DIR / "flann_sweep.vhd"], "test_family_thermal_sweep",
                                 build_dir / tag, {"model": str(design.model), "manifest": dict(man), "sweep": sweep},
                                 params, temps, name="family_thermal_sweep", seed=seed, backend=backend,
                                 progress=progress(image["name"]) if progress else None)
        runs.append(res)
        rec = res.records.get("family_thermal_sweep", {})
        bench["tests"] += res.tests
        bench["failures"] += res.failures
        bench["failed"] += [f"{image['name']}: {t}" for t in res.failed_tests]
        bench["seconds"] = round(bench["seconds"] + res.seconds, 1)
        ok = ok and res.ok and bool(rec)
        total += rec.get("samples", 0)
        mismatches = None if mismatches is None or rec.get("mismatches") is None else mismatches + rec["mismatches"]
        per_image[image["name"]] = rec.get("mismatches")
        got = _sweep_rows(out_file, samples)
        if got is not None:
            c, t, out, _sat = got
            twin = FlannFamilyThermalTop(spec, words).process(c, t).out_data
            groups.append({"name": image["name"], "codes": c, "temps": t, "hdl": out, "ref": twin,
                           "valid": np.ones(c.size, dtype=bool)})
    s = _summary(design, total, mismatches, None, {"family_thermal_sweep": bench}, ok, spec.output_lsb_mm)
    s["images"] = [image["name"] for image, _ in loaded]
    s["image_mismatches"] = per_image
    s["temperature_codes"] = temps
    s["temperature_codes_tested"] = len(temps)
    s["voltage_codes_tested"] = spec.code_max - spec.code_min + 1
    s["sweep"] = _sweep_about(backend, *runs, samples=samples)
    curve = plots.two_input(groups, temps, spec.temp_lsb_c, ref=plots.TWIN, simulator=f"GHDL, {backend}",
                            calibrated=(spec.temp_lo, spec.temp_hi)) if groups else None
    return {"summary": s, "curve": curve, "spec": spec}


BENCHES = {"sweep": _fixed, "thermal_sweep": _thermal, "f18_top": _float18, "family": _family,
           "family_thermal": _family_thermal}
LOADS_IMAGES = (_family, _family_thermal)   # the benches that load weight images (--image)


def simulate(design: Design, build_dir, *, netlist: bool = False, **kw) -> dict:
    """Verify ``design`` with its datapath's bench (flann sim); with ``netlist``, then its mapped
    netlist over every code (the sweep of :data:`flann.verify.netlist.SWEEPS` it names)."""
    dp = design.datapath
    if dp.bench is None:
        raise FlannError(f"{design.directory}: {dp.why_no_bench}")
    if netlist:
        require_sweep_driver(dp, design.directory, "--netlist")
    if kw.get("engine") == "verilator" and BENCHES[dp.bench] not in (_fixed, _thermal):
        # GHDL's netlist compiled by Verilator stands in for the one-input and thermal sweep benches only
        raise FlannError(f"--engine verilator: replaces the fixed-point and thermal datapaths' VHDL sweep; {design.directory} "
                         f"holds a {dp.name} design (its bench runs under GHDL)")
    if kw.get("images") and BENCHES[dp.bench] not in LOADS_IMAGES:
        raise FlannError(f"--image: {design.directory} is a {dp.name} design, its weights are built in "
                         "(weight images load into a family design's memory)")
    res = BENCHES[dp.bench](design, build_dir, **kw)
    if netlist:
        s = res["summary"]
        # a family design's netlist computes with the last image given (--image), as its bench ends
        given = kw.get("images")
        s["netlist"], passed = netlist_summary(design, build_dir, kw.get("progress"),
                                               image=given[-1] if given else None)
        s["all_passed"] = s["all_passed"] and passed
    return res


__all__ = ["simulate", "BENCHES"]
