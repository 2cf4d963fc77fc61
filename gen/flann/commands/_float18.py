"""Command-line glue for the float18 format, shared by `flann gen --format float18` and
`flann trace --format float18`: which generator options apply, and the gen summary."""

from __future__ import annotations

import argparse
import json

from ..hardware.float18.spec import FRONT_END_OPTIONS
from .gen import add_spec_arguments, spec_options


def spec_defaults() -> dict:
    """The generator options' values when not given on the command line."""
    p = argparse.ArgumentParser()
    add_spec_arguments(p)
    return spec_options(p.parse_args([]))


def float18_options(args, fixed_too: bool = False) -> dict:
    """Generator options for the float18 design.  Fixed-only options left at their defaults
    are dropped; given explicitly they are kept, so that the spec rejects them with a clear
    message, unless ``fixed_too`` (a comparison where they are meant for the fixed design)."""
    opts = spec_options(args)
    defaults = spec_defaults()
    for k in list(opts):
        if k not in FRONT_END_OPTIONS and (opts[k] == defaults.get(k) or fixed_too):
            del opts[k]
    return opts


def run_gen(args) -> int:
    """`flann gen MODEL -o DIR --format float18`."""
    from ..hardware.float18.render import generate

    man = generate(args.model, args.out, **float18_options(args))
    if getattr(args, "json", False):
        print(json.dumps(man, indent=2))
        return 0
    print(f"wrote {len(man['files'])} VHDL files + manifest.json to {args.out} (float18, top {man['top']})")
    print(f"  {man['input_bits']}-bit input x {man['input_lsb_v']} V -> float18 displacement in mm "
          f"({man['output']['exp_bits']} exponent, {man['output']['frac_bits']} fraction bits); "
          f"{man['cycles_per_sample']} cycles/sample")
    return 0
