"""FLANN LVDT compensator: golden model, VHDL-93 generator, co-simulation, physics and diagnosis."""

__version__ = "0.1.0"
