"""``flann trace model.json [--format fixed|float18] [--json] [--plot OUT.png]``.

Stage-by-stage error of the bit-true hardware against the float64 golden model over every
input code: which block and which term contribute most, over which input span, and why.
``--hdl`` also simulates the generated VHDL over every input code and compares its own
outputs; ``--compare`` adds the other format (errors of both on the same axes, as the seed's
Fig. 6(b)); ``--at CSV`` also lists the error at the recordings' input voltages.
"""

from __future__ import annotations

import dataclasses
import tempfile
from pathlib import Path

from ..argtypes import png_path
from ..errors import FlannError
from ..golden.model import load_model
from ..recordings import read_recordings
from ..analysis.plugin import insight
from ..analysis.trace import (check_design_hdl, check_hdl, plot_compare, run_trace,
                              trace_design)
from ..hardware.registry import FORMATS as REGISTRY_FORMATS, datapath
from ..hardware.design import from_directory
from ..hardware import options as gen_options
from .common import add_common, check_jobs, cores_limited, emit_json, info
from .gen import generator_options, refuse_generator_options

HELP = "stage-by-stage error of hardware against the golden model"
FORMATS = REGISTRY_FORMATS


def add_arguments(parser) -> None:
    parser.add_argument("model", metavar="MODEL|DIR",
                        help="model.json (flann-model/1), or a design directory written by flann gen -o DIR "
                             "(traced as it is, with the model it keeps)")
    parser.add_argument("--model", dest="design_model", metavar="MODEL.json", default=None,
                        help="with DIR: the model DIR was generated from (checked against the manifest's sha256)")
    parser.add_argument("--format", choices=FORMATS, default=None,
                        help=f"number format of the datapath (default {FORMATS[0]}; a design directory: its own)")
    parser.add_argument("--compare", action="store_true",
                        help="also trace the other format; --plot then shows both errors on one axis")
    parser.add_argument("--at", metavar="CSV", help="also report the error at these recordings' voltages")
    parser.add_argument("--hdl", action="store_true",
                        help="also simulate the generated VHDL over every input code (GHDL + cocotb, "
                             "about a minute) and compare its outputs with the twin and the golden model")
    parser.add_argument("--plot", metavar="OUT.png", type=png_path, help="plot error per stage vs input voltage")
    add_common(parser, json="the report", jobs="--hdl simulation shards")
    gen_options.add_arguments(parser)


def _options(args, fmt: str) -> dict:
    return datapath(fmt).derive_options(generator_options(args)[0], args.compare)


def _design_dir(args):
    """A design directory: trace exactly that design (its manifest's options and model)."""
    if not Path(args.model).is_dir():
        return None
    if args.format is not None or args.compare:
        raise FlannError(f"{args.model}: a design directory is traced as it is (no --format, no --compare)")
    refuse_generator_options(args.model, args, generator_options(args)[1], "traced")
    return from_directory(args.model, args.design_model)


def traced(design) -> str:
    """A design's trace as its label names it: the datapath, and for a family design the member
    whose weights fill the memory (the first member's, its init_model, unless --model names
    another model)."""
    name, man = design.datapath.name, design.manifest
    init = man.get("init_model")
    if not init:
        return name
    if Path(design.model) != (design.directory / init).resolve():
        return f"{name}: {Path(design.model).name}'s weights in the memory (--model)"
    images = man.get("images") or []
    first = images[0].get("name") if images and isinstance(images[0], dict) else None
    who = f"member {first}" if first else "its first member"
    return f"{name}: {who}, the memory's initial weights from {init}"


def run(args) -> int:
    check_jobs(args.jobs)
    design = _design_dir(args)
    model = None if design else load_model(args.model)  # a design's datapath says whether it has stages
    label = None   # a design's: what was traced (traced())
    args.format = args.format or FORMATS[0]
    fmts = [args.format] + ([f for f in FORMATS if f != args.format] if args.compare else [])
    if design:
        args.format = design.datapath.name
        if args.at and insight(design.datapath).trace is not None:
            raise FlannError(f"{args.model}: --at lists the error at one-input voltages; a two-input "
                             "design's error at recordings is flann eval MODEL REC --design DIR")
        # the label names the datapath and, for a family, its member; the JSON keeps the number format
        label = traced(design)
        results = {args.format: trace_design(design)}
    else:
        results = {f: run_trace(model, f, **_options(args, f)) for f in fmts}
    if args.hdl:
        for f, r in results.items():
            info(args, f"simulating the {f} design over every input code ...")
            with cores_limited(args.jobs), tempfile.TemporaryDirectory(prefix="flann-trace-") as tmp:
                if design:
                    check_design_hdl(r, design, tmp)
                else:
                    check_hdl(r, args.model, _options(args, f), tmp)
    points = None
    if args.at:
        rec = read_recordings(args.at, announce=not args.quiet)
        points = {f: r.at_voltages(rec.voltage_v) for f, r in results.items()}
    if args.plot:
        if args.compare:
            plot_compare(results, args.plot, points, title=f"hardware − golden: {args.model}",
                         points_label=f"inputs of {Path(args.at).name}" if args.at else "")
        else:
            results[args.format].plot(args.plot, title=f"flann trace {args.model} ({label or args.format})")
    if args.json:
        out = {f: r.to_dict() for f, r in results.items()} if args.compare else results[args.format].to_dict()
        if not args.compare:   # a model's trace is of the datapath of its number format
            out.update(datapath=design.datapath.name if design else args.format, traced=label or args.format)
        if points:
            out = {"trace": out, "at": points}
        if emit_json(args, out):
            return 0
    for f, r in results.items():
        print((dataclasses.replace(r, fmt=label) if design else r).text())
        print()
    if points:
        print(f"at the input voltages of {args.at} (nearest input code):")
        head = f"{'V':>8} {'code':>6} {'golden mm':>10}" + "".join(f" {f + ' err mm':>16}" for f in points)
        print(head)
        first = next(iter(points.values()))
        for k, row in enumerate(first):
            line = f"{row['voltage_v']:>8.3f} {row['code']:>6d} {row['golden_mm']:>10.4f}"
            line += "".join(f" {points[f][k]['error_mm']:>16.4f}" for f in points)
            print(line)
        for f, rows in points.items():
            m = max(abs(r["error_mm"]) for r in rows)
            print(f"  {f}: max |error| at these points {m:.4f} mm")
    if args.plot:
        print(f"plot: {args.plot}")
    return 0
