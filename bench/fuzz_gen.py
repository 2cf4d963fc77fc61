"""Generator fuzzing: random valid configurations on models of random sensors (flann.verify.fuzz).

Each case: gen -> the twin over every input code against the float model's stated bound ->
the HDL on a sample of codes (a random window and the clamp edges) bit-exact against the twin.
Prints one line per case and the totals; exit 1 when any case failed.

    .venv/bin/python bench/fuzz_gen.py [--seed 1] [--n 40] [--hdl-codes 24]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections import Counter

from flann.verify.fuzz import run_cases


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--hdl-codes", type=int, default=24, help="random window of codes simulated per case")
    args = ap.parse_args()
    t0 = time.monotonic()

    def show(c) -> None:
        opts = " ".join(f"{k}={v}" for k, v in c.options.items() if k != "check_device")
        print(f"{c.index:>3} {c.outcome:<7} {c.number_format:<7} terms={c.terms:<2} {opts}  twin codes {c.codes_twin} "
              f"max {c.max_err_lsb} <= {c.bound_lsb} LSB, HDL codes {c.codes_hdl} mismatches {c.mismatches}"
              + (f"  [{c.detail}]" if c.detail else ""), flush=True)

    with tempfile.TemporaryDirectory(prefix="fuzz-gen-") as tmp:
        cases = run_cases(args.seed, args.n, tmp, args.hdl_codes, progress=show)
    n = Counter(c.outcome for c in cases)
    print(f"{len(cases)} configurations (seed {args.seed}): {n['ok']} ok, {n['refused']} refused by the generator, "
          f"{n['FAIL']} failed; twin codes checked {sum(c.codes_twin for c in cases)}, HDL codes simulated "
          f"{sum(c.codes_hdl for c in cases)}, mismatches {sum(c.mismatches for c in cases)}; "
          f"{time.monotonic() - t0:.0f} s")
    return 1 if n["FAIL"] else 0


if __name__ == "__main__":
    sys.exit(main())
