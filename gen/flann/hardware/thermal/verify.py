"""The two-input (thermal) datapath's verification: the sweep harness with a temperature loop
over every voltage code at the temperature codes :func:`temperature_codes` chooses, under GHDL;
or (engine verilator, auto when GHDL would take more than about a minute) GHDL's synthesised
netlist compiled by Verilator over every sample, with the VHDL under GHDL on a sample of it.
One choice of temperature codes for every sweep of the design (RTL, netlist, ``flann trace``)."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from ...verify import plots
from ...verify.benches import BENCH_DIR
from ...verify.netlist import check_rtl_netlist, compare, top_sweep
from ...verify.plugin import Verification
from ...verify.results import SimResult, bench_entry, summary, sweep_about, sweep_rows, temperature_fields
from ...verify.runner import backend_for, choose_engine, sweep_temperatures
from ..design import Design
from .twin import FlannThermalTop

# a two-input sweep over every voltage code at every temperature code up to this many samples;
# above it, every voltage code at THERMAL_TEMPS temperature codes (both ends of the code range,
# both ends of the calibrated range, evenly spaced codes between)
THERMAL_MAX_SAMPLES = 2_000_000
THERMAL_TEMPS = 17
# the mapped netlist: every temperature code while a sweep stays below this many samples (it
# runs some thousands of samples a second on a core); above it, the RTL sweep's spread of codes
NETLIST_MAX_SAMPLES = 150_000
# the VHDL sample beside the compiled netlist: a window of voltage codes across the upper clamp
# code at the ends and the middle of the temperature codes
VHDL_SAMPLE_CODES = 64


def temperature_codes(spec, max_samples: int = THERMAL_MAX_SAMPLES) -> tuple[list[int], bool]:
    """(temperature codes the sweep runs, every code?)."""
    every = list(range(spec.temp_code_min, spec.temp_code_max + 1))
    if len(every) * (spec.code_max - spec.code_min + 1) <= max_samples:
        return every, True
    inner = np.linspace(spec.temp_lo, spec.temp_hi, THERMAL_TEMPS - 2).round().astype(int).tolist()
    return sorted({spec.temp_code_min, spec.temp_code_max, *inner}), False


def bench(design: Design, build_dir, *, seed=1, codes=None, engine="auto", progress=None, **_) -> SimResult:
    """``codes``: (lo, hi), a narrower voltage code range than every code (tests of wide inputs).
    Every sample through the VHDL under GHDL, or (engine verilator; auto when GHDL would take more
    than about a minute) through GHDL's synthesised netlist compiled by Verilator, with the VHDL
    under GHDL on a sample of it."""
    spec = design.spec
    temps, every = temperature_codes(spec)
    code_lo, code_hi = (spec.code_min, spec.code_max) if codes is None else codes
    samples = len(temps) * (code_hi - code_lo + 1)
    build_dir = Path(build_dir).resolve()
    build_dir.mkdir(parents=True, exist_ok=True)
    if codes is None and choose_engine(design, engine, samples) == "verilator":
        return _thermal_netlist(design, build_dir, temps, every, seed=seed, progress=progress)
    res, rec, backend, out_file = _thermal_vhdl(design, build_dir, temps, (code_lo, code_hi), seed=seed,
                                                progress=progress)
    benches = {"thermal_sweep": bench_entry(res)}
    lsb = spec.output_lsb_mm
    err = rec.get("max_err_lsb")
    s = summary(design, rec.get("samples", 0), rec.get("mismatches"), None if err is None else err * lsb,
                 benches, res.ok and bool(rec), lsb)
    s["sweep"] = sweep_about(backend, res, samples=samples)
    temperature_fields(s, temps, every, code_hi - code_lo + 1)
    got = sweep_rows(out_file, samples)
    curve = None if got is None else _thermal_curve(design, *got[:3], *_against_model(spec, *got), temps,
                                                    f"GHDL, {backend}")
    return SimResult(s, curve, spec, bool(s["all_passed"]), error_bound_lsb(design))


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


def _thermal_netlist(design: Design, build_dir: Path, temps, every: bool, *, seed=1, progress=None) -> SimResult:
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
    benches = {"thermal_sweep": bench_entry(res)}
    ok = res.ok and bool(rec) and not rec.get("mismatches") and judged.codes_tested > 0
    s = summary(design, judged.codes_tested, judged.mismatches, err, benches, ok, lsb)
    s["sweep"] = {"engine": "verilator", "netlist": "ghdl --synth --out=verilog (repaired), Verilator",
                  "shards": nl["shards"], "seconds": round(nl["seconds"], 1),
                  "build_seconds": round(nl["build_seconds"], 1),
                  "codes_per_s": round(c.size / nl["seconds"], 1) if nl["seconds"] else None,
                  "vhdl_sample": {"codes": int(rec.get("samples", 0)), "backend": f"ghdl-{backend}",
                                  "bench_ok": res.ok, "mismatches": rec.get("mismatches")}}
    temperature_fields(s, temps, every, spec.code_max - spec.code_min + 1)
    curve = _thermal_curve(design, c, t, out, ref, inside, temps, "Verilator, GHDL's synthesised netlist")
    return SimResult(s, curve, spec, bool(s["all_passed"]), error_bound_lsb(design))


def _against_model(spec, c, t, out, sat):
    """(the float model in output LSBs, the samples judged against it): a saturated output is
    left out where the model itself lies beyond the output's range, as the sweep bench judges."""
    ref = spec.float_reference(c, t) / spec.output_lsb_mm
    return ref, ~(sat & (np.abs(ref) > spec.out_fmt.max_int))


def error_bound_lsb(design: Design) -> float:
    """The design's stated bound on |HDL - float model| (output LSBs): the error before the
    output rounding, and the rounding."""
    return design.manifest["analysis"]["pre_rounding_lsb"] + 0.5


def _thermal_curve(design: Design, c, t, out, ref, valid, temps, simulator: str):
    spec = design.spec
    bound = error_bound_lsb(design)
    return plots.two_input([{"name": "", "codes": c, "temps": t, "hdl": out, "ref": ref, "valid": valid}],
                           temps, spec.temp_lsb_c, ref=plots.GOLDEN, simulator=simulator,
                           bound={"value": bound, "label": f"±{bound:.3g} LSB (the design's error bound)"},
                           calibrated=(spec.temp_lo, spec.temp_hi))


def netlist(design: Design, image=None):
    spec = design.spec
    temps, _ = temperature_codes(spec, NETLIST_MAX_SAMPLES)
    return top_sweep(design, FlannThermalTop(spec).process, temps=tuple(temps), temp_bits=spec.temp_bits)


VERIFICATION = Verification(bench=bench, netlist=netlist, engines=("ghdl", "verilator"))

__all__ = ["VERIFICATION", "bench", "netlist", "temperature_codes", "THERMAL_MAX_SAMPLES", "THERMAL_TEMPS"]
