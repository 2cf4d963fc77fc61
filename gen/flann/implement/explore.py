"""Design space of the FLANN datapath on a Spartan-II, and the seed paper's architecture.

``explore(model_path)`` generates each candidate with :mod:`flann.hardware.fixed.render`, measures it with
the same flow as ``flann synth`` (GHDL synthesis + Yosys ``synth_xilinx -family xcv``) and
takes the accuracy from the bit-true twin over every input code.  The seed architecture
(51 expansion outputs, 51 multipliers, 50 two-input adders, all in parallel) is rendered
from ``templates/seed_parallel.vhd.j2`` in 18-bit fixed point and measured the same way;
its accuracy comes from :class:`SeedParallel`, the template's bit-true twin.
"""

from __future__ import annotations

import json
import math
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import __version__
from ..errors import FlannError, SpecError
from ..fileio import atomic_directory
from ..textgen import template
from ..numeric.fixed import bits_literal
from ..golden.model import FlannModel, load_model, model_sha256, term_kind

CLOCK_HZ = 50e6
SEED_FILE = "flann_seed_parallel.vhd"


# ----------------------------------------------------------------------------- seed twin
@dataclass(frozen=True)
class SeedParallel:
    """The seed architecture in ``word``-bit fixed point: constants and bit-true arithmetic.

    Formats (all ``word`` = 18 bits, signed): v in Q1.17 (saturated), terms with 16 fraction
    bits, weights with ``weight_frac`` fraction bits, products rounded to the accumulator
    format with ``acc_frac`` fraction bits, chosen so that bias + sum |w_i| fits: the adder
    tree cannot overflow.  Phase of harmonic m: (m v) mod 2 on ``word`` bits.
    """

    model: FlannModel = field(repr=False)
    input_bits: int
    input_lsb_v: float
    clamp_lo: int
    clamp_hi: int
    word: int = 18
    addr_bits: int = 10
    norm_guard: int = 16
    model_sha256: str = ""

    # ---- derived constants ----------------------------------------------------------------
    @property
    def terms(self) -> int:
        return self.model.terms

    @property
    def frac_v(self) -> int:
        return self.word - 1

    @property
    def frac_t(self) -> int:
        return self.word - 2

    @property
    def ka(self) -> int:
        return round(self.input_lsb_v / self.model.input_scale_v * 2.0 ** (self.frac_v + self.norm_guard))

    @property
    def kb(self) -> int:
        off = -self.model.input_offset_v / self.model.input_scale_v
        return round(off * 2.0 ** (self.frac_v + self.norm_guard)) + (1 << (self.norm_guard - 1))

    @property
    def weight_frac(self) -> int:
        wmax = max(abs(w) for w in self.model.weights)
        return math.floor(math.log2(((1 << (self.word - 1)) - 1) / wmax))

    @property
    def weights_q(self) -> list[int]:
        return [round(w * 2.0 ** self.weight_frac) for w in self.model.weights]

    @property
    def acc_frac(self) -> int:
        bound = abs(self.model.bias) + sum(abs(w) for w in self.model.weights)
        room = (1 << (self.word - 1)) - 1 - self.terms  # one rounding LSB per product
        return math.floor(math.log2(room / bound))

    @property
    def shift(self) -> int:
        s = self.frac_t + self.weight_frac - self.acc_frac
        if s < 1:
            raise SpecError(f"seed architecture: product shift {s} < 1 (weights too small for {self.word} bits)")
        return s

    @property
    def bias_q(self) -> int:
        return round(self.model.bias * 2.0 ** (self.frac_t + self.weight_frac))

    @property
    def rounds(self) -> list[int]:
        half = 1 << (self.shift - 1)
        return [half + self.bias_q] + [half] * (self.terms - 1)

    @property
    def table(self) -> list[int]:
        n = 1 << self.addr_bits
        k = np.arange(n)
        vals = np.round(np.sin(2 * np.pi * (k + 0.5) / n) * 2.0 ** self.frac_t).astype(np.int64)
        return [int(v) for v in np.clip(vals, -(1 << (self.word - 1)), (1 << (self.word - 1)) - 1)]

    @property
    def harmonics(self) -> list[int]:
        return [term_kind(i)[1] for i in range(1, self.terms)]

    @property
    def phase_offsets(self) -> list[int]:
        quarter = 1 << (self.word - 2)  # pi/2 in units of pi with word-1 fraction bits
        return [quarter if term_kind(i)[0] == "cos" else 0 for i in range(1, self.terms)]

    @property
    def levels(self) -> list[dict]:
        """Adder tree levels: input offset, output offset, pairs, odd pass-through."""
        out, inp, n, nxt = [], 0, self.terms, self.terms
        while n > 1:
            pairs, odd = n // 2, n % 2
            out.append({"inp": inp, "out": nxt, "pairs": pairs, "odd": bool(odd)})
            inp, n = nxt, pairs + odd
            nxt = inp + n
        return out

    @property
    def n_adders(self) -> int:
        return sum(lv["pairs"] for lv in self.levels)

    @property
    def nodes(self) -> int:
        lv = self.levels
        return (lv[-1]["out"] + 1) if lv else self.terms

    @property
    def latency_cycles(self) -> int:
        return 5 + len(self.levels)

    @property
    def output_lsb_mm(self) -> float:
        return 2.0 ** -self.acc_frac

    def _widths(self) -> dict:
        ka_bits = max(2, int(self.ka).bit_length() + 1)
        norm_bits = max(self.input_bits + ka_bits, int(abs(self.kb)).bit_length() + 1) + 1
        harm_bits = max(self.harmonics, default=1).bit_length() + 1
        pmax = (1 << (self.word - 1)) ** 2 + max(abs(r) for r in self.rounds)
        prod_bits = max(2 * self.word, pmax.bit_length() + 1)
        return dict(ka_bits=ka_bits, norm_bits=norm_bits, harm_bits=harm_bits, prod_bits=prod_bits)

    # ---- bit-true twin ----------------------------------------------------------------------
    def process(self, codes) -> tuple[np.ndarray, np.ndarray]:
        """(out_data, out_sat) for ADC codes, exactly as the template computes them."""
        c_in = np.asarray(codes, dtype=np.int64)
        c = np.clip(c_in, self.clamp_lo, self.clamp_hi)
        W = self.word
        full = (c * self.ka + self.kb) >> self.norm_guard
        v = np.clip(full, -(1 << (W - 1)), (1 << (W - 1)) - 1)
        table = np.asarray(self.table, dtype=np.int64)
        terms = [v >> 1]
        for m, off in zip(self.harmonics, self.phase_offsets):
            theta = ((v * m) + off) & ((1 << W) - 1)
            terms.append(table[theta >> (W - self.addr_bits)])
        acc = np.zeros_like(v)
        lim = 1 << (W - 1)
        for t, w, r in zip(terms, self.weights_q, self.rounds):
            p = (t * w + r) >> self.shift
            if np.any((p < -lim) | (p >= lim)):
                raise SpecError("seed architecture: a product overflows the accumulator format")
            acc = acc + p
        if np.any((acc < -lim) | (acc >= lim)):
            raise SpecError("seed architecture: the adder tree overflows")
        return acc, c != c_in

    def error_vs_float(self) -> dict:
        codes = np.arange(self.clamp_lo, self.clamp_hi + 1, dtype=np.int64)
        out, _ = self.process(codes)
        ref = self.model.predict(codes * self.input_lsb_v)
        e = float(np.max(np.abs(out * self.output_lsb_mm - ref)))
        return {"max_err_lsb": e / self.output_lsb_mm, "max_err_mm": e, "codes": int(codes.size)}

    # ---- rendering ----------------------------------------------------------------------------
    def spec_dict(self) -> dict:
        return {
            "architecture": "seed_parallel",
            "number_format": f"fixed{self.word}",
            "terms": self.terms,
            "multipliers": self.terms,
            "adders": self.n_adders,
            "input_bits": self.input_bits,
            "input_lsb_v": self.input_lsb_v,
            "clamp_codes": [self.clamp_lo, self.clamp_hi],
            "table_addr_bits": self.addr_bits,
            "weight_frac_bits": self.weight_frac,
            "acc_frac_bits": self.acc_frac,
            "output_lsb_mm": self.output_lsb_mm,
        }

    def render(self) -> str:
        W = self.word
        wd = self._widths()
        lim = (1 << (W - 1)) - 1
        ctx = dict(
            terms=self.terms, n_adders=self.n_adders, word=W, latency=self.latency_cycles,
            in_bits=self.input_bits, shift=self.shift, norm_guard=self.norm_guard,
            clamp_lo=bits_literal(self.clamp_lo, self.input_bits),
            clamp_hi=bits_literal(self.clamp_hi, self.input_bits),
            ka=bits_literal(self.ka, wd["ka_bits"]), kb=bits_literal(self.kb, wd["norm_bits"]),
            v_max=bits_literal(lim, wd["norm_bits"]), v_min=bits_literal(-lim - 1, wd["norm_bits"]),
            depth=1 << self.addr_bits, addr_bits=self.addr_bits,
            table=[bits_literal(t, W) for t in self.table],
            harmonics=self.harmonics,
            phase_offsets=[bits_literal(p, W, False) for p in self.phase_offsets],
            weights=[bits_literal(w, W) for w in self.weights_q],
            rounds=[bits_literal(r, wd["prod_bits"]) for r in self.rounds],
            levels=self.levels, nodes=self.nodes, **wd,
        )
        header = dict(
            file=SEED_FILE, version=__version__, model_sha256=self.model_sha256 or "(not from a file)",
            spec_lines=[f"{k} = {json.dumps(v)}" for k, v in self.spec_dict().items()],
        )
        return template("hardware/seed/templates/seed_parallel.vhd.j2").render(h=header, **ctx)

    def manifest(self) -> dict:
        return {
            "top": "flann_top",
            "files": [SEED_FILE],
            "input_bits": self.input_bits,
            "input_lsb_v": self.input_lsb_v,
            "output_bits": self.word,
            "output_lsb_mm": self.output_lsb_mm,
            "latency_cycles": self.latency_cycles,
            "cycles_per_sample": 1,
            "generator_version": __version__,
            "spec": self.spec_dict(),
            "model_sha256": self.model_sha256,
        }

    def write(self, out_dir) -> dict:
        man = self.manifest()
        text = self.render()
        with atomic_directory(out_dir) as tmp:
            (Path(tmp) / SEED_FILE).write_text(text, newline="")
            (Path(tmp) / "manifest.json").write_text(json.dumps(man, indent=2) + "\n", newline="")
        return man


