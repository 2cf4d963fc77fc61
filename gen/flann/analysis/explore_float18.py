"""The float18 design as a row of the design-space table.

``measure(model_path, device)`` generates the float18 design, measures it with the same
flow as ``flann synth`` (GHDL synthesis + Yosys ``synth_xilinx -family xcv``) and takes
the accuracy from the bit-true twin over every input code (``flann trace``), so a
design-space table can list it beside the fixed-point candidates.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from ..golden.model import load_model
from ..hardware.float18.render import generate
from ..hardware.registry import FLOAT18
from ..hardware.target import CLOCK_HZ, DEFAULT_PART
from ..implement import synth
from .trace import run_trace


def measure(model_path, device: str = DEFAULT_PART, abc: str = "full", **options) -> dict:
    with tempfile.TemporaryDirectory(prefix="flann-f18-") as tmp:
        out = Path(tmp) / FLOAT18.name
        man = generate(model_path, out, **options)
        rep = synth.synthesize(out, device, progress=False, abc=abc).to_dict()
    tr = run_trace(load_model(model_path), FLOAT18.name, **options)
    return {
        "format": FLOAT18.number_format, "top": man["top"], "device": device,
        "luts": rep["luts"], "ffs": rep["ffs"], "brams": rep["brams"], "fits": rep["fits"],
        "cycles_per_sample": man["cycles_per_sample"],
        "samples_per_s_at_50mhz": round(CLOCK_HZ / man["cycles_per_sample"], 1),
        "max_err_mm": tr.total["max_mm"], "rms_err_mm": tr.total["rms_mm"],
        "dominant_error_stage": tr.dominant["stage"],
    }


__all__ = ["measure"]
