"""Spartan-II device table (flann.hardware.target) against the data sheet's own arithmetic.

Expected figures are typed in from DS001 here (CLB count x 4 LUT4 / 4 FF per CLB, block
RAMs, PQ208 user I/O), not read from the code under test.
"""

import pytest

from flann.hardware.target import DEVICES, parse_part, device
from flann.errors import FlannError

# DS001 Table 1: CLB array (rows x cols), total CLBs, block RAM bits; user I/O chart for PQ208.
DS001 = {
    "xc2s15": (8 * 12, 16 * 1024, None),
    "xc2s30": (12 * 18, 24 * 1024, 132),
    "xc2s50": (16 * 24, 32 * 1024, 140),
    "xc2s100": (20 * 30, 40 * 1024, 140),
    "xc2s150": (24 * 36, 48 * 1024, 140),
    "xc2s200": (28 * 42, 56 * 1024, 140),
}


def test_table_matches_ds001_per_clb_arithmetic():
    assert [d.name for d in DEVICES] == list(DS001)
    for d in DEVICES:
        clbs, bram_bits, pq208 = DS001[d.name]
        assert d.clbs == clbs
        assert d.luts == 4 * clbs and d.ffs == 4 * clbs  # 2 slices x (2 LUT4 + 2 FF)
        assert d.bram_bits == bram_bits and d.brams == bram_bits // 4096
        assert d.user_io("pq208") == pq208


def test_brief_figures():
    # LUT4/FF and block RAM counts as the device data sheets list them (DS001)
    assert [(d.luts, d.brams) for d in DEVICES] == [(384, 4), (864, 6), (1536, 8), (2400, 10), (3456, 12), (4704, 14)]


def test_parse_part():
    p = parse_part("XC2S200-PQ208-5")
    assert (p.device.name, p.package, p.speed, p.name) == ("xc2s200", "pq208", "5", "xc2s200-pq208-5")
    assert parse_part("xc2s50pq208-6").name == "xc2s50-pq208-6"


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("xc2s15-pq208-5", "not offered in pq208"),
        ("xc2s300-pq208-5", "unknown Spartan-II device"),
        ("xc2s200-pq208-7", "speed grade -7"),
        ("spartan", "DEVICE-PACKAGE-SPEED"),
    ],
)
def test_bad_parts_are_named(text, fragment):
    with pytest.raises(FlannError, match=fragment):
        parse_part(text)


def test_unknown_device():
    with pytest.raises(FlannError, match="allowed: xc2s15"):
        device("xc3s200")
