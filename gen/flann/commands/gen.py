"""``flann gen model.json -o DIR [--format fixed|float18]``: VHDL-93 for a model plus DIR/manifest.json."""

from __future__ import annotations

import json

from ..hardware.fixed.render import generate
from ..hardware.family.command import add_family_arguments, run_family
from ..hardware.fixed.spec import MULT_STYLES

HELP = "generate VHDL-93 for a model"


def add_spec_arguments(parser) -> None:
    """Generator options shared by `flann gen` and `flann sim`."""
    g = parser.add_argument_group("architecture and widths (defaults from the error analysis)")
    g.add_argument("--device", default="xc2s200-pq208-5", help="target part-package-speed (default %(default)s)")
    g.add_argument("--input-bits", type=int, default=12, help="signed ADC code width (default %(default)s)")
    g.add_argument("--input-lsb-v", type=float, default=None, help="volts per input code (default: trained range + 10%%)")
    g.add_argument("--no-clamp", action="store_true", help="do not clamp codes to the trained range")
    g.add_argument("--output-bits", type=int, default=None, help="signed output width")
    g.add_argument("--output-lsb-mm", type=float, default=None, help="mm per output code")
    g.add_argument("--lanes", type=int, default=1, help="parallel term lanes (default %(default)s)")
    g.add_argument("--mult-style", choices=MULT_STYLES, default="shiftadd", help="multiplier style (default %(default)s)")
    g.add_argument("--mult-digit-bits", type=int, default=2, help="shift-add: weight bits per cycle (default %(default)s)")
    g.add_argument("--no-interp", action="store_true", help="plain table lookup, no slope correction")
    g.add_argument("--phase-bits", type=int, default=None, help="phase width (units of pi, mod 2)")
    g.add_argument("--table-addr-bits", type=int, default=None, help="quarter-wave table address bits")
    g.add_argument("--term-frac-bits", type=int, default=None, help="fraction bits of sin/cos terms")
    g.add_argument("--weight-frac-bits", type=int, default=None, help="fraction bits of weights (output LSB units)")
    g.add_argument("--product-frac-bits", type=int, default=None, help="fraction bits kept after each product")


def spec_options(args) -> dict:
    return dict(
        device=args.device, input_bits=args.input_bits, input_lsb_v=args.input_lsb_v,
        clamp=not args.no_clamp, output_bits=args.output_bits, output_lsb_mm=args.output_lsb_mm,
        lanes=args.lanes, mult_style=args.mult_style, mult_digit_bits=args.mult_digit_bits,
        interp=not args.no_interp,
        phase_bits=args.phase_bits, table_addr_bits=args.table_addr_bits,
        term_frac_bits=args.term_frac_bits, weight_frac_bits=args.weight_frac_bits,
        product_frac_bits=args.product_frac_bits,
    )


def add_arguments(parser) -> None:
    parser.add_argument("model", nargs="?", help="model.json (flann-model/1); not with --family")
    parser.add_argument("-o", "--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument("--json", action="store_true", help="print the manifest as JSON")
    parser.add_argument("--format", choices=("fixed", "float18"), default="fixed",
                        help="number format of the products and the sum: fixed point sized by the error "
                             "budget (default) or the seed's 18-bit floating point (docs/float18.md)")
    add_spec_arguments(parser)
    add_family_arguments(parser)


def run(args) -> int:
    if args.family is not None or args.model is None:
        return run_family(args, spec_options(args))
    if args.format == "float18":
        from ._float18 import run_gen

        return run_gen(args)
    man = generate(args.model, args.out, **spec_options(args))
    if args.json:
        print(json.dumps(man, indent=2))
    else:
        a = man["analysis"]
        print(f"wrote {len(man['files'])} VHDL files + manifest.json to {args.out}")
        print(f"  {man['input_bits']}-bit input x {man['input_lsb_v']} V -> {man['output_bits']}-bit output x "
              f"{man['output_lsb_mm']} mm; {man['cycles_per_sample']} cycles/sample")
        print(f"  error bound {a['bound_total_lsb']:.3f} LSB; estimate {a['estimate']}")
    return 0