def seed_for(model_path, **spec_options) -> SeedParallel:
    """The seed architecture with the same ADC scaling and clamp as our design for this model."""
    from ..hardware.fixed import render as hdlgen

    spec = hdlgen.load(model_path, check_device=False, **spec_options)
    path = Path(model_path)
    return SeedParallel(
        model=load_model(path), input_bits=spec.input_bits, input_lsb_v=spec.input_lsb_v,
        clamp_lo=spec.clamp_lo, clamp_hi=spec.clamp_hi, model_sha256=model_sha256(path),
    )


# ----------------------------------------------------------------------------- design space
WIDTH_PRESETS = ("budget", "narrow")
NARROW_BITS = 4  # fraction bits taken off terms and weights in the "narrow" preset


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


def _width_options(model_path, preset: str, base: dict) -> dict:
    if preset == "budget":
        return {}
    if preset == "narrow":
        from ..hardware.fixed import render as hdlgen

        ref = hdlgen.load(model_path, check_device=False, **base)
        return {
            "term_frac_bits": max(4, ref.term_fmt.frac_bits - NARROW_BITS),
            "weight_frac_bits": max(0, ref.weight_fmt.frac_bits - NARROW_BITS),
        }
    raise FlannError(f"width preset {preset!r}: allowed {', '.join(WIDTH_PRESETS)}")


