"""The conditioner's verification (``flann sim DIR``): each block under GHDL and cocotb against
its twin (the converter port on every code, the NCO over every phase it visits, seeded random and
boundary cases for the demodulator, the rotation and the divider), then a waveform through the
whole chain (``flann_cond_top`` against :class:`~.twin.ConditionerChain`), 0 mismatches.  A
directory ``flann gen`` wrote from a model trained from waveforms also holds the FLANN behind the
conditioner and the chain joining them: the FLANN's own benches (every input code against its
twin; a two-input FLANN's at its temperature codes) run after the conditioner's, then a waveform
(and its temperature codes, one a strobe) through ``flann_chain_top`` against
:class:`~.chain.FlannChainTop` (the recording the model was trained from when the directory
keeps it, whole windows of it at a stride, at most ``CHAIN_SAMPLES`` strobes; else the
closed-form LVDT below), one summary for all.

The waveform is an LVDT's in closed form (the verify layer sits below the physics simulator):
the secondaries ``(1 +- u) / 2`` of the carrier at a phase off the table's steps, a quadrature
residual and noise, ``u`` stepped one position a window through the null and beyond the
stroke (the divider's saturation); the reference is calibrated on it as the hardware's is.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import asdict
from pathlib import Path

import numpy as np

from ...errors import FlannError
from ...golden.thermal import load_any_model
from ...recordings.waveform import read_waveforms
from ...verify.plugin import Verification, verification
from ...verify.results import SimResult, bench_entry, summary
from ...verify.runner import BenchResult, run_cocotb
from ..accuracy import temperature_codes
from ..design import Design
from ..manifest import MANIFEST, Manifest
from ..registry import check_widths
from .chain import CHAIN_TOP, ChainSpec, FlannChainTop
from .datapath import FLANN, flann_datapath
from .condition import adc_codes, calibrate_reference
from .settings import of_model
from .render import cycles_per_sample
from .spec import ConditionerSpec, Reference, identity
from .twin import ConditionerChain

# the chain's stimulus: one position a window, the phase of the secondaries against the
# excitation (rad, off the table's steps), quadrature and noise in fractions of full scale
POSITIONS = np.array([-1.3, -0.9, -0.5, -0.2, -0.05, 0.0, 0.05, 0.2, 0.5, 0.9, 1.3])
PHASE_RAD = 0.7
QUADRATURE = 0.05
NOISE = 2e-4
# block bench -> (entity, cocotb module in flann.verify.benches, its configuration from the spec)
BLOCKS = {
    "nco": ("flann_cond_nco", "cond_nco_bench",
            lambda s: dict(cycles=4 * s.samples_per_period + 200, p_en=0.6, entries=min(s.samples_per_period, 1 << s.table_bits))),
    "adc": ("flann_cond_adc", "cond_adc_bench", lambda s: {}),
    "demod": ("flann_cond_demod", "cond_demod_bench", lambda s: dict(windows=3)),
    "rotate": ("flann_cond_rotate", "cond_rotate_bench", lambda s: dict(cases=200)),
    "ratio": ("flann_cond_ratio", "cond_ratio_bench", lambda s: dict(pairs=300)),
}
TOP_BENCH = "cond_top_bench"
CHAIN_BENCH = "cond_chain_bench"
CHAIN_SAMPLES = 4096   # the whole-chain run's strobes at most: a few seconds under GHDL and cocotb


def run_block(files, spec: ConditionerSpec, entity: str, module: str, build_dir, *, seed: int = 1,
              **config) -> BenchResult:
    """The cocotb module ``module`` against ``entity`` built from ``files`` (every entity's: a
    top needs its blocks); the bench reads the spec and ``config``."""
    return run_cocotb(files, entity, module, build_dir, {"spec": spec.to_dict(), **config}, name=entity, seed=seed)


def lvdt_codes(spec: ConditionerSpec, seed: int = 1, positions=POSITIONS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(codes A, codes B, position per window) of the closed-form LVDT, straight binary."""
    rng = np.random.default_rng(seed)
    m, full = spec.window, (1 << (spec.adc_bits - 1)) - 1
    u = np.repeat(np.asarray(positions, dtype=float), m)
    theta = 2 * math.pi * np.arange(u.size) / spec.samples_per_period + PHASE_RAD
    carrier, quad = 0.45 * np.cos(theta), QUADRATURE * np.sin(theta)
    codes = []
    for sign in (1, -1):
        v = (1 + sign * u) * carrier + quad + NOISE * rng.standard_normal(u.size)
        codes.append(np.clip(np.round(v * full), -full - 1, full).astype(np.int64) + full + 1)
    return codes[0], codes[1], np.asarray(positions, dtype=float)


