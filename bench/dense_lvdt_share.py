#!/usr/bin/env python3
"""The paper's LVDT, dense, rolling over at the ends, behind a 12-bit converter.

    .venv/bin/python bench/dense_lvdt_share.py [--bits 12] [--noise-v 0.002]

Simulates `flann simulate data/sensors/paper_lvdt.toml --sweeps 2 --step-mm 0.5 --noise-v
0.002` with the sensor file's converter set to --bits, trains `flann train` (defaults: the
converter is read from the recording's grid), and judges the float model on 2,000 dense
held-out positions (noise-free, quantised to the converter): the share within +-0.06 mm,
next to the share a perfect inverse of the quantised readings reaches.  Exit 0 when the
model's share is at least 95 % of the perfect inverse's.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from flann.cli import main as flann  # noqa: E402
from flann.golden.model import load_model  # noqa: E402
from flann.recordings import read_recordings  # noqa: E402

SENSOR = Path(__file__).resolve().parents[1] / "data" / "sensors" / "paper_lvdt.toml"
BAND_MM = 0.06


def with_bits(text: str, bits: int) -> str:
    return re.sub(r"(?m)^bits = \d+", f"bits = {bits}", text)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bits", type=int, default=12)
    ap.add_argument("--noise-v", type=float, default=0.002)
    a = ap.parse_args()
    text = SENSOR.read_text()
    full_scale = float(re.search(r"(?m)^full_scale_v = ([0-9.]+)", text).group(1))
    lsb = 2 * full_scale / 2 ** a.bits
    with tempfile.TemporaryDirectory() as t:
        t = Path(t)
        (t / "s.toml").write_text(with_bits(text, a.bits))
        (t / "fine.toml").write_text(with_bits(text, 30))
        rc = flann(["simulate", str(t / "s.toml"), "--sweeps", "2", "--step-mm", "0.5",
                    "--noise-v", str(a.noise_v), "-o", str(t / "rec.csv")])
        rc |= flann(["simulate", str(t / "fine.toml"), "--step-mm", "0.01", "-o", str(t / "fine.csv")])
        rc |= flann(["train", str(t / "rec.csv"), "-o", str(t / "model.json")])
        if rc:
            return 1
        model = load_model(t / "model.json")
        fine = read_recordings(t / "fine.csv")
    x, v = fine.displacement_mm, fine.voltage_v
    pick = np.sort(np.random.default_rng(0).choice(x.size, 2000, replace=False))
    xh, vq = x[pick], np.round(v[pick] / lsb) * lsb
    o = np.argsort(v)
    perfect = np.mean(np.abs(np.interp(vq, v[o], x[o]) - xh) <= BAND_MM)
    ours = np.mean(np.abs(model.predict(vq) - xh) <= BAND_MM)
    print(f"{a.bits}-bit converter ({lsb:.4g} V/code), noise {a.noise_v:g} V: share within +-{BAND_MM:g} mm: "
          f"perfect inverse {100 * perfect:.1f} %, flann {100 * ours:.1f} % ({model.terms} terms, converter "
          f"judged at {model.training.get('converter', {}).get('input_bits', '12 and 16')} bits) "
          f"= {100 * ours / perfect:.1f} % of the perfect inverse's share")
    return 0 if ours >= 0.95 * perfect else 1


if __name__ == "__main__":
    sys.exit(main())