def _measure(row: Row, design_dir: Path, device: str, work: Path | None, abc: str) -> None:
    from .synth import synthesize

    rep = synthesize(design_dir, device, work=work, abc=abc)
    d = rep.to_dict()
    row.luts, row.ffs, row.brams = d["luts"], d["ffs"], d["brams"]
    row.fits, row.smallest_device = d["fits"], d["smallest_device"]
    if d["warnings"]:
        row.note = (row.note + "; " if row.note else "") + f"{len(d['warnings'])} yosys warning(s)"


def explore(model_path, device: str = "xc2s200-pq208-5", lanes=(1, 2, 4), styles=("lut", "shiftadd"),
            widths=WIDTH_PRESETS, seed: bool = True, progress: bool = True, abc: str = "fast",
            adc: dict | None = None) -> list[Row]:
    """Generate, synthesise and score each candidate; the seed architecture last.  ``adc``:
    input_bits / input_lsb_v of the converter, as flann gen takes them."""
    import warnings as _w

    from ..hardware.fixed import render as hdlgen
    from ..hardware.target import parse_part
    from ..hardware.fixed.spec import CLOCK_HZ as SPEC_CLOCK
    from ..hardware.fixed.twin import FlannTop

    parse_part(device)
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
                base = dict(lanes=lane, mult_style=style, **(adc or {}))
                with _w.catch_warnings(record=True) as caught:
                    _w.simplefilter("always")
                    opts = {**base, **_width_options(model_path, preset, base)}
                    spec = hdlgen.load(model_path, check_device=False, device=device, **opts)
                if not spec.analysis.get("guaranteed_1lsb", True):
                    row.note = f"worst-case bound {spec.analysis['bound_total_lsb']:.2f} LSB > 1"
                elif caught:
                    row.note = "; ".join(str(w.message) for w in caught)
                err = FlannTop(spec).error_vs_float()
                row.cycles_per_sample = spec.cycles_per_sample
                row.samples_per_s = SPEC_CLOCK / spec.cycles_per_sample
                row.max_err_lsb, row.max_err_mm = err["max_err_lsb"], err["max_err_mm"]
                row.output_lsb_mm = spec.output_lsb_mm
                ddir = Path(tmp) / f"d{k}"
                hdlgen.write(spec, ddir)
                _measure(row, ddir, device, None, abc)
            except FlannError as exc:
                row.note = (row.note + "; " if row.note else "") + str(exc)
    if seed:
        rows += seed_rows(model_path, device, abc=abc, progress=progress)
    return rows


