"""``flann gen model.json -o DIR [--format fixed|float18]``: VHDL-93 for a model plus DIR/manifest.json."""

from __future__ import annotations

import json
import warnings

from ..hardware import options as gen_options
from .family import add_family_arguments, run_family
from ..hardware.fixed.render import generate as generate_fixed
from ..hardware.float18.render import generate as generate_float18
from ..hardware.float18.spec import float18_options
from ..golden.model import load_model
from ..golden.train import converter_mismatch

HELP = "generate VHDL-93 for a model"


def add_arguments(parser) -> None:
    parser.add_argument("model", nargs="?", help="model.json (flann-model/1); not with --family")
    parser.add_argument("-o", "--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument("--json", action="store_true", help="print the manifest as JSON")
    parser.add_argument("--format", choices=("fixed", "float18"), default="fixed",
                        help="number format of the products and the sum: fixed point sized by the error "
                             "budget (default) or the seed's 18-bit floating point (docs/float18.md)")
    gen_options.add_arguments(parser)
    add_family_arguments(parser)


def run(args) -> int:
    opts = gen_options.from_args(args)
    if args.family is not None or args.model is None:
        return run_family(args, opts.to_kwargs())
    other = converter_mismatch(load_model(args.model), opts.input_bits, opts.input_lsb_v)
    if other:
        warnings.warn(other)
    if args.format == "float18":
        man = generate_float18(args.model, args.out, **float18_options(opts))
    else:
        man = generate_fixed(args.model, args.out, opts)
    if args.json:
        print(json.dumps(man, indent=2))
    elif args.format == "float18":
        print(f"wrote {len(man['files'])} VHDL files + manifest.json to {args.out} (float18, top {man['top']})")
        print(f"  {man['input_bits']}-bit input x {man['input_lsb_v']} V -> float18 displacement in mm "
              f"({man['output']['exp_bits']} exponent, {man['output']['frac_bits']} fraction bits); "
              f"{man['cycles_per_sample']} cycles/sample")
    else:
        a = man["analysis"]
        print(f"wrote {len(man['files'])} VHDL files + manifest.json to {args.out}")
        print(f"  {man['input_bits']}-bit input x {man['input_lsb_v']} V -> {man['output_bits']}-bit output x "
              f"{man['output_lsb_mm']} mm; {man['cycles_per_sample']} cycles/sample")
        print(f"  error bound {a['bound_total_lsb']:.3f} LSB; estimate {a['estimate']}")
    return 0
