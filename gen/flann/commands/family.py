"""The ``--family`` option of ``flann gen``: its arguments and what it runs (not a subcommand of its own)."""

from __future__ import annotations

import argparse
import json

from ..errors import FlannError
from ..hardware.family.build import DEFAULT_TERMS, generate_family
from ..hardware.family.spec import DEFAULT_MARGIN


def _terms(text: str):
    if text == "auto":
        return "auto"
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer or 'auto', got {text!r}") from None


def add_family_arguments(parser) -> None:
    g = parser.add_argument_group("one design for a family of sensors (docs/production.md)")
    g.add_argument("--family", nargs="+", metavar="REC_OR_MODEL", default=None,
                   help="size one design for these sensors (recordings .csv or model .json); per-sensor "
                        "values go to a weight memory loadable through cfg_we/cfg_addr/cfg_data")
    g.add_argument("--terms", type=_terms, default=DEFAULT_TERMS,
                   help="--family: expansion terms when training recordings (default %(default)s), or "
                        "'auto': chosen like flann train --terms auto at the design's converter, for the "
                        "member that needs the most (docs/production.md)")
    g.add_argument("--margin", type=float, default=DEFAULT_MARGIN,
                   help="--family: headroom for sensors like these, 0.5 = 50 %% larger weights and "
                        "ranges (default %(default)s)")


def run_family(args, options: dict) -> int:
    if args.family is None:
        raise FlannError("give a model.json, or --family REC_OR_MODEL...")
    if args.model is not None:
        raise FlannError(f"{args.model}: give either a model or --family, not both")
    if args.format != "fixed":
        raise FlannError("--family generates the fixed-point datapath only (--format fixed)")
    man = generate_family(args.family, args.out, terms=args.terms, margin=args.margin, **options)
    if args.json:
        print(json.dumps(man, indent=2))
        return 0
    fam = man["family"]
    mem = fam["memory"]
    print(f"wrote {len(man['files'])} VHDL files + manifest.json + {man['init_model']} to {args.out}")
    print(f"  family of {len(fam['members'])} sensor(s), margin {fam['margin']:g}, {fam['terms']} terms")
    print(f"  {man['input_bits']}-bit input x {man['input_lsb_v']} V -> {man['output_bits']}-bit output x "
          f"{man['output_lsb_mm']} mm; {man['cycles_per_sample']} cycles/sample")
    print(f"  weight memory {mem['used_words']} of {mem['depth']} x {mem['data_bits']}-bit words "
          f"(cfg_addr {mem['addr_bits']} bits); estimate {man['analysis']['estimate']}")
    for c in man.get("terms_chosen", []):
        own = f", {c['own_cost']:.0f} LUT4-eq." if c["own_cost"] is not None else ""
        print(f"  {c['name']}: own design {c['own_terms']} terms (held-out RMS {c['own_rms_mm']:.4g} mm{own}); "
              f"in the family {fam['terms']} terms, held-out RMS {c['family_rms_mm']:.4g} mm "
              f"({c['family_rms_mm'] / c['own_rms_mm']:.2f}x its own)")
    return 0
