-- Simulation-only harness of the two-input design: every voltage code from code_lo_g to
-- code_hi_g at each temperature code listed in temps_file_g (one per line), through
-- flann_thermal_top, back to back, one text line per sample ("code temp data sat latency") in
-- out_file_g.  Stimulus, clock and response stay in VHDL: the cocotb bench
-- (test_thermal_sweep.py) is woken once, at done, and checks the whole file against the twin.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;
use std.textio.all;

entity flann_thermal_sweep is
  generic (
    in_bits_g    : positive := 10;
    temp_bits_g  : positive := 6;
    out_bits_g   : positive := 16;
    code_lo_g    : integer  := -512;
    code_hi_g    : integer  := 511;
    temps_file_g : string   := "temps.txt";
    out_file_g   : string   := "sweep.txt";
    half_ns_g    : positive := 5
  );
  port (
    done : out std_logic
  );
end entity flann_thermal_sweep;

architecture sim of flann_thermal_sweep is
  signal clk       : std_logic := '0';
  signal running   : boolean   := true;
  signal rst       : std_logic := '1';
  signal in_valid  : std_logic := '0';
  signal in_ready  : std_logic;
  signal in_data   : std_logic_vector(in_bits_g - 1 downto 0) := (others => '0');
  signal in_temp   : std_logic_vector(temp_bits_g - 1 downto 0) := (others => '0');
  signal out_valid : std_logic;
  signal out_data  : std_logic_vector(out_bits_g - 1 downto 0);
  signal out_sat   : std_logic;
  signal cycle     : natural := 0;
begin
  -- the clock stops after the last sample, so the simulation ends by itself
  clk <= not clk after half_ns_g * 1 ns when running else clk;

  i_dut : entity work.flann_thermal_top
    port map (
      clk       => clk,
      rst       => rst,
      in_valid  => in_valid,
      in_ready  => in_ready,
      in_data   => in_data,
      in_temp   => in_temp,
      out_valid => out_valid,
      out_data  => out_data,
      out_sat   => out_sat
    );

  p_cycle : process (clk)
  begin
    if rising_edge(clk) then
      cycle <= cycle + 1;
    end if;
  end process p_cycle;

  -- offer each (code, temperature) until an edge with in_ready high takes it, wait for its result
  p_run : process
    file f      : text open write_mode is out_file_g;
    file tf     : text open read_mode is temps_file_g;
    variable l  : line;
    variable tl : line;
    variable c  : integer;
    variable t  : integer;
    variable t0 : natural;
    variable ok : boolean;
  begin
    done <= '0';
    wait until rising_edge(clk);
    wait until rising_edge(clk);
    rst <= '0';
    while not endfile(tf) loop
      readline(tf, tl);
      read(tl, t, ok);
      next when not ok;
      c := code_lo_g;
      while c <= code_hi_g loop
        in_data  <= std_logic_vector(to_signed(c, in_bits_g));
        in_temp  <= std_logic_vector(to_signed(t, temp_bits_g));
        in_valid <= '1';
        loop
          wait until rising_edge(clk);
          exit when in_ready = '1';
        end loop;
        t0       := cycle;
        in_valid <= '0';
        wait until rising_edge(clk) and out_valid = '1';
        write(l, c);
        write(l, ' ');
        write(l, t);
        write(l, ' ');
        write(l, to_integer(signed(out_data)));
        write(l, ' ');
        if out_sat = '1' then
          write(l, 1);
        else
          write(l, 0);
        end if;
        write(l, ' ');
        -- out_valid rose after the previous edge: that edge is the one the latency counts
        write(l, cycle - t0 - 1);
        writeline(f, l);
        c := c + 1;
      end loop;
    end loop;
    file_close(f);  -- flushed before the bench reads it
    running <= false;
    done    <= '1';
    wait;
  end process p_run;
end architecture sim;
