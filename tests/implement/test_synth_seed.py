"""The seed paper's fully parallel architecture (hardware/seed: SeedSpec, FlannSeedTop, flann_seed_top)."""

import dataclasses
import math
import shutil
import subprocess

import numpy as np
import pytest

from flann.hardware.seed import render
from flann.hardware.seed.render import SEED_FILE
from flann.hardware.seed.spec import SeedSpec
from flann.hardware.seed.twin import FlannSeedTop
from flann.golden.model import load_model

MODEL = "data/default_model.json"


def _seed(terms=None, **kw):
    m = load_model(MODEL)
    if terms is not None:
        m = dataclasses.replace(m, weights=m.weights[:terms])
    lsb = 0.00284
    return SeedSpec(model=m, input_bits=12, input_lsb_v=lsb,
                        clamp_lo=math.ceil(m.voltage_range_v[0] / lsb), clamp_hi=math.floor(m.voltage_range_v[1] / lsb), **kw)


def test_seed_structure_is_the_papers():
    s = _seed()
    assert s.terms == 51
    # a binary tree of two-input adders over 51 leaves has 51 - 1 internal nodes
    assert s.n_adders == 50
    assert len(s.levels) == math.ceil(math.log2(51)) == 6
    text = render.render(s)[SEED_FILE]
    assert text.count("g_lvl") == 2 * 6  # generate label + its end label per level
    assert "constant terms_c    : natural := 51;" in text
    assert "entity flann_seed_top is" in text and "flann_top" not in text.replace("flann_seed_top", "")
    assert render.manifest(s)["cycles_per_sample"] == 1 and render.manifest(s)["top"] == "flann_seed_top"
    assert FlannSeedTop(s).entity == "flann_seed_top" and FlannSeedTop(s).latency == s.latency_cycles


def test_seed_error_within_the_table_step_bound():
    s = _seed()
    err = FlannSeedTop(s).error_vs_float()
    m = s.model
    # full-wave table with 2^A midpoint samples: |sin error| <= pi / 2^A per trig term,
    # plus half an LSB per rounding (v, terms, weights, products) -- a loose independent bound
    step = math.pi / 2 ** s.addr_bits
    w = np.abs(np.asarray(m.weights))
    bound = step * w[1:].sum() + w.sum() * 2.0 ** -16 + (m.terms + 1) * 2.0 ** -s.acc_frac + w[0] * 2.0 ** -16
    assert err["codes"] == s.clamp_hi - s.clamp_lo + 1
    assert 0 < err["max_err_mm"] <= bound


TB = """\
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;
use std.textio.all;

entity tb is
end entity tb;

architecture sim of tb is
  signal clk, rst, in_valid, in_ready, out_valid, out_sat : std_logic := '0';
  signal in_data  : std_logic_vector(11 downto 0) := (others => '0');
  signal out_data : std_logic_vector(17 downto 0);
  signal done     : boolean := false;
begin
  dut : entity work.flann_seed_top
    port map (clk => clk, rst => rst, in_valid => in_valid, in_ready => in_ready, in_data => in_data,
              out_valid => out_valid, out_data => out_data, out_sat => out_sat);
  clk <= not clk after 5 ns when not done;

  p_drive : process
  begin
    rst <= '1';
    wait until rising_edge(clk);
    rst <= '0';
    for c in {lo} to {hi} loop
      in_data  <= std_logic_vector(to_signed(c, 12));
      in_valid <= '1';
      wait until rising_edge(clk);
    end loop;
    in_valid <= '0';
    for i in 0 to 40 loop
      wait until rising_edge(clk);
    end loop;
    done <= true;
    wait;
  end process p_drive;

  p_mon : process (clk)
    variable l : line;
  begin
    if rising_edge(clk) and out_valid = '1' then
      write(l, to_integer(signed(out_data)));
      write(l, string'(" "));
      write(l, std_logic'image(out_sat));
      writeline(output, l);
    end if;
  end process p_mon;
end architecture sim;
"""


@pytest.mark.sim
@pytest.mark.skipif(shutil.which("ghdl") is None, reason="ghdl is required")
def test_seed_vhdl_equals_its_twin(tmp_path):
    s = _seed(terms=5)
    render.write(s, tmp_path)
    lo, hi = s.clamp_lo - 3, s.clamp_lo + 60  # includes clamped codes below the range
    (tmp_path / "tb.vhd").write_text(TB.replace("{lo}", str(lo)).replace("{hi}", str(hi)))
    for cmd in (["ghdl", "-a", "--std=93c", SEED_FILE, "tb.vhd"], ["ghdl", "-e", "--std=93c", "tb"]):
        subprocess.run(cmd, cwd=tmp_path, check=True, capture_output=True)
    r = subprocess.run(["ghdl", "-r", "--std=93c", "tb", "--ieee-asserts=disable"], cwd=tmp_path,
                       capture_output=True, text=True, check=True)
    got = [ln.split() for ln in r.stdout.splitlines() if ln.strip() and not ln.startswith("tb")]
    vals = np.array([int(g[0]) for g in got])
    sats = np.array([g[1] == "'1'" for g in got])
    codes = np.arange(lo, hi + 1)
    out, sat = FlannSeedTop(s).process(codes)
    assert vals.size == codes.size
    np.testing.assert_array_equal(vals, out)
    np.testing.assert_array_equal(sats, sat)
    assert sats[:3].all() and not sats[3:].any()
