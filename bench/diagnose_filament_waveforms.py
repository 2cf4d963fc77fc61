#!/usr/bin/env python3
"""Waveform diagnosis on the independent forward model: exact sets named, per case.

    .venv/bin/python bench/diagnose_filament_waveforms.py [--seeds 5] [--dwell-s 0.003]
        [--positions 33] [--sensor FILE] [--keep DIR]

Each case hides effects in a waveform recording made by the filament model
(:func:`flann.physics.filament.simulate_waveforms`: current sheets, a dipole core, the primary
current with its phase; a forward model `flann diagnose` never imports), on ``--seeds`` random
geometries (primary 2-20 mm, secondaries 8-40 mm, carrier 1-10 kHz, output scaled to 2-8 V
at the travel's end, travel 60-100 % of the monotonic range, centred on 0 mm), sampled at
32 x the carrier by 12-bit converters, 4 mV rms white noise on every channel, ``--positions``
dwells of ``--dwell-s`` forward and back.  Each file goes through the command line as a
user's would, ``flann diagnose wave.csv --json``, and the set of effects it names (and any
alternatives) is compared with the hidden set: a case is exact when the set is the hidden one
and no alternative is offered.  ``null_offset`` is a DC demodulator offset, made after the
secondaries: its waveform shows nothing and must name nothing (the report must list it under
``not_in_waveforms``).  Exit 1 when any case is not exact.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import sys
import tempfile
import time
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from flann.cli import main as flann  # noqa: E402
from flann.physics import filament as F  # noqa: E402
from flann.recordings.waveform import write_waveforms  # noqa: E402

NOISE_V = 0.004
IMBALANCE = 0.015        # secondary 1 coupled 1.5 % more than secondary 2
SHIFT_MM = 0.6           # the core's null 0.6 mm from displacement 0
QUADRATURE_V = 0.04      # output-referred, as the filament model's rectified output has it
DRIFT_PCT = 1.0          # excitation amplitude over the run

# case -> (what is hidden, filament-model effects, the set the diagnosis must name)
CASES = {
    "control": ("nothing (4 mV noise)", {}, set()),
    "imbalance": (f"secondary 1 coupled {100 * IMBALANCE:g} % more",
                  {"imbalance": {"fraction": IMBALANCE}}, {"secondary_imbalance"}),
    "zero_shift": (f"null {SHIFT_MM:g} mm off", {"zero_shift": {"shift_mm": SHIFT_MM}}, {"zero_shift"}),
    "quadrature": (f"q {1e3 * QUADRATURE_V:g} mV at the output",
                   {"quadrature": {"quadrature_v": QUADRATURE_V}}, {"quadrature_null"}),
    "imbalance + shift": ("both of the above",
                          {"imbalance": {"fraction": IMBALANCE}, "zero_shift": {"shift_mm": SHIFT_MM}},
                          {"secondary_imbalance", "zero_shift"}),
    "shift + quadrature": ("both of the above",
                           {"zero_shift": {"shift_mm": SHIFT_MM}, "quadrature": {"quadrature_v": QUADRATURE_V}},
                           {"zero_shift", "quadrature_null"}),
    "null_offset (DC only)": ("demodulator offset 4 mV: not in the secondaries",
                              {"offset": {"offset_v": 0.004}}, set()),
    "excitation drift": (f"drive {DRIFT_PCT:g} % over the run",
                         {"excitation_drift": {"drift_pct": DRIFT_PCT}}, {"excitation_drift"}),
}


def truths(m: F.FilamentLVDT, effects: dict) -> dict:
    """The waveform figures' true values: e, s, the A - B quadrature at the secondaries, drift %."""
    out = {}
    if "imbalance" in effects:
        out["secondary_imbalance"] = effects["imbalance"]["fraction"]
    if "zero_shift" in effects:
        out["zero_shift"] = effects["zero_shift"]["shift_mm"]
    if "quadrature" in effects:
        out["quadrature_null"] = effects["quadrature"]["quadrature_v"] / abs(m.gain)
    if "excitation_drift" in effects:
        out["excitation_drift"] = effects["excitation_drift"]["drift_pct"]
    return out


