"""The family-with-temperature datapath's verification: the sweep harness with a temperature
loop, each sensor's weight image loaded through the cfg port first, every voltage code at the
temperature codes :func:`temperature_codes` chooses; the sweep of its mapped netlist."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import FlannError
from ...verify import plots
from ...verify.benches import BENCH_DIR
from ...verify.images import checked_images, kept_images, loaded_image
from ...verify.netlist import top_sweep
from ...verify.plugin import Verification
from ...verify.results import SimResult, summary, sweep_about, sweep_rows
from ...verify.runner import backend_for, sweep_temperatures
from ..design import Design
from ..family.images import check_image
from .twin import FlannFamilyThermalTop

# every voltage code at both ends of the temperature code range and this many codes evenly
# spaced over the calibrated range (its ends included)
FAMILY_THERMAL_TEMPS = 7


def temperature_codes(spec) -> list[int]:
    """The temperature codes the sweeps run: both ends of the code range (clamped),
    FAMILY_THERMAL_TEMPS evenly spaced codes over the calibrated range (its ends included)."""
    inner = np.linspace(spec.temp_lo, spec.temp_hi, FAMILY_THERMAL_TEMPS).round().astype(int).tolist()
    return sorted({spec.temp_code_min, spec.temp_code_max, *inner})


def bench(design: Design, build_dir, *, seed=1, images=None, progress=None, **_) -> SimResult:
    """Each sensor's image given (--image), else the design's last member (not the memories'
    initial sensor, so the cfg port is what loads it), at every voltage code and the stated
    temperature codes: one run of the sweep harness per image."""
    spec, man = design.spec, design.manifest
    loaded = checked_images(design, images or kept_images(design)[-1:], spec.image_words)
    if not loaded:
        raise FlannError(f"{design.directory}: the {design.datapath.name} bench loads a sensor weight image through "
                         "the cfg port; the design holds none: pass --image A.hex (written by flann calibrate)")
    temps = temperature_codes(spec)
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
        got = sweep_rows(out_file, samples)
        if got is not None:
            c, t, out, _sat = got
            twin = FlannFamilyThermalTop(spec, words).process(c, t).out_data
            groups.append({"name": image["name"], "codes": c, "temps": t, "hdl": out, "ref": twin,
                           "valid": np.ones(c.size, dtype=bool)})
    s = summary(design, total, mismatches, None, {"family_thermal_sweep": bench}, ok, spec.output_lsb_mm)
    s["images"] = [image["name"] for image, _ in loaded]
    s["image_mismatches"] = per_image
    s["temperature_codes"] = temps
    s["temperature_codes_tested"] = len(temps)
    s["voltage_codes_tested"] = spec.code_max - spec.code_min + 1
    s["sweep"] = sweep_about(backend, *runs, samples=samples)
    curve = plots.two_input(groups, temps, spec.temp_lsb_c, ref=plots.TWIN, simulator=f"GHDL, {backend}",
                            calibrated=(spec.temp_lo, spec.temp_hi)) if groups else None
    return SimResult(s, curve, spec, bool(s["all_passed"]))


def netlist(design: Design, image=None):
    spec = design.spec
    words = loaded_image(design, spec.image_words, image)
    return top_sweep(design, FlannFamilyThermalTop(spec, words).process, image=tuple(words),
                     cfg_addr_bits=spec.cfg_addr_bits, temps=tuple(temperature_codes(spec)), temp_bits=spec.temp_bits)


def check_words(spec, words: list[int], source) -> None:
    """Each temperature order's memory in turn, as the one-input family's image is checked."""
    depth = spec.fam.mem_depth
    for j in range(spec.orders):
        check_image(spec.fam, words[j * depth:(j + 1) * depth], f"{source} (temperature order {j})")


VERIFICATION = Verification(bench=bench, netlist=netlist, loads_images=True, check_words=check_words)

__all__ = ["VERIFICATION", "bench", "netlist", "temperature_codes", "FAMILY_THERMAL_TEMPS"]
