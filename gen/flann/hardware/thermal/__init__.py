"""The two-input datapath x(v, T): spec (error analysis) and bit-true twin; no VHDL yet."""
