"""``flann gen model.json -o DIR [--format fixed|float18]``: VHDL-93 for a model plus DIR/manifest.json.

The datapath is looked up in :mod:`flann.hardware.registry`; the directory is written as a whole
(VHDL, manifest.json and the model), replacing an earlier flann design there (said on stderr).
"""

from __future__ import annotations

import json
import sys
import warnings

from ..golden.thermal import load_any_model
from ..golden.train import converter_mismatch
from ..hardware import options as gen_options
from ..hardware.manifest import is_design
from ..hardware.registry import FORMATS, datapath_for_model, family_datapath
from .family import add_family_arguments, check_family_args

HELP = "generate VHDL-93 for a model"


def add_arguments(parser) -> None:
    parser.add_argument("model", nargs="?", help="model.json (flann-model/1, or flann-thermal-model/1: the two-input datapath); "
                        "not with --family")
    parser.add_argument("-o", "--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument("--json", action="store_true", help="print the manifest as JSON")
    parser.add_argument("--format", choices=FORMATS, default=FORMATS[0],
                        help="number format of the products and the sum: fixed point sized by the error "
                             "budget (default) or the seed's 18-bit floating point (docs/float18.md)")
    gen_options.add_arguments(parser)
    add_family_arguments(parser)


def run(args) -> int:
    opts = gen_options.from_args(args)
    if args.family is not None or args.model is None:
        check_family_args(args)
        dp, source, extra = family_datapath(args.family), args.family, {"margin": args.margin}
        if args.terms is not None:  # else the datapath's own default (auto; fixed with temperature)
            extra["terms"] = args.terms
    else:
        dp, source, extra = datapath_for_model(args.model, args.format), args.model, {}
        other = converter_mismatch(load_any_model(args.model), opts.input_bits, opts.input_lsb_v)
        if other:
            warnings.warn(other)
    replacing = is_design(args.out)
    man = dp.generate(source, args.out, opts, **extra)
    if replacing:
        print(f"flann gen: replaced the flann design in {args.out}", file=sys.stderr)
    if args.json:
        print(json.dumps(man, indent=2))
        return 0
    kept = [f for f in (man.get("model"), *(im["hex"] for im in man.get("images", []))) if f]
    print(f"wrote {len(man['files'])} VHDL files + manifest.json + {', '.join(dict.fromkeys(kept))} to {args.out} "
          f"({dp.name}, top {man['top']})")
    for line in dp.summary(man):
        print(line)
    return 0
