"""Design space of the FLANN datapath on a Spartan-II, and the seed paper's architecture.

``explore(model_path)`` generates each candidate with :mod:`flann.hardware.fixed.render`, measures it with
the same flow as ``flann synth`` (GHDL synthesis + Yosys ``synth_xilinx -family xcv``) and
takes the accuracy from the bit-true twin over every input code.  The seed architecture
(51 expansion outputs, 51 multipliers, 50 two-input adders, all in parallel;
:mod:`flann.hardware.seed`) is measured the same way; its accuracy comes from its twin.
"""

from __future__ import annotations

import dataclasses
import sys
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import FlannError
from ..golden.model import load_model
from ..hardware.fixed import render as hdlgen
from ..hardware.fixed.spec import check_mult_style, max_lanes
from ..hardware.fixed.twin import FlannTop
from ..hardware.registry import FLOAT18
from ..hardware.seed import render as seed_render
from ..hardware.seed.spec import derive_seed_spec
from ..hardware.seed.twin import FlannSeedTop
from ..hardware.target import CLOCK_HZ, DEFAULT_PART, parse_part
from ..implement.synth import Resources, shortfall, smallest_fit, synthesize


# ----------------------------------------------------------------------------- design space
WIDTH_PRESETS = ("budget", "narrow")
NARROW_BITS = 4  # fraction bits taken off terms and weights in the "narrow" preset
MIN_TERM_FRAC_BITS = 4  # the fewest term fraction bits the fixed datapath takes (spec's range)


class NotApplicable(Exception):
    """A row that does not apply to this model: said in its note (``skipped: ...``), not run."""


@dataclass
class Row:
    design: str
    lanes: int | None
    mult_style: str
    widths: str
    luts: int | None = None
    ffs: int | None = None
    brams: int | None = None
    cycles_per_sample: int | None = None
    samples_per_s: float | None = None
    max_err_lsb: float | None = None
    max_err_mm: float | None = None
    output_lsb_mm: float | None = None
    fits: bool | None = None
    smallest_device: str | None = None
    note: str = ""

    def to_dict(self) -> dict:
        return dict(self.__dict__)


def check_width_preset(preset: str) -> None:
    if preset not in WIDTH_PRESETS:
        raise FlannError(f"width preset {preset!r}: allowed {', '.join(WIDTH_PRESETS)}")


def _width_options(model_path, preset: str, base: dict) -> dict:
    if preset == "budget":
        return {}
    if preset == "narrow":
        ref = hdlgen.load(model_path, check_device=False, **base)
        if ref.term_fmt.frac_bits <= MIN_TERM_FRAC_BITS:
            # sin/cos weights of (nearly) nothing: taking bits off the weights alone breaks
            # the products' rounding (an internal width constraint), and saves nothing real
            wsum = float(np.abs(np.asarray(ref.model.weights[1:], dtype=float)).sum())
            raise NotApplicable(
                f"nothing to narrow: this {load_model(model_path).terms}-term model's sin/cos weights "
                f"sum to {wsum:.3g} mm, so its terms already have the fewest fraction bits the "
                f"datapath takes ({MIN_TERM_FRAC_BITS})")
        return {
            "term_frac_bits": max(MIN_TERM_FRAC_BITS, ref.term_fmt.frac_bits - NARROW_BITS),
            "weight_frac_bits": max(0, ref.weight_fmt.frac_bits - NARROW_BITS),
        }
    raise AssertionError(f"width preset {preset!r} has no options")  # a preset added without its options


def _measure(row: Row, design_dir: Path, device: str, work: Path | None, abc: str) -> None:
    rep = synthesize(design_dir, device, work=work, abc=abc)
    d = rep.to_dict()
    row.luts, row.ffs, row.brams = d["luts"], d["ffs"], d["brams"]
    row.fits, row.smallest_device = d["fits"], d["smallest_device"]
    if d["yosys_warnings"]:
        row.note = (row.note + "; " if row.note else "") + f"{len(d['yosys_warnings'])} yosys warning(s)"


DEFAULT_LANES, DEFAULT_STYLES = (1, 2, 4), ("lut", "shiftadd")


