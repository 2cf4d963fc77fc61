"""Golden-model throughput: samples/s of the float64 FLANN for 51 terms (numpy, vectorised).

Run:  .venv/bin/python bench/bench_golden.py [--terms 51] [--samples 1000000] [--repeat 5]
Prints the best of --repeat timed runs of FlannModel.predict (trigonometric sum by
recurrence, one core: set OPENBLAS_NUM_THREADS=1) on --samples voltages spread over the
model's voltage range (data/default_model.json unless --model is given), the same for the
direct sum (one sin and cos per term) on a tenth of the samples, and their largest
difference relative to the sum of |terms|.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from flann.golden.model import FlannModel, load_model


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="data/default_model.json")
    ap.add_argument("--terms", type=int, default=51,
                    help="terms (a model of this size with the file's weights repeated)")
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--chunk", type=int, default=65536, help="samples per predict call")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    base = load_model(args.model)
    w = np.resize(np.asarray(base.weights), args.terms)
    model = FlannModel(weights=tuple(w), bias=base.bias, input_offset_v=base.input_offset_v,
                       input_scale_v=base.input_scale_v, voltage_range_v=base.voltage_range_v)
    lo, hi = model.voltage_range_v
    v = np.linspace(lo, hi, args.samples)
    best = float("inf")
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        for i in range(0, v.size, args.chunk):
            model.predict(v[i:i + args.chunk])
        best = min(best, time.perf_counter() - t0)
    print(f"golden model, {args.terms} terms, float64: {args.samples / best:,.0f} samples/s "
          f"({args.samples} samples in chunks of {args.chunk}, best of {args.repeat}: "
          f"{best * 1e3:.1f} ms)")
    vd = v[::10]
    t0 = time.perf_counter()
    for i in range(0, vd.size, args.chunk):
        model.predict_direct(vd[i:i + args.chunk])
    direct = time.perf_counter() - t0
    scale = abs(model.bias) + np.abs(model.features(vd)) @ np.abs(w)
    rel = np.max(np.abs(model.predict(vd) - model.predict_direct(vd)) / scale)
    print(f"direct sum (sin and cos per term): {vd.size / direct:,.0f} samples/s; "
          f"largest |recurrence - direct| / sum|terms| = {rel:.2e}")


if __name__ == "__main__":
    main()
