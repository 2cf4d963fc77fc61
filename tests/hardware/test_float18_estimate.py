"""The float18 resource estimate (what `flann ise` refuses or recommends a part by)."""

from __future__ import annotations

import pytest

from flann.hardware.float18.datapath import DATAPATH
from flann.hardware.target import parse_part
from flann.implement.synth import Resources, shortfall, smallest_fit

# Measured, not computed: `flann synth DIR --json --no-netlist-check` (GHDL + Yosys
# synth_xilinx -family xcv, abc full, xc2s200-pq208-5) of float18 designs generated from
# models trained on one invented sensor recording (12-bit, +-25 mm), run for this test with
# bench/bench_float18.py --estimate-vs-synth; the spec is each design's manifest.json spec.
# (LUT4, FF, block RAM, user I/O)
MEASURED = {
    "5 terms lms, 8-bit": (
        dict(terms=5, input_bits=8, phase_bits=14, table_addr_bits=6, interp=True, dq_bits=7,
             value="ufix<12,1,rnd,sat>", slope="ufix<6,0,rnd,sat>", term="sfix<13,2,rnd,sat>"),
        (1497, 403, 1, 31)),
    "11 terms lms, 8-bit": (
        dict(terms=11, input_bits=8, phase_bits=15, table_addr_bits=6, interp=True, dq_bits=8,
             value="ufix<13,1,rnd,sat>", slope="ufix<7,0,rnd,sat>", term="sfix<14,2,rnd,sat>"),
        (1547, 425, 1, 31)),
    "25 terms, 12-bit": (
        dict(terms=25, input_bits=12, phase_bits=20, table_addr_bits=8, interp=True, dq_bits=11,
             value="ufix<18,1,rnd,sat>", slope="ufix<10,0,rnd,sat>", term="sfix<19,2,rnd,sat>"),
        (1969, 494, 2, 35)),
    "51 terms, 12-bit": (
        dict(terms=51, input_bits=12, phase_bits=21, table_addr_bits=8, interp=True, dq_bits=12,
             value="ufix<18,1,rnd,sat>", slope="ufix<10,0,rnd,sat>", term="sfix<19,2,rnd,sat>"),
        (2058, 503, 2, 35)),
    "auto (61 terms), 8-bit": (
        dict(terms=61, input_bits=8, phase_bits=25, table_addr_bits=10, interp=True, dq_bits=13,
             value="ufix<21,1,rnd,sat>", slope="ufix<11,0,rnd,sat>", term="sfix<22,2,rnd,sat>"),
        (2093, 495, 7, 31)),
    "auto (61 terms), 10-bit": (
        dict(terms=61, input_bits=10, phase_bits=26, table_addr_bits=10, interp=True, dq_bits=14,
             value="ufix<23,1,rnd,sat>", slope="ufix<13,0,rnd,sat>", term="sfix<24,2,rnd,sat>"),
        (2245, 514, 8, 33)),
}
# an estimate that refuses or recommends a part errs high, by no more than this
HIGH_BY_AT_MOST = 1.10


def _estimate(spec: dict) -> dict:
    return DATAPATH.estimate({"spec": spec})


@pytest.mark.parametrize("name", MEASURED)
def test_estimate_is_high_but_close_to_synthesis(name):
    spec, (luts, ffs, brams, _io) = MEASURED[name]
    est = _estimate(spec)
    assert luts <= est["luts"] <= HIGH_BY_AT_MOST * luts, est
    assert ffs <= est["ffs"] <= HIGH_BY_AT_MOST * ffs, est
    assert brams <= est["brams"] <= brams + 2, est


@pytest.mark.parametrize("name", MEASURED)
def test_the_part_recommended_is_one_synthesis_accepts(name):
    """`flann ise` names the smallest part the estimate fits; the synthesised design must fit it."""
    spec, (luts, ffs, brams, io) = MEASURED[name]
    est = _estimate(spec)
    res = Resources(luts=est["luts"], ffs=est["ffs"], brams=est["brams"], carry=0, xorcy=0, mult_and=0,
                    muxf5=0, muxf6=0, io=io)
    part = smallest_fit(res, parse_part("xc2s15-tq144-5"))
    measured = Resources(luts=luts, ffs=ffs, brams=brams, carry=0, xorcy=0, mult_and=0, muxf5=0, muxf6=0, io=io)
    assert part is not None and not shortfall(measured, part), part


def test_estimate_grows_with_terms_and_input_bits():
    spec = dict(MEASURED["11 terms lms, 8-bit"][0])
    last = None
    for terms in (5, 11, 25, 51, 61, 101):
        est = _estimate(dict(spec, terms=terms))
        if last is not None:
            # past the words Yosys keeps in LUTs the weight ROM moves to block RAM
            assert est["ffs"] >= last["ffs"] and est["brams"] >= last["brams"]
            assert est["luts"] >= last["luts"] or est["brams"] > last["brams"]
        last = est
    small, wide = _estimate(dict(spec, input_bits=8)), _estimate(dict(spec, input_bits=12))
    assert wide["luts"] > small["luts"] and wide["ffs"] > small["ffs"]
