"""What each generator choice costs: error bound, exhaustive twin error, estimated size, speed.

For the default model, vary one choice at a time from the default spec and print a Markdown
table: worst-case bound (spec analysis), max |twin - float| over every input code (exact,
bit-true twin), pre-synthesis LUT4/BRAM estimate, cycles per sample.  `flann synth` gives
measured resources for any one of these (generate it with the same `flann gen` options).

    .venv/bin/python bench/hw_tradeoffs.py [model.json]
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

from flann.golden.model import load_model
from flann.hardware.fixed.spec import derive_spec
from flann.hardware.fixed.twin import FlannTop

REPO = Path(__file__).resolve().parents[1]

VARIANTS = [
    ("default (shift-add, 2 bits/cycle, 1 lane)", {}),
    ("--mult-style lut", {"mult_style": "lut"}),
    ("--mult-digit-bits 1", {"mult_digit_bits": 1}),
    ("--mult-digit-bits 4", {"mult_digit_bits": 4}),
    ("--lanes 2", {"lanes": 2}),
    ("--phase-bits 18", {"phase_bits": 18}),
    ("--table-addr-bits 7", {"table_addr_bits": 7}),
    ("--no-interp (table 2^10)", {"interp": False}),
    ("--term-frac-bits 14", {"term_frac_bits": 14}),
    ("--weight-frac-bits 5", {"weight_frac_bits": 5}),
    ("--product-frac-bits 5", {"product_frac_bits": 5}),
    ("--output-lsb-mm 0.001 --output-bits 17", {"output_lsb_mm": 0.001, "output_bits": 17}),
    ("--input-bits 14", {"input_bits": 14}),
]


def main() -> None:
    model = load_model(sys.argv[1] if len(sys.argv) > 1 else REPO / "data" / "default_model.json")
    print("| choice | bound (LSB) | max twin-float (LSB) | est. LUT4 | est. BRAM | cycles/sample |")
    print("|---|---|---|---|---|---|")
    for name, opts in VARIANTS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            spec = derive_spec(model, check_device=False, **opts)
        err = FlannTop(spec).error_vs_float()["max_err_lsb"]
        est = spec.analysis["estimate"]
        print(f"| {name} | {spec.analysis['bound_total_lsb']:.3f} | {err:.3f} | {est['luts']} | "
              f"{est['brams']} | {spec.cycles_per_sample} |")


if __name__ == "__main__":
    main()