def explore(model_path, device: str = DEFAULT_PART, lanes=DEFAULT_LANES, styles=DEFAULT_STYLES,
            widths=WIDTH_PRESETS, seed: bool = True, progress: bool = True, abc: str = "fast",
            adc: dict | None = None) -> list[Row]:
    """Generate, synthesise and score each candidate; the seed architecture last.  ``adc``:
    input_bits / input_lsb_v of the converter, as flann gen takes them."""
    parse_part(device)
    # a bad preset or style is the caller's mistake, refused before any row is built
    for preset in widths:
        check_width_preset(preset)
    for style in styles:
        check_mult_style(style)
    terms = load_model(model_path).terms
    rows: list[Row] = []
    combos = [(l, s, w) for w in widths for s in styles for l in lanes]
    with tempfile.TemporaryDirectory(prefix="flann-explore-") as tmp:
        for k, (lane, style, preset) in enumerate(combos, 1):
            row = Row("ours", lane, style, preset)
            rows.append(row)
            if progress:
                print(f"explore [{k}/{len(combos)}] lanes={lane} mult={style} widths={preset}",
                      file=sys.stderr)
            try:
                if lane > max_lanes(terms):
                    raise NotApplicable(f"{lane} lanes: this {terms}-term model has "
                                        f"{max_lanes(terms)} sin/cos term(s) to share among them")
                base = dict(lanes=lane, mult_style=style, **(adc or {}))
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always")
                    opts = {**base, **_width_options(model_path, preset, base)}
                    spec = hdlgen.load(model_path, check_device=False, device=device, **opts)
                if not spec.analysis.get("guaranteed_1lsb", True):
                    row.note = f"worst-case bound {spec.analysis['bound_total_lsb']:.2f} LSB > 1"
                elif caught:
                    row.note = "; ".join(str(w.message) for w in caught)
                err = FlannTop(spec).error_vs_float()
                row.cycles_per_sample = spec.cycles_per_sample
                row.samples_per_s = CLOCK_HZ / spec.cycles_per_sample
                row.max_err_lsb, row.max_err_mm = err["max_err_lsb"], err["max_err_mm"]
                row.output_lsb_mm = spec.output_lsb_mm
                ddir = Path(tmp) / f"d{k}"
                hdlgen.write(spec, ddir)
                _measure(row, ddir, device, None, abc)
            except NotApplicable as exc:
                row.note = f"skipped: {exc}"
            except FlannError as exc:
                row.note = (row.note + "; " if row.note else "") + str(exc)
    if seed:
        rows += seed_rows(model_path, device, abc=abc, progress=progress)
    return rows


SEED_SCALING_TERMS = (5, 9, 17)
SEED_MIN_TERMS = 2   # the seed's VHDL has a sin/cos table and multiplier per term after the first


def seed_rows(model_path, device: str, abc: str = "fast", terms=SEED_SCALING_TERMS,
              progress: bool = True) -> list[Row]:
    """The seed architecture: measured at a few term counts, extrapolated to the model's.

    The 51-term parallel design is 51 copies of one slice (table look-up, constant
    multiplier, adder); Yosys needs hours for all of them at once, so the slices are
    measured with the first 5, 9 and 17 terms of the model and a least-squares line per
    resource gives the figure at the full term count (stated in the row's note).  A model
    with no more terms than the largest slice is synthesised whole instead.
    """
    full = derive_seed_spec(model_path)
    if full.terms < SEED_MIN_TERMS or full.terms <= max(terms):
        return [_seed_whole(full, device, abc, terms, progress)]
    rows, pts = [], []
    with tempfile.TemporaryDirectory(prefix="flann-seed-") as tmp:
        for k, n in enumerate(terms, 1):
            if progress:
                print(f"explore: seed architecture, first {n} terms [{k}/{len(terms)}]", file=sys.stderr)
            s = dataclasses.replace(full, model=dataclasses.replace(full.model, weights=full.model.weights[:n]))
            row = Row(f"seed, first {n} terms", None, "constant", f"fixed{s.word}", cycles_per_sample=1,
                      samples_per_s=CLOCK_HZ)
            ddir = Path(tmp) / f"seed{n}"
            seed_render.write(s, ddir)
            try:
                _measure(row, ddir, device, None, abc)
                pts.append((n, row.luts, row.ffs, row.brams))
            except FlannError as exc:
                row.note = str(exc)
            rows.append(row)
    row = _seed_row(full)
    if len(pts) >= 2:
        n = np.array([p[0] for p in pts], dtype=float)
        est = []
        for col in (1, 2, 3):
            y = np.array([p[col] for p in pts], dtype=float)
            b, a = np.polyfit(n, y, 1)
            est.append(int(round(a + b * full.terms)))
        row.luts, row.ffs, row.brams = est
        part = parse_part(device)
        res = Resources(luts=est[0], ffs=est[1], brams=est[2], carry=0, xorcy=0, mult_and=0, muxf5=0, muxf6=0,
                        io=0)
        row.fits = not shortfall(res, part)
        best = smallest_fit(res, part)
        row.smallest_device = best.name if best else None
        row.note = (f"extrapolated: least-squares line through the {'/'.join(str(p[0]) for p in pts)}-term "
                    "syntheses above")
    else:
        row.note = "too few seed syntheses succeeded to extrapolate"
    rows.append(row)
    return rows


