"""The cocotb benches and VHDL harnesses, shipped as package data so an installed `flann sim` runs anywhere."""

from pathlib import Path

BENCH_DIR = Path(__file__).resolve().parent
