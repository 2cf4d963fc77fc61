"""flann explore MODEL: design-space table (lanes x multiplier x widths) plus the seed architecture."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..argtypes import bounded
from ..implement import explore
from ..errors import FlannError
from ..hardware.registry import read_design
from ..hardware.target import DEFAULT_PART
from ..verify.design import design_model

HELP = "design-space table (lanes x multiplier x widths)"


def _ints(text: str) -> tuple[int, ...]:
    try:
        vals = tuple(int(x) for x in text.split(","))
    except ValueError:
        raise FlannError(f"--lanes {text!r}: expected a comma-separated list of integers such as 1,2,4") from None
    return vals


def add_arguments(p):
    p.add_argument("model", metavar="MODEL|DIR",
                   help="model.json, or a design directory written by flann gen (its model and its ADC)")
    p.add_argument("--device", default=DEFAULT_PART, metavar="PART", help="target part (default %(default)s)")
    p.add_argument("--lanes", default="1,2,4", help="lane counts to try (default 1,2,4)")
    p.add_argument("--mult", default="lut,shiftadd", help="multiplier styles (default lut,shiftadd)")
    p.add_argument("--widths", default=",".join(explore.WIDTH_PRESETS),
                   help="width presets: budget (error budget <= 1 LSB), narrow (4 fraction bits fewer)")
    p.add_argument("--no-seed", action="store_true", help="leave out the seed architecture (its synthesis is slow)")
    p.add_argument("--seed-only", action="store_true", help="only the seed architecture rows")
    p.add_argument("--float18", action="store_true",
                   help="add the float18 rows: the serial float18 design and the seed's arithmetic in float18")
    p.add_argument("--abc", choices=("fast", "full"), default="fast",
                   help="yosys LUT mapping (default fast: abc -fast; full = synth_xilinx as is, slow)")
    p.add_argument("--input-bits", type=bounded(int, 4, 32), default=None, metavar="B",
                   help="ADC width in bits, as for flann gen (default: flann gen's)")
    p.add_argument("--input-lsb-v", type=bounded(float, 0, lo_open=True), default=None, metavar="V",
                   help="volts per ADC code, as for flann gen (default: flann gen's)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")


def _design_model(args) -> None:
    """DIR: explore the model the design keeps, at the design's ADC unless given."""
    if not Path(args.model).is_dir():
        return
    man, dp = read_design(args.model)
    if dp.why_no_explore:
        raise FlannError(f"{args.model}: {dp.why_no_explore}")
    model = design_model(args.model, man, dp)
    args.model = str(model)
    args.input_bits = man["input_bits"] if args.input_bits is None else args.input_bits
    args.input_lsb_v = man["input_lsb_v"] if args.input_lsb_v is None else args.input_lsb_v


def run(args) -> int:
    _design_model(args)
    progress = sys.stderr.isatty()   # progress lines on a terminal only, never into a log
    if args.seed_only:
        rows = explore.seed_rows(args.model, args.device, abc=args.abc, progress=progress)
        if args.float18:
            rows += explore.float18_rows(args.model, args.device, abc=args.abc, progress=progress)
        print(json.dumps([r.to_dict() for r in rows], indent=2) if args.json else explore.markdown(rows, args.device))
        return 0
    rows = explore.explore(
        args.model, args.device, lanes=_ints(args.lanes), styles=tuple(args.mult.split(",")),
        widths=tuple(args.widths.split(",")), seed=not args.no_seed, progress=progress, abc=args.abc,
        adc={k: v for k, v in (("input_bits", args.input_bits), ("input_lsb_v", args.input_lsb_v)) if v is not None},
    )
    if args.float18:
        rows += explore.float18_rows(args.model, args.device, abc=args.abc, progress=progress)
    if args.json:
        print(json.dumps([r.to_dict() for r in rows], indent=2))
    else:
        print(explore.markdown(rows, args.device))
    return 0
