#!/usr/bin/env python3
"""Sensors of a family's kind that were not in the gen set: calibrated, or refused by the design?

    .venv/bin/python bench/family_headroom.py [--seeds 1-6] [--later 30] [--terms auto] [--out build/family_headroom]

Per seed: three closed-form S-curve sensors (amplitude 2.9-3.2 V, asymmetry +-3 %, width
+-5 %; 14-bit converter, 0.5 mV noise, 300 positions forward and back) size a design
(``flann gen --family``'s sizing, default terms), then ``--later`` sensors drawn wider
(amplitude 2.8-3.3 V, asymmetry +-6 %, width +-10 %) are trained for it as ``flann calibrate``
does (:func:`flann.production.calibrate.train_for_design`).  Prints, per seed, the terms and
how many later sensors the design refused and why.  Exit 0 when none is refused.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from flann.hardware.family.build import generate_family  # noqa: E402
from flann.hardware.family.datapath import rebuild  # noqa: E402
from flann.hardware.family.spec import FitError  # noqa: E402
from flann.production.calibrate import train_for_design  # noqa: E402
from flann.recordings import Recordings, read_recordings, write_recordings  # noqa: E402

LSB = 2 * 3.6 / 2 ** 14


def sensor(rng, amp, asym, w_mm, path):
    x = np.linspace(-10.0, 10.0, 300)
    xs = np.concatenate([x, x[::-1]])
    u = xs / w_mm
    v = amp * np.where(u >= 0, 1 + asym, 1 - asym) * u / (1 + np.abs(u) ** 2.5) ** 0.4
    v = np.round((v + rng.normal(0, 5e-4, xs.size)) / LSB) * LSB
    write_recordings(path, Recordings(displacement_mm=xs, voltage_v=v, direction=np.sign(np.gradient(xs))))
    return path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1-6")
    ap.add_argument("--later", type=int, default=30)
    ap.add_argument("--terms", default="auto")
    ap.add_argument("--out", default="build/family_headroom")
    a = ap.parse_args()
    lo, _, hi = a.seeds.partition("-")
    total = refused = 0
    for seed in range(int(lo), int(hi or lo) + 1):
        out = Path(a.out) / f"seed{seed}"
        out.mkdir(parents=True, exist_ok=True)
        rng = np.random.default_rng(seed)
        members = [sensor(rng, rng.uniform(2.9, 3.2), rng.uniform(-0.03, 0.03), 7 * rng.uniform(0.95, 1.05),
                          out / f"m{k}.csv") for k in range(3)]
        terms = a.terms if a.terms == "auto" else int(a.terms)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            man = generate_family(members, out / "design", terms=terms, input_bits=14, input_lsb_v=LSB)
        fam, _ = rebuild(out / "design" / "init_model.json", man)
        why = []
        for k in range(a.later):
            p = sensor(rng, rng.uniform(2.8, 3.3), rng.uniform(-0.06, 0.06), 7 * rng.uniform(0.9, 1.1),
                       out / f"later{k}.csv")
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    train_for_design(read_recordings(p), fam)
            except FitError as exc:
                why.append(str(exc).split(" reach")[0].split(":")[0])
        total += a.later
        refused += len(why)
        print(f"seed {seed}: {fam.terms} terms, linear accumulator {fam.spec.lin_width} bits; "
              f"{len(why)} of {a.later} later sensors refused" + (f" ({'; '.join(sorted(set(why)))})" if why else ""))
    print(f"refused {refused} of {total} sensors not in the gen set")
    return 0 if refused == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