SEED_SCALING_TERMS = (5, 9, 17)


def seed_rows(model_path, device: str, abc: str = "fast", terms=SEED_SCALING_TERMS,
              progress: bool = True) -> list[Row]:
    """The seed architecture: measured at a few term counts, extrapolated to the model's.

    The 51-term parallel design is 51 copies of one slice (table look-up, constant
    multiplier, adder); Yosys needs hours for all of them at once, so the slices are
    measured with the first 5, 9 and 17 terms of the model and a least-squares line per
    resource gives the figure at the full term count (stated in the row's note).
    """
    import dataclasses

    full = seed_for(model_path)
    rows, pts = [], []
    with tempfile.TemporaryDirectory(prefix="flann-seed-") as tmp:
        for k, n in enumerate(terms, 1):
            if progress:
                print(f"explore: seed architecture, first {n} terms [{k}/{len(terms)}]", file=sys.stderr)
            s = dataclasses.replace(full, model=dataclasses.replace(full.model, weights=full.model.weights[:n]))
            row = Row(f"seed, first {n} terms", None, "constant", f"fixed{s.word}", cycles_per_sample=1,
                      samples_per_s=CLOCK_HZ)
            ddir = Path(tmp) / f"seed{n}"
            s.write(ddir)
            try:
                _measure(row, ddir, device, None, abc)
                pts.append((n, row.luts, row.ffs, row.brams))
            except FlannError as exc:
                row.note = str(exc)
            rows.append(row)
    err = full.error_vs_float()
    row = Row(f"seed (paper), {full.terms} terms", None, "constant", f"fixed{full.word}", cycles_per_sample=1,
              samples_per_s=CLOCK_HZ, max_err_lsb=err["max_err_lsb"], max_err_mm=err["max_err_mm"],
              output_lsb_mm=full.output_lsb_mm)
    if len(pts) >= 2:
        n = np.array([p[0] for p in pts], dtype=float)
        est = []
        for col in (1, 2, 3):
            y = np.array([p[col] for p in pts], dtype=float)
            b, a = np.polyfit(n, y, 1)
            est.append(int(round(a + b * full.terms)))
        row.luts, row.ffs, row.brams = est
        from ..hardware.target import parse_part
        from .synth import Resources, smallest_fit, shortfall

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
def float18_rows(model_path, device: str, abc: str = "fast", seed_terms: int | None = None,
                 progress: bool = True) -> list[Row]:
    """The paper's 18-bit floating point: the project's serial float18 design, and the
    seed architecture's arithmetic in float18 (N multipliers + N-1 adders, each block
    synthesised once with this flow and multiplied by its count; tables not included).
    """
    from .explore_float18 import measure
    from ..hardware.float18.render import render_block
    from ..hardware.target import parse_part
    from .synth import Resources, shortfall, smallest_fit, synthesize

    rows = []
    if progress:
        print("explore: float18 design (serial)", file=sys.stderr)
    r = Row("float18 (serial)", 1, "float18", "float18")
    try:
        m = measure(model_path, device)
        r.luts, r.ffs, r.brams, r.fits = m["luts"], m["ffs"], m["brams"], m["fits"]
        r.cycles_per_sample, r.samples_per_s = m["cycles_per_sample"], m["samples_per_s_at_50mhz"]
        r.max_err_mm = m["max_err_mm"]
        r.note = f"dominant error: {m['dominant_error_stage']}"
        part = parse_part(device)
        best = smallest_fit(Resources(m["luts"], m["ffs"], m["brams"], 0, 0, 0, 0, 0, 0), part)
        r.smallest_device = best.name if best else None
    except FlannError as exc:
        r.note = str(exc)
    rows.append(r)

    n = seed_terms or load_model(model_path).terms
    per = {}
    with tempfile.TemporaryDirectory(prefix="flann-f18blk-") as tmp:
        for kind in ("mul", "add"):
            if progress:
                print(f"explore: float18 {kind} block", file=sys.stderr)
            name, text = render_block(kind)
            d = Path(tmp) / kind
            d.mkdir()
            (d / name).write_text(text)
            (d / "manifest.json").write_text(json.dumps({"top": name[:-4], "files": [name]}))
            rep = synthesize(d, device, abc=abc)
            per[kind] = (rep.resources.luts, rep.resources.ffs, rep.resources.brams)
    luts = n * per["mul"][0] + (n - 1) * per["add"][0]
    ffs = n * per["mul"][1] + (n - 1) * per["add"][1]
    brams = n * per["mul"][2] + (n - 1) * per["add"][2]
    part = parse_part(device)
    res = Resources(luts, ffs, brams, 0, 0, 0, 0, 0, 0)
    best = smallest_fit(res, part)
    rows.append(Row(
        f"seed arithmetic in float18, {n} terms", None, "float18", "float18", luts=luts, ffs=ffs, brams=brams,
        cycles_per_sample=1, samples_per_s=CLOCK_HZ, fits=not shortfall(res, part),
        smallest_device=best.name if best else None,
        note=(f"{n} x flann_f18_mul ({per['mul'][0]} LUT4, {per['mul'][1]} FF) + {n - 1} x flann_f18_add "
              f"({per['add'][0]} LUT4, {per['add'][1]} FF), each synthesised once; expansion tables not counted"),
    ))
    return rows