def diagnose(csv_path: Path, sensor: str | None) -> dict:
    js = csv_path.with_suffix(".json")
    argv = ["diagnose", str(csv_path), "--json", str(js), "--quiet"] + (["--sensor", sensor] if sensor else [])
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        rc = flann(argv)
    if rc != 0:
        raise RuntimeError(f"flann {' '.join(argv)}: exit {rc}: {err.getvalue().strip()}")
    return json.loads(js.read_text())


def judge(obj: dict, want: set[str], effects: dict) -> tuple[bool, list[str], list]:
    named = sorted(e["name"] for e in obj["effects"])
    alternatives = obj.get("alternatives") or []
    exact = set(named) == want and not alternatives
    if "offset" in effects:   # the report must say why a waveform cannot show it
        exact = exact and any(n["name"] == "null_offset" for n in obj["not_in_waveforms"])
    return exact, named, alternatives


def figure(obj: dict, effect: str):
    """The deciding figure of ``effect`` (the first evidence line): (value, stderr, threshold)."""
    ev = next(e for e in obj["evidence"] if e["effect"] == effect)
    return ev["value"], ev["stderr"], ev["threshold"]


def run() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--dwell-s", type=float, default=0.003)
    ap.add_argument("--positions", type=int, default=33, help="dwell positions per pass (odd)")
    ap.add_argument("--sensor", default=None, help="pass --sensor FILE to diagnose (default: none)")
    ap.add_argument("--cases", default=None, help="comma-separated subset of: " + ", ".join(CASES))
    ap.add_argument("--keep", type=Path, default=None, help="keep the CSV and JSON files here")
    args = ap.parse_args()
    names = list(CASES) if not args.cases else [c.strip() for c in args.cases.split(",")]
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    root = args.keep or Path(tempfile.mkdtemp(prefix="fwave-"))
    root.mkdir(parents=True, exist_ok=True)
    print(f"filament waveforms: {len(names)} cases x {len(seeds)} geometries, {args.positions} positions "
          f"per pass forward and back, {1e3 * args.dwell_s:g} ms dwells, 32 x carrier, 12 bits, "
          f"{1e3 * NOISE_V:g} mV rms; diagnose {'--sensor ' + args.sensor if args.sensor else 'without --sensor'}")
    print(f"{'case':<22} {'seed':>4} {'exact':<5} {'named':<36} figures (value/true; |value|/threshold)")
    per_case, wrong, t_start = {}, [], time.time()
    for name in names:
        hidden, effects, want = CASES[name]
        hits = 0
        for seed in seeds:
            m, h, step = F.waveform_draw(seed, args.positions)
            wave = F.simulate_waveforms(m.with_effects(**effects), h, step, NOISE_V, seed=seed,
                                        dwell_s=args.dwell_s, source=f"filament {name} seed {seed}")
            path = root / f"{name.split()[0].replace('+', '')}-{len(per_case)}-{seed}.csv"
            write_waveforms(path, wave, wave.comments)
            obj = diagnose(path, args.sensor)
            exact, named, alternatives = judge(obj, want, effects)
            hits += exact
            figs = []
            for eff, true in truths(m, effects).items():
                v, _s, thr = figure(obj, eff)
                figs.append(f"{eff.split('_')[0]} {v:.4g}/{true:.4g} ({abs(v) / thr:.1f})")
            text = ", ".join(named) or "nothing"
            if alternatives:
                text += f" (alternatives {alternatives})"
            print(f"{name:<22} {seed:>4} {'yes' if exact else 'NO':<5} {text:<36} {'; '.join(figs)}", flush=True)
            if not exact:
                wrong.append((name, seed, named, alternatives))
        per_case[name] = (hits, len(seeds), hidden)
    print()
    print(f"{'case':<22} {'hidden':<48} exact")
    for name, (hits, n, hidden) in per_case.items():
        print(f"{name:<22} {hidden:<48} {hits} of {n}")
    total = sum(h for h, _n, _ in per_case.values())
    count = sum(n for _h, n, _ in per_case.values())
    print(f"\nexact {total} of {count} ({time.time() - t_start:.0f} s)")
    for name, seed, named, alternatives in wrong:
        print(f"WRONG: {name} seed {seed}: named {named or 'nothing'}"
              + (f", alternatives {alternatives}" if alternatives else "") + f"; hidden {sorted(CASES[name][2])}")
    return 0 if not wrong else 1


if __name__ == "__main__":
    sys.exit(run())