def _seed_row(full) -> Row:
    """The seed architecture at the model's full term count, accuracy from its twin."""
    err = FlannSeedTop(full).error_vs_float()
    return Row(f"seed (paper), {full.terms} terms", None, "constant", f"fixed{full.word}", cycles_per_sample=1,
               samples_per_s=CLOCK_HZ, max_err_lsb=err["max_err_lsb"], max_err_mm=err["max_err_mm"],
               output_lsb_mm=full.output_lsb_mm)


def _seed_whole(full, device: str, abc: str, terms, progress: bool) -> Row:
    """A model with no more terms than the largest slice: the first-N-terms slices would be
    the whole design again, so it is measured as it is (one synthesis, nothing extrapolated);
    a straight line (1 term) has no sin/cos term to build the seed's tables from."""
    row = _seed_row(full)
    if full.terms < SEED_MIN_TERMS:
        row.note = (f"skipped synthesis: a {full.terms}-term model is a straight line, the seed "
                    "architecture has no sin/cos table or multiplier to build")
        return row
    if progress:
        print(f"explore: seed architecture, all {full.terms} terms", file=sys.stderr)
    with tempfile.TemporaryDirectory(prefix="flann-seed-") as tmp:
        ddir = Path(tmp) / "seed"
        seed_render.write(full, ddir)
        try:
            _measure(row, ddir, device, None, abc)
            row.note = (f"synthesised whole: its {full.terms} terms are no more than the largest "
                        f"slice ({max(terms)} terms) that longer models are extrapolated from"
                        + (f"; {row.note}" if row.note else ""))
        except FlannError as exc:
            row.note = str(exc)
    return row


def _fmt(x, spec: str = "") -> str:
    if x is None:
        return "—"
    if isinstance(x, bool):
        return "yes" if x else "no"
    return format(x, spec)


def markdown(rows: list[Row], device: str) -> str:
    head = ("| design | lanes | multiplier | widths | LUT4 | FF | BRAM | cycles/sample | samples/s @ 50 MHz "
            f"| max err (LSB) | max err (mm) | fits {device} | smallest Spartan-II | note |")
    sep = "|" + "---|" * 14
    lines = [head, sep]
    for r in rows:
        lines.append(
            f"| {r.design} | {_fmt(r.lanes)} | {r.mult_style} | {r.widths} | {_fmt(r.luts)} | {_fmt(r.ffs)} "
            f"| {_fmt(r.brams)} | {_fmt(r.cycles_per_sample)} | {_fmt(r.samples_per_s, ',.0f')} "
            f"| {_fmt(r.max_err_lsb, '.3f')} | {_fmt(r.max_err_mm, '.4f')} | {_fmt(r.fits)} "
            f"| {_fmt(r.smallest_device)} | {r.note} |"
        )
    return "\n".join(lines)


# ----------------------------------------------------------------------------- float18 rows
F18 = FLOAT18.number_format


