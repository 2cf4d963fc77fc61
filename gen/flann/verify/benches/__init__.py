"""The cocotb benches and VHDL harnesses, shipped as package data so an installed `flann sim` runs anywhere.

One configuration channel for every bench: the runner (flann.verify.runner) writes a JSON
file and names it in ``FLANN_BENCH_CONFIG`` (GHDL's VPI cannot read generics).
"""

import json
import os
from pathlib import Path

BENCH_DIR = Path(__file__).resolve().parent
CONFIG_ENV = "FLANN_BENCH_CONFIG"
# the simulation clock of every bench and harness (100 MHz; timing is checked by synthesis, not here)
CLK_NS = 10


def config() -> dict:
    path = os.environ.get(CONFIG_ENV)
    if not path:
        raise RuntimeError(f"{CONFIG_ENV} is not set (run the benches through flann.verify.runner)")
    return json.loads(Path(path).read_text())
