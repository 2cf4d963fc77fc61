"""Render ``flann_seed_top`` from a :class:`~flann.hardware.seed.spec.SeedSpec`; write it with its manifest."""

from __future__ import annotations

from ... import __version__
from ...numeric.fixed import bits_literal
from ...textgen import template
from ..header import header
from ..manifest import write_design
from .spec import ENTITY, SeedSpec

SEED_FILE = f"{ENTITY}.vhd"


def context(s: SeedSpec) -> dict:
    W = s.word
    wd = s.widths
    wf = s.word_fmt
    return dict(
        entity=ENTITY, terms=s.terms, n_adders=s.n_adders, word=W, word_type=wf.vhdl_type,
        latency=s.latency_cycles,
        in_bits=s.input_bits, shift=s.shift, norm_guard=s.norm_guard,
        clamp_lo=bits_literal(s.clamp_lo, s.input_bits), clamp_hi=bits_literal(s.clamp_hi, s.input_bits),
        ka=bits_literal(s.ka, wd["ka_bits"]), kb=bits_literal(s.kb, wd["norm_bits"]),
        v_max=bits_literal(wf.max_int, wd["norm_bits"]), v_min=bits_literal(wf.min_int, wd["norm_bits"]),
        depth=1 << s.addr_bits, addr_bits=s.addr_bits,
        addr_lsb=W - s.addr_bits,  # lowest bit of the table address (the phase's top addr_bits bits)
        table=[wf.literal(t) for t in s.table],
        harmonics=s.harmonics,
        phase_offsets=[bits_literal(p, W, False) for p in s.phase_offsets],
        weights=[wf.literal(w) for w in s.weights_q],
        rounds=[bits_literal(r, wd["prod_bits"]) for r in s.rounds],
        levels=s.levels, n_levels=len(s.levels), nodes=s.nodes, **wd,
    )


def render(s: SeedSpec) -> dict[str, str]:
    """{file name: VHDL text}."""
    text = template("hardware/seed/templates/seed_parallel.vhd.j2").render(
        h=header(SEED_FILE, "the seed paper's FLANN architecture, fully parallel, for comparison only",
                 "flann explore", s.to_dict(), s.model_sha256),
        **context(s))
    return {SEED_FILE: text}


DATAPATH = "seed"


def manifest(s: SeedSpec) -> dict:
    return {
        "top": ENTITY,
        "datapath": DATAPATH,
        "files": [SEED_FILE],
        "input_bits": s.input_bits,
        "input_lsb_v": s.input_lsb_v,
        "output_bits": s.word,
        "output_lsb_mm": s.output_lsb_mm,
        "latency_cycles": s.latency_cycles,
        "cycles_per_sample": 1,
        "generator_version": __version__,
        "spec": s.to_dict(),
        "model_sha256": s.model_sha256,
    }


def write(s: SeedSpec, out_dir) -> dict:
    return write_design(render(s), manifest(s), out_dir)


__all__ = ["ENTITY", "SEED_FILE", "context", "render", "manifest", "write"]
