"""``flann sim DIR`` for every datapath: the design's datapath folder offers its bench
(:mod:`flann.verify.plugin`), this runs it; with ``netlist``, then the mapped netlist over every
code.  A datapath without a bench is refused in one line saying why."""

from __future__ import annotations

from ..errors import FlannError
from ..hardware.design import Design
from .netlist import netlist_summary, require_sweep_driver
from .plugin import bench_of
from .results import SimResult


def simulate(design: Design, build_dir, *, netlist: bool = False, **kw) -> SimResult:
    """Verify ``design`` with its datapath's bench (flann sim); with ``netlist``, then its mapped
    netlist over every code."""
    dp, found = design.datapath, bench_of(design)
    if netlist:
        require_sweep_driver(dp, design.directory, "--netlist")
    engine = kw.get("engine", "auto")
    if engine not in ("auto", *found.engines):
        raise FlannError(f"--engine {engine}: {design.directory} holds a {dp.name} design, simulated by "
                         f"{' or '.join(found.engines)} only")
    if kw.get("images") and not found.loads_images:
        raise FlannError(f"--image: {design.directory} is a {dp.name} design, its weights are built in "
                         "(weight images load into a family design's memory)")
    res = found.bench(design, build_dir, **kw)
    if netlist:
        # a family design's netlist computes with the last image given (--image), as its bench ends
        given = kw.get("images")
        about, passed = netlist_summary(design, build_dir, kw.get("progress"), image=given[-1] if given else None)
        res.judged_with("netlist", about, passed)
    return res


__all__ = ["simulate"]
