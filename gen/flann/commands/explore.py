"""flann explore MODEL: design-space table (lanes x multiplier x widths) plus the seed architecture."""

from __future__ import annotations

from pathlib import Path

from ..argtypes import bounded, checked
from ..golden.model import MAX_TERMS
from ..eda import ABC_MODES
from ..analysis import explore
from ..analysis.plugin import insight
from ..hardware.float18.analysis import float18_rows
from ..implement.synth import manifest_device
from ..hardware.adc import ADC_BITS
from ..errors import FlannError
from ..hardware.fixed.spec import check_mult_style, max_lanes
from ..hardware.registry import FORMATS, datapath_for_model
from ..hardware.target import DEFAULT_PART
from ..hardware.design import design_model, open_directory
from .common import add_common, emit_json, on_terminal

HELP = "design-space table (lanes x multiplier x widths)"

def _list_of(parse_item, name: str):
    """An argparse ``type`` for a comma-separated list, each item read by ``parse_item``: its
    value, or None to keep the item's text (a check that only raises)."""
    def parse(text: str) -> tuple:
        items = [item.strip() for item in text.split(",")]
        return tuple(item if value is None else value for item, value in zip(items, map(parse_item, items)))

    parse.__name__ = name
    return parse

# a count above what this model takes is a skipped row (its note says why); above what any
# model takes, or below one lane, it is a typing mistake
LANES = _list_of(bounded(int, 1, max_lanes(MAX_TERMS)), "lanes")
STYLES = _list_of(checked(check_mult_style), "multiplier styles")
WIDTHS = _list_of(checked(explore.check_width_preset), "width presets")

def add_arguments(p):
    p.add_argument("model", metavar="MODEL|DIR",
                   help="model.json, or a design directory written by flann gen (its model and its ADC)")
    p.add_argument("--device", default=None, metavar="PART",
                   help=f"target part (default: a design directory's own part, else {DEFAULT_PART})")
    p.add_argument("--lanes", type=LANES, metavar="N[,N...]", default=None,
                   help="lane counts to try (default 1,2,4; a float18 design has one lane)")
    p.add_argument("--mult", type=STYLES, metavar="STYLE[,STYLE...]", default=None,
                   help="multiplier styles (default lut,shiftadd; not for a float18 design: the seed's multiplier)")
    p.add_argument("--widths", type=WIDTHS, metavar="PRESET[,PRESET...]", default=explore.WIDTH_PRESETS,
                   help="width presets: budget (error budget <= 1 LSB), narrow (4 fraction bits fewer; "
                        "a float18 design: of its terms)")
    p.add_argument("--no-seed", action="store_true", help="leave out the seed architecture (its synthesis is slow)")
    p.add_argument("--seed-only", action="store_true", help="only the seed architecture rows")
    p.add_argument("--float18", action="store_true",
                   help="add the float18 rows: the serial float18 design and the seed's arithmetic in float18")
    p.add_argument("--abc", choices=ABC_MODES, default="fast",
                   help="yosys LUT mapping (default fast: abc -fast; full = synth_xilinx as is, slow)")
    p.add_argument("--input-bits", type=bounded(int, *ADC_BITS), default=None, metavar="B",
                   help="ADC width in bits, as for flann gen (default: flann gen's; not with a design "
                        "directory: its own)")
    p.add_argument("--input-lsb-v", type=bounded(float, 0, lo_open=True), default=None, metavar="V",
                   help="volts per ADC code, as for flann gen (default: flann gen's; not with a design "
                        "directory: its own)")
    add_common(p, json="the rows")

def _design_model(args):
    """The datapath whose design space is explored: a design directory's own (its model and,
    unless given, its ADC), else the one flann gen MODEL builds."""
    source = args.model
    is_dir = Path(source).is_dir()
    design = open_directory(source) if is_dir else None   # read once
    man, dp = (design.manifest, design.datapath) if is_dir else ({}, datapath_for_model(args.model, FORMATS[0]))
    if insight(dp).explore is None:
        raise dp.lacking(args.model, "design space for flann explore")
    if is_dir:
        model = design_model(args.model, man, dp)
        given = " ".join(f"{flag} {value:g}" for flag, value in (("--input-bits", args.input_bits),
                                                                 ("--input-lsb-v", args.input_lsb_v))
                         if value is not None)
        if given:
            # as flann sim and flann trace: a design directory is taken as written, never re-sized
            raise FlannError(f"{args.model}: a design directory is explored with the ADC it was generated for; "
                             f"for another ADC explore its model: flann explore {model} {given}")
        args.model = str(model)
        args.input_bits, args.input_lsb_v = man["input_bits"], man["input_lsb_v"]
    if args.device is None:   # as flann synth and flann ise: the part the design was generated for
        args.device = manifest_device(man) if is_dir else DEFAULT_PART
    return dp

def run(args) -> int:
    dp = _design_model(args)
    progress = on_terminal(args)   # progress lines on a terminal only, never into a log
    if args.seed_only:
        rows = explore.seed_rows(args.model, args.device, abc=args.abc, progress=progress)
        if args.float18:
            rows += float18_rows(args.model, args.device, abc=args.abc, progress=progress)
        if not emit_json(args, [r.to_dict() for r in rows]):
            print(explore.markdown(rows, args.device))
        return 0
    rows = insight(dp).explore(
        args.model, args.device, lanes=args.lanes, styles=args.mult,
        widths=args.widths, seed=not args.no_seed, progress=progress, abc=args.abc,
        adc={k: v for k, v in (("input_bits", args.input_bits), ("input_lsb_v", args.input_lsb_v)) if v is not None},
    )
    if args.float18:
        rows += float18_rows(args.model, args.device, abc=args.abc, progress=progress)
    if not emit_json(args, [r.to_dict() for r in rows]):
        print(explore.markdown(rows, args.device))
    return 0
