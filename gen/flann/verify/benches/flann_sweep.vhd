-- Simulation-only harness: every input code from code_lo_g to code_hi_g (or, when codes_file_g
-- names a file, the codes listed there, one per line) through the design's top, back to back,
-- one text line per sample in out_file_g.  A one-input design (temp_bits_g = 0) is flann_top and
-- the lines are "code data sat latency"; a two-input design (temp_bits_g > 0) is
-- flann_thermal_top, the codes run at each temperature code listed in temps_file_g (one per
-- line) and the lines are "code temp data sat latency".  A two-input design with a weight memory
-- (addr_bits_g > 0) is flann_family_thermal_top: a sensor's image (image_file_g, one line
-- "address high16 low16" per word, decimal) is first written through its cfg port, one word per
-- clock.  Stimulus, clock and response stay in VHDL: the cocotb bench (test_sweep.py,
-- test_thermal_sweep.py, test_family_thermal_sweep.py) is woken once, at done, and checks the
-- whole file against the twin.  Widths and ranges come in as generics.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;
use std.textio.all;

entity flann_sweep is
  generic (
    in_bits_g    : positive := 12;
    out_bits_g   : positive := 16;
    code_lo_g    : integer  := -2048;
    code_hi_g    : integer  := 2047;
    codes_file_g : string   := "";
    temp_bits_g  : natural  := 0;
    temps_file_g : string   := "";
    addr_bits_g  : natural  := 0;
    image_file_g : string   := "";
    out_file_g   : string   := "sweep.txt";
    half_ns_g    : positive := 5
  );
  port (
    done : out std_logic
  );
end entity flann_sweep;

architecture sim of flann_sweep is
  -- a one-input design has no in_temp, a design without memory no cfg_addr: one bit that stays
  -- 0 keeps the signal declared
  function at_least_one (n : natural) return positive is
  begin
    if n > 0 then
      return n;
    end if;
    return 1;
  end function at_least_one;

  -- components, not entity instantiation: only the generated branch's top must exist
  component flann_top is
    port (
      clk       : in  std_logic;
      rst       : in  std_logic;
      in_valid  : in  std_logic;
      in_ready  : out std_logic;
      in_data   : in  std_logic_vector(in_bits_g - 1 downto 0);
      out_valid : out std_logic;
      out_data  : out std_logic_vector(out_bits_g - 1 downto 0);
      out_sat   : out std_logic
    );
  end component flann_top;

  component flann_thermal_top is
    port (
      clk       : in  std_logic;
      rst       : in  std_logic;
      in_valid  : in  std_logic;
      in_ready  : out std_logic;
      in_data   : in  std_logic_vector(in_bits_g - 1 downto 0);
      in_temp   : in  std_logic_vector(at_least_one(temp_bits_g) - 1 downto 0);
      out_valid : out std_logic;
      out_data  : out std_logic_vector(out_bits_g - 1 downto 0);
      out_sat   : out std_logic
    );
  end component flann_thermal_top;

  component flann_family_thermal_top is
    port (
      clk       : in  std_logic;
      rst       : in  std_logic;
      in_valid  : in  std_logic;
      in_ready  : out std_logic;
      in_data   : in  std_logic_vector(in_bits_g - 1 downto 0);
      in_temp   : in  std_logic_vector(at_least_one(temp_bits_g) - 1 downto 0);
      out_valid : out std_logic;
      out_data  : out std_logic_vector(out_bits_g - 1 downto 0);
      out_sat   : out std_logic;
      cfg_we    : in  std_logic;
      cfg_addr  : in  std_logic_vector(at_least_one(addr_bits_g) - 1 downto 0);
      cfg_data  : in  std_logic_vector(31 downto 0)
    );
  end component flann_family_thermal_top;

  signal clk       : std_logic := '0';
  signal running   : boolean   := true;
  signal rst       : std_logic := '1';
  signal in_valid  : std_logic := '0';
  signal in_ready  : std_logic;
  signal in_data   : std_logic_vector(in_bits_g - 1 downto 0) := (others => '0');
  signal in_temp   : std_logic_vector(at_least_one(temp_bits_g) - 1 downto 0) := (others => '0');
  signal out_valid : std_logic;
  signal out_data  : std_logic_vector(out_bits_g - 1 downto 0);
  signal out_sat   : std_logic;
  signal cfg_we    : std_logic := '0';
  signal cfg_addr  : std_logic_vector(at_least_one(addr_bits_g) - 1 downto 0) := (others => '0');
  signal cfg_data  : std_logic_vector(31 downto 0) := (others => '0');
  signal cycle     : natural := 0;
