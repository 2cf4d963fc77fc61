"""What a datapath's folder offers verification.

A datapath folder under ``hardware/`` may hold a ``verify.py`` (it belongs to the verify layer,
beside the folder's generator) defining ``VERIFICATION``, one :class:`Verification`: the bench
``flann sim`` runs, the sweep of its mapped netlist, and how the generator fuzz checks a case
drawn on it.  No table names the datapaths: a folder without ``verify.py`` has no bench, and the
commands say so in one line.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable

from ..hardware.registry import DATAPATHS


@dataclass(frozen=True)
class Verification:
    bench: Callable                       # (Design, build_dir, **options) -> SimResult: flann sim
    netlist: Callable | None = None       # (Design, image | None) -> NetlistSweep: its mapped netlist, every code
    fuzz: Callable | None = None          # (model, Case, spec, rng, work, hdl_codes) -> Case: one fuzz case checked
    fuzz_share: float = 0.0               # share of the generator fuzz cases drawn on it
    fuzz_options: Callable | None = None  # rng -> its own generator options drawn at random
    engines: tuple = ("ghdl",)            # with "verilator": GHDL's netlist compiled by Verilator can replace its VHDL sweep
    loads_images: bool = False            # its bench loads weight images (flann sim --image)
    check_words: Callable | None = None   # (spec, words, source): an image's words the hardware would wrap with refused


def folder_module(dp, layer: str):
    """The module ``hardware/<datapath>/<layer>.py`` of ``dp``'s folder, or None when the folder
    (a design flann did not write has none) or the module does not exist."""
    folder = f"{__package__.rsplit('.', 1)[0]}.hardware.{dp.name}"
    try:
        return importlib.import_module(f"{folder}.{layer}")
    except ModuleNotFoundError as exc:
        if exc.name in (folder, f"{folder}.{layer}"):
            return None
        raise


def verification(dp) -> Verification | None:
    """The verification ``dp``'s folder offers, or None when it has no ``verify.py``."""
    module = folder_module(dp, "verify")
    return None if module is None else module.VERIFICATION


def bench_of(design) -> Verification:
    """The verification of ``design``'s datapath, or the one-line refusal saying why it has none."""
    found = verification(design.datapath)
    if found is None:
        raise design.datapath.lacking(design.directory, "simulation bench")
    return found


def with_netlist() -> list:
    """The datapaths whose mapped netlist the netlist sweep drives."""
    return [dp for dp in DATAPATHS.values() if (v := verification(dp)) is not None and v.netlist is not None]


__all__ = ["Verification", "folder_module", "verification", "bench_of", "with_netlist"]
