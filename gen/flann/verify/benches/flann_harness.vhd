-- Simulation-only harness around flann_top: the clock is generated here, in VHDL, so the
-- cocotb bench is woken once per sample instead of twice per clock (GHDL VPI cost).
-- Ports mirror flann_top; the widths come in as generics (set by the runner with -g).
library ieee;
use ieee.std_logic_1164.all;

entity flann_harness is
  generic (
    in_bits_g  : positive := 12;
    out_bits_g : positive := 16;
    half_ns_g  : positive := 5
  );
  port (
    clk       : buffer std_logic := '0';
    rst       : in  std_logic;
    in_valid  : in  std_logic;
    in_ready  : out std_logic;
    in_data   : in  std_logic_vector(in_bits_g - 1 downto 0);
    out_valid : out std_logic;
    out_data  : out std_logic_vector(out_bits_g - 1 downto 0);
    out_sat   : out std_logic
  );
end entity flann_harness;

architecture sim of flann_harness is
begin
  -- the bench waits on this very signal (no delta-delayed copy of the DUT's clock)
  clk <= not clk after half_ns_g * 1 ns;

  i_dut : entity work.flann_top
    port map (
      clk       => clk,
      rst       => rst,
      in_valid  => in_valid,
      in_ready  => in_ready,
      in_data   => in_data,
      out_valid => out_valid,
      out_data  => out_data,
      out_sat   => out_sat
    );
end architecture sim;