def run_chain(files, spec: ConditionerSpec, build_dir, *, seed: int = 1) -> tuple[BenchResult, int]:
    """The closed-form waveform through ``flann_cond_top``; (bench result, converter samples)."""
    a, b, x = lvdt_codes(spec, seed)
    ref, _phase = calibrate_reference(spec, ConditionerChain(spec).process(a, b, identity(spec)), x)
    res = run_block(files, spec, ConditionerChain.entity, TOP_BENCH, build_dir, seed=seed, codes_a=a.tolist(),
                    codes_b=b.tolist(), ref=asdict(ref), cycles_per_sample=cycles_per_sample(spec))
    return res, int(a.size)


def kept_waveform(design: Design, chain: ChainSpec):
    """(codes A, codes B, reference, what they are, temperature codes or None) of the training
    recording the directory keeps (its temperature column as the chain's two-input FLANN receives it):
    whole windows at a stride (each starts on a whole carrier period, so the NCO's phase runs on
    across the windows left out), at the model's reference turned by the record's excitation;
    None when it keeps none."""
    name = design.manifest.get("waveform")
    if name is None:
        return None
    model = load_any_model(design.directory / design.manifest["model"])
    settings = of_model(model, str(design.directory / design.manifest["model"]))
    path = design.directory / name
    sha = hashlib.sha256(path.read_bytes()).hexdigest() if path.is_file() else None
    if settings is None or sha != (model.training or {}).get("data_sha256"):
        raise FlannError(f"{path}: not the recording {design.manifest['model']} was trained from "
                         "(missing or edited): regenerate the design with flann gen")
    wave = read_waveforms(path, announce=False)
    ref = settings.reference_for(wave)
    spec = chain.conditioner
    windows = len(wave) // spec.window
    stride = -(-windows // max(1, CHAIN_SAMPLES // spec.window))   # at most CHAIN_SAMPLES, one window at least
    idx = (np.arange(windows)[::stride, None] * spec.window + np.arange(spec.window)).ravel()
    a = adc_codes(wave.sec_a_v, spec.adc_bits, settings.adc_range_v)[idx]
    b = adc_codes(wave.sec_b_v, spec.adc_bits, settings.adc_range_v)[idx]
    temps = None
    if chain.temp_bits:
        if wave.temperature_c is None:
            raise FlannError(f"{path}: no temperature_c column, but the FLANN behind the conditioner takes the "
                             "temperature: regenerate the design with flann gen")
        temps = temperature_codes(chain.flann, wave.temperature_c[idx])
    return a, b, ref, f"{name} (the training recording), one window in {stride}", temps


def swept_temperatures(flann_spec, n: int) -> np.ndarray:
    """A two-input FLANN's temperature codes for ``n`` strobes of the closed-form LVDT: a ramp
    one code apart from a few codes below its calibrated range to a few above (its clamp), so
    that the code at each window's last strobe differs from the window's others."""
    lo, hi = flann_spec.temp_lo - 4, flann_spec.temp_hi + 4
    ramp = lo + np.arange(n) % (hi - lo + 1)
    return np.clip(ramp, flann_spec.temp_code_min, flann_spec.temp_code_max)


def chain_stimulus(design: Design, chain: ChainSpec):
    """(codes A, codes B, reference, what they are, temperature codes or None) of the
    whole-chain run: the kept training recording, else the closed-form LVDT calibrated as the
    hardware is (a two-input FLANN's temperature swept over its codes)."""
    kept = kept_waveform(design, chain)
    if kept is not None:
        return kept
    spec = chain.conditioner
    a, b, x = lvdt_codes(spec)
    ref, _phase = calibrate_reference(spec, ConditionerChain(spec).process(a, b, identity(spec)), x)
    temps = swept_temperatures(chain.flann, a.size) if chain.temp_bits else None
    return a, b, ref, "the closed-form LVDT", temps


def run_chain_top(files, chain: ChainSpec, codes_a, codes_b, ref: Reference, build_dir, *,
                  seed: int = 1, temp_codes=None) -> BenchResult:
    """Converter codes (and a two-input FLANN's temperature codes, one a strobe) through
    ``flann_chain_top`` (built from ``files``: every entity's) against :class:`FlannChainTop`,
    whose values the bench is given."""
    want = FlannChainTop(chain).process(codes_a, codes_b, ref, temp_codes)
    spec = chain.conditioner
    cfg = {"spec": spec.to_dict(), "codes_a": np.asarray(codes_a).tolist(),
           "codes_b": np.asarray(codes_b).tolist(), "ref": asdict(ref),
           "cycles_per_sample": cycles_per_sample(spec),
           "latencies": chain.latencies(want.ratio_sat).tolist(),
           "expected": [[int(d), int(s)] for d, s in zip(want.out_data, want.out_sat)]}
    if temp_codes is not None:
        cfg["temp_codes"] = np.asarray(temp_codes).tolist()
    return run_cocotb(files, CHAIN_TOP, CHAIN_BENCH, build_dir, cfg, name=CHAIN_TOP, seed=seed)


def run_whole_chain(design: Design, flann: Design, build_dir, *, seed: int = 1) -> tuple[BenchResult, dict]:
    """A waveform through ``flann_chain_top`` against :class:`FlannChainTop`; (bench result, what
    was run)."""
    chain = ChainSpec(design.spec, flann.spec, flann.manifest["top"])
    a, b, ref, source, temps = chain_stimulus(design, chain)
    res = run_chain_top(design.files, chain, a, b, ref, build_dir, seed=seed, temp_codes=temps)
    return res, {"samples": int(a.size), "source": source}


def flann_design(design: Design) -> Design | None:
    """The FLANN design a conditioner's directory holds behind it (``flann gen`` of a model
    trained from waveforms: the fixed datapath, or the two-input one of a model trained at several
    temperatures), with its twin; None for a conditioner written from a spec."""
    fman = design.manifest.get(FLANN)
    if fman is None:
        return None
    where = design.directory / MANIFEST
    if not isinstance(fman, dict):
        raise FlannError(f"{where}: field {FLANN!r} must be an object (the FLANN design's manifest)")
    dp = flann_datapath(fman)
    dp.check(fman, f"{where}: field {FLANN!r}")
    check_widths(fman, f"{where}: field {FLANN!r}")
    if not set(fman["files"]) <= set(design.manifest["files"]) or fman.get("model") != design.manifest.get("model"):
        raise FlannError(f"{where}: field {FLANN!r} names files or a model the design does not list: "
                         "regenerate the design with flann gen")
    files = tuple(design.directory / f for f in fman["files"])
    return Design(design.directory, Manifest(design.directory, fman["top"], files, fman), datapath=dp).with_twin()


def bench(design: Design, build_dir, *, seed=1, **options) -> SimResult:
    """The conditioner's benches; with a FLANN behind it, then the FLANN's own (its every code
    against its twin): one summary, the FLANN's sweep and the conditioner's chain together."""
    flann = flann_design(design)   # a tampered FLANN manifest is refused before any simulation
    spec, files, build_dir = design.spec, design.files, Path(build_dir)
    results = {name: run_block(files, spec, entity, module, build_dir / name, seed=seed, **make(spec))
               for name, (entity, module, make) in BLOCKS.items()}
    results["top"], samples = run_chain(files, spec, build_dir / "top", seed=seed)
    rec = results["top"].records.get("cond_top", {})
    ok = all(r.ok for r in results.values()) and bool(rec)
    s = summary(design, samples, rec.get("mismatches"), None, {n: bench_entry(r) for n, r in results.items()}, ok)
    s["windows"], s["saturated_windows"] = rec.get("windows"), rec.get("saturated")
    if flann is None:
        return SimResult(s, None, spec, ok)
    fres = verification(flann.datapath).bench(flann, build_dir / FLANN, seed=seed, **options)
    f = fres.summary
    cond = {"samples": samples, "mismatches": s["mismatches"], "windows": s["windows"],
            "saturated_windows": s["saturated_windows"]}
    cres, whole = run_whole_chain(design, flann, build_dir / "chain", seed=seed)
    crec = cres.records.get("cond_chain", {})
    whole.update({k: crec.get(k) for k in ("windows", "mismatches", "saturated", "latency_cycles")})
    parts = (s["mismatches"], f["mismatches"], whole["mismatches"])
    bad = None if None in parts else sum(parts)
    merged = {**f, "codes_tested": samples + f["codes_tested"] + whole["samples"], "mismatches": bad,
              "conditioner": cond, "chain": whole,
              "flann": {k: f[k] for k in ("codes_tested", "mismatches", "max_err_lsb", "max_err_mm",
                                          "cycles_per_sample", "latency_cycles")},
              "cycles_per_sample": s["cycles_per_sample"], "latency_cycles": s["latency_cycles"],
              "benches": {**s["benches"], **{f"{FLANN}_{n}": b for n, b in f["benches"].items()},
                          "chain": bench_entry(cres)},
              "all_passed": ok and fres.passed and cres.ok and bool(crec)}
    merged.update({k: s[k] for k in s if k.startswith("samples_per_s") or k == "clock_hz"})
    return SimResult(merged, fres.curve, spec, merged["all_passed"], fres.bound_lsb)


VERIFICATION = Verification(bench=bench)

__all__ = ["VERIFICATION", "BLOCKS", "CHAIN_SAMPLES", "run_block", "run_chain", "run_whole_chain", "run_chain_top",
           "chain_stimulus", "lvdt_codes", "flann_design"]