begin
  -- the clock stops after the last sample, so the simulation ends by itself
  clk <= not clk after half_ns_g * 1 ns when running else clk;

  g_one_input : if temp_bits_g = 0 generate
    i_dut : component flann_top
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
  end generate g_one_input;

  g_two_inputs : if temp_bits_g > 0 and addr_bits_g = 0 generate
    i_dut : component flann_thermal_top
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
  end generate g_two_inputs;

  g_memory : if temp_bits_g > 0 and addr_bits_g > 0 generate
    i_dut : component flann_family_thermal_top
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
  end generate g_memory;

  p_cycle : process (clk)
  begin
    if rising_edge(clk) then
      cycle <= cycle + 1;
    end if;
  end process p_cycle;

  -- offer each code (at each temperature) until an edge with in_ready high takes it, wait for
  -- its result, write it
  p_run : process
    file f       : text open write_mode is out_file_g;
    file cf      : text;
    file tf      : text;
    file imf     : text;
    variable st  : file_open_status;
    variable l   : line;
    variable cl  : line;
    variable tl  : line;
    variable c   : integer;
    variable t   : integer := 0;
    variable a   : integer;
    variable hi  : integer;
    variable lo  : integer;
    variable t0  : natural;
    variable ok  : boolean;
    variable lst : boolean := codes_file_g'length > 0;
    variable two : boolean := temp_bits_g > 0;
  begin
    done <= '0';
    assert addr_bits_g = 0 or two
      report "a weight memory (addr_bits_g > 0) is a two-input design's (temp_bits_g > 0)"
      severity failure;
    if two then
      file_open(st, tf, temps_file_g, read_mode);
      assert st = open_ok report "cannot open " & temps_file_g severity failure;
    end if;
    wait until rising_edge(clk);
    wait until rising_edge(clk);
    rst <= '0';
    if addr_bits_g > 0 then
      -- the sensor's image, one word per clock through the cfg port
      file_open(st, imf, image_file_g, read_mode);
      assert st = open_ok report "cannot open " & image_file_g severity failure;
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
      file_close(imf);
      cfg_we <= '0';
      wait until rising_edge(clk);
    end if;
    -- one pass over the codes per temperature code (a one-input design: one pass)
    loop
      if two then
        exit when endfile(tf);
        readline(tf, tl);
        read(tl, t, ok);
        next when not ok;
        in_temp <= std_logic_vector(to_signed(t, at_least_one(temp_bits_g)));
      end if;
      if lst then
        file_open(st, cf, codes_file_g, read_mode);
        assert st = open_ok report "cannot open " & codes_file_g severity failure;
      end if;
      c := code_lo_g;
      loop
        if lst then
          exit when endfile(cf);
          readline(cf, cl);
          read(cl, c, ok);
          next when not ok;
        else
          exit when c > code_hi_g;
        end if;
        in_data  <= std_logic_vector(to_signed(c, in_bits_g));
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
        if two then
          write(l, t);
          write(l, ' ');
        end if;
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
      if lst then
        file_close(cf);
      end if;
      exit when not two;
    end loop;
    file_close(f);  -- flushed before the bench reads it
    running <= false;
    done    <= '1';
    wait;
  end process p_run;
end architecture sim;
