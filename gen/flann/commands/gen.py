"""``flann gen model.json -o DIR [--format fixed|float18]``: VHDL-93 for a model plus DIR/manifest.json.

The datapath is looked up in :mod:`flann.hardware.registry`; the directory is written as a whole
(VHDL, manifest.json and the model), replacing an earlier flann design there (said on stderr).
"""

from __future__ import annotations

import warnings

from ..errors import FlannError
from ..golden.thermal import load_any_model
from ..golden.train import converter_mismatch, converter_text, judged_converter, same_converter
from ..hardware import options as gen_options
from ..hardware.conditioner.settings import flann_options
from ..hardware.manifest import is_design
from ..hardware.registry import FORMATS, datapath_for_model, family_datapath
from .common import add_common, emit_json, info, json_word_as_input
from .family import add_family_arguments, check_family_args

HELP = "generate VHDL-93 for a model"


def generator_options(args) -> tuple[gen_options.GenOptions, tuple[str, ...]]:
    """(the options, the names of those given on the command line); refuses a flag the options given make meaningless."""
    opts = gen_options.from_args(args)
    given = gen_options.given(args)
    if "mult_digit_bits" in given and opts.mult_style != "shiftadd":
        # the lut multiplier takes the whole weight in one cycle: the digit would be recorded, not used
        raise FlannError(f"--mult-digit-bits {opts.mult_digit_bits}: sets the shift-add multiplier's weight bits "
                         f"per cycle; --mult-style {opts.mult_style} has no digit (leave --mult-digit-bits out)")
    return opts, given


def refuse_generator_options(target, args, given, verb: str) -> None:
    """A design directory is used as written: generator flags given with it would be ignored."""
    if given:
        flags = " ".join(gen_options.flag_text(n, getattr(args, n)) for n in given)
        raise FlannError(f"{target}: a design directory is {verb} as written, {flags} would be ignored; "
                         f"regenerate it with flann gen MODEL -o DIR {flags}, or pass a model.json")


def add_arguments(parser) -> None:
    parser.add_argument("model", nargs="?", help="model.json (flann-model/1, or flann-thermal-model/1: the two-input datapath); "
                        "not with --family")
    parser.add_argument("--format", choices=FORMATS, default=FORMATS[0],
                        help="number format of the products and the sum: fixed point sized by the error "
                             "budget (default) or the seed's 18-bit floating point (docs/float18.md)")
    add_common(parser, output=dict(help="output directory", metavar="DIR", required=True, legacy_out=True),
               json="the manifest")
    gen_options.add_arguments(parser)
    add_family_arguments(parser)


def run(args) -> int:
    opts, _given = generator_options(args)
    if args.family is None:
        json_word_as_input(args, "model")   # `flann gen --json model.json -o DIR`
    model, other = None, ""
    if args.family is not None or args.model is None:
        check_family_args(args)
        dp, source, extra = family_datapath(args.family), args.family, {"margin": args.margin}
        if args.terms is not None:  # else the datapath's own default (auto; fixed with temperature)
            extra["terms"] = args.terms
    else:
        dp, source, extra = datapath_for_model(args.model, args.format), args.model, {}
        model = load_any_model(args.model)
        opts = flann_options(model, opts, _given, args.model)
        other = converter_mismatch(model, opts.input_bits, opts.input_lsb_v)
        if other:
            warnings.warn(other)
    replacing = is_design(args.output)
    man = dp.generate(source, args.output, opts, **extra)
    if model is not None and opts.input_lsb_v is None and not other:
        # the volts per code were derived from the model's voltage range, not given: say so when
        # the model knows the converter it was recorded with and that one reads other codes
        conv = judged_converter(model)
        if conv is not None and not same_converter(conv, man["input_bits"], man["input_lsb_v"]):
            warnings.warn(f"{args.output}: input LSB {man['input_lsb_v']:.6g} V, derived from the model's voltage "
                          f"range (no --input-lsb-v), but the model was judged for a {converter_text(*conv[:2])} "
                          f"converter ({conv[2]}): give --input-lsb-v for the converter the design will read")
    if replacing:
        info(args, f"flann gen: replaced the flann design in {args.output}")
    if emit_json(args, man):
        return 0
    kept = [f for f in (man.get("model"), *(im["hex"] for im in man.get("images", [])), man.get("waveform")) if f]
    print(f"wrote {len(man['files'])} VHDL files + manifest.json + {', '.join(dict.fromkeys(kept))} to {args.output} "
          f"({dp.name}, top {man['top']})")
    for line in dp.summary(man):
        print(line)
    return 0
