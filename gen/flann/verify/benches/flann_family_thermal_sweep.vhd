-- Simulation-only harness of the family design with temperature: writes a sensor's image
-- (image_file_g: one line "address high16 low16" per word, decimal) through the cfg port, then
-- drives every voltage code from code_lo_g to code_hi_g at each temperature code listed in
-- temps_file_g through flann_family_thermal_top, back to back, one text line per sample
-- ("code temp data sat latency") in out_file_g.  The cocotb bench
-- (test_family_thermal_sweep.py) is woken once, at done, and checks the file against the twin.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;
use std.textio.all;

entity flann_family_thermal_sweep is
  generic (
    in_bits_g    : positive := 10;
    temp_bits_g  : positive := 6;
    out_bits_g   : positive := 16;
    addr_bits_g  : positive := 7;
    code_lo_g    : integer  := -512;
    code_hi_g    : integer  := 511;
    image_file_g : string   := "image.txt";
    temps_file_g : string   := "temps.txt";
    out_file_g   : string   := "sweep.txt";
    half_ns_g    : positive := 5
  );
  port (
    done : out std_logic
  );
end entity flann_family_thermal_sweep;

architecture sim of flann_family_thermal_sweep is
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
  signal cfg_we    : std_logic := '0';
  signal cfg_addr  : std_logic_vector(addr_bits_g - 1 downto 0) := (others => '0');
  signal cfg_data  : std_logic_vector(31 downto 0) := (others => '0');
  signal cycle     : natural := 0;
begin
  -- the clock stops after the last sample, so the simulation ends by itself
  clk <= not clk after half_ns_g * 1 ns when running else clk;

  i_dut : entity work.flann_family_thermal_top
    port map (
      clk       => clk,
      rst       => rst,
      in_valid  => in_valid,
      in_ready  => in_ready,
      in_data   => in_data,
      in_temp   => in_temp,
      out_valid => out_valid,
      out_data  => out_data,
      out_sat   => out_sat,
      cfg_we    => cfg_we,
      cfg_addr  => cfg_addr,
      cfg_data  => cfg_data
    );

  p_cycle : process (clk)
  begin
    if rising_edge(clk) then
      cycle <= cycle + 1;
    end if;
  end process p_cycle;

  p_run : process
    file f      : text open write_mode is out_file_g;
    file tf     : text open read_mode is temps_file_g;
    file imf    : text open read_mode is image_file_g;
    variable l  : line;
    variable tl : line;
    variable c  : integer;
    variable t  : integer;
    variable a  : integer;
    variable hi : integer;
    variable lo : integer;
    variable t0 : natural;
    variable ok : boolean;
  begin
    done <= '0';
    wait until rising_edge(clk);
    wait until rising_edge(clk);
    rst <= '0';
    -- the sensor's image, one word per clock through the cfg port
    while not endfile(imf) loop
      readline(imf, tl);
      read(tl, a, ok);
      next when not ok;
      read(tl, hi);
      read(tl, lo);
      cfg_addr <= std_logic_vector(to_unsigned(a, addr_bits_g));
      cfg_data <= std_logic_vector(to_unsigned(hi, 16)) & std_logic_vector(to_unsigned(lo, 16));
      cfg_we   <= '1';
      wait until rising_edge(clk);
    end loop;
    cfg_we <= '0';
    wait until rising_edge(clk);
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
        write(l, cycle - t0 - 1);
        writeline(f, l);
        c := c + 1;
      end loop;
    end loop;
    file_close(f);
    running <= false;
    done    <= '1';
    wait;
  end process p_run;
end architecture sim;
