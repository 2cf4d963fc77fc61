"""``flann trace model.json [--format fixed|float18] [--json] [--plot OUT.png]``.

Stage-by-stage error of the bit-true hardware against the float64 golden model over every
input code: which block and which term contribute most, over which input span, and why.
"""

from __future__ import annotations

import json

from ..model import load_model
from ..trace import plot_trace, run_trace
from .gen import add_spec_arguments, spec_options

HELP = "stage-by-stage error of hardware against the golden model"


def add_arguments(parser) -> None:
    parser.add_argument("model", help="model.json (flann-model/1)")
    parser.add_argument("--format", choices=("fixed", "float18"), default="fixed",
                        help="number format of the datapath (default %(default)s)")
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    parser.add_argument("--plot", metavar="OUT.png", help="plot error per stage vs input voltage")
    add_spec_arguments(parser)


def run(args) -> int:
    model = load_model(args.model)
    opts = spec_options(args)
    if args.format == "float18":
        opts = {k: v for k, v in opts.items()
                if k not in ("output_bits", "output_lsb_mm", "weight_frac_bits", "product_frac_bits",
                             "mult_style") or v not in (None, "lut")}
    result = run_trace(model, args.format, **opts)
    if args.plot:
        plot_trace(result, args.plot, title=f"flann trace {args.model} ({args.format})")
    if args.json:
        print(json.dumps(result.to_dict(), indent=2))
    else:
        print(result.text())
        if args.plot:
            print(f"plot: {args.plot}")
    return 0
