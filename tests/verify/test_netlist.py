"""Post-synthesis simulation (Yosys synth_xilinx -family xcv netlist under Verilator) and Ctrl-C."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from dataclasses import replace

from flann.eda import complete_pmux_cases, ghdl_to_verilog
from flann.errors import FlannError
from flann.hardware.family.images import read_image
from flann.hardware.family.twin import FlannFamilyTop
from flann.hardware.manifest import read_manifest
from flann.hardware.design import from_directory
from flann.verify.netlist import check_netlist, compare, compile_netlist, mapped_netlist, run_netlist, sweep_of

pytestmark = [pytest.mark.sim, pytest.mark.synth,
              pytest.mark.skipif(not all(shutil.which(t) for t in ("ghdl", "yosys", "verilator")),
                                 reason="needs ghdl, yosys, verilator (scripts/ensure_tools.sh)")]


def test_mapped_netlist_every_code_and_a_wrong_netlist(tmp_path, small_designs, small_synths):
    small_synths("fixed")   # the run's one synthesis of this design: the check below takes it from the cache
    design = from_directory(small_designs["dir"] / "fixed")
    r = check_netlist(design, tmp_path / "nl")
    assert r.codes_tested == 256 and r.mismatches == 0, r
    assert Path(r.netlist).read_text().count("LUT") > 10  # the mapped cells, not RTL
    # GHDL's Verilog as GHDL prints it (no repair) disagrees with the twin: the check sees it
    work = tmp_path / "raw"
    ghdl_to_verilog(read_manifest(design.directory), work)
    raw = subprocess.run(["ghdl", "--synth", "--std=93c", f"--workdir={work / 'ghdl'}", "--out=verilog",
                          "flann_top"], capture_output=True, text=True, check=True).stdout
    (work / "raw.v").write_text(complete_pmux_cases(raw)[0])
    bad = check_netlist(design, tmp_path / "nl_raw", netlist=work / "raw.v")
    assert bad.codes_tested == 256 and bad.mismatches > 0


def test_family_netlist_computes_with_the_image_its_cfg_port_loaded(tmp_path, small_designs):
    """The family's mapped netlist (weights in a RAMB4) takes a sensor's image through cfg_* and
    then agrees with that sensor's twin on every code; loaded with the other sensor's image it
    agrees with the other twin and not the first: the load, not the initial contents, decides."""
    design = from_directory(small_designs["dir"] / "family")
    sweep = sweep_of(design)
    kept = [read_image(design.directory / im["hex"]) for im in design.manifest["images"]]
    assert len(kept) == 2 and kept[0] != kept[1] and list(sweep.image) == kept[-1]
    # an image given (flann sim --image) is the one loaded
    given = design.manifest["images"][0]
    assert list(sweep_of(design, {"name": "given", "hex": design.directory / given["hex"]}).image) == kept[0]
    netlist = mapped_netlist(design, tmp_path / "synth")
    assert "RAMB4" in netlist.read_text()   # the weights in a block RAM, not in logic
    exe = compile_netlist(netlist, tmp_path / "verilator", sweep)
    other = replace(sweep, image=tuple(kept[0]), process=FlannFamilyTop(design.spec, kept[0]).process)
    for name, loaded in (("own", sweep), ("other", other)):
        (tmp_path / name).mkdir()
        got = run_netlist(exe, loaded, tmp_path / name, shards=1)
        res = compare(loaded, got)
        assert res.codes_tested == 256 and res.mismatches == 0, (name, res)
        if loaded is other:
            assert compare(sweep, got).mismatches > 0
    # an image cut short would leave the memory's initial sensor in place: the driver refuses it
    (tmp_path / "short").mkdir()
    with pytest.raises(FlannError, match=f"{len(kept[0]) - 1} hex words read, the memory takes {len(kept[0])}"):
        run_netlist(exe, replace(sweep, image=tuple(kept[0][:-1])), tmp_path / "short", shards=1)


def test_two_input_netlist_follows_its_temperature_input(tmp_path, small_designs):
    """A design with temperature: GHDL's netlist (as Yosys reads it) runs every voltage code at the
    RTL sweep's temperature codes and agrees with the twin at each; against the twin one
    temperature code up it disagrees, so in_temp is driven and read, not left at 0 (the family
    with temperature's mapped netlist: flann synth in tests/hardware/test_datapath_matrix.py)."""
    design = from_directory(small_designs["dir"] / "thermal")
    sweep = sweep_of(design)
    spec = design.spec
    assert sweep.temps[0] == spec.temp_code_min and sweep.temps[-1] == spec.temp_code_max
    verilog = ghdl_to_verilog(read_manifest(design.directory), tmp_path / "ghdl")
    exe = compile_netlist(verilog, tmp_path / "verilator", sweep, cells=False)
    got = run_netlist(exe, sweep, tmp_path, shards=2)
    res = compare(sweep, got)
    assert res.codes_tested == 256 * len(sweep.temps) == sweep.samples and res.mismatches == 0, res
    assert sorted(set(got["temps"].tolist())) == list(sweep.temps)
    up = replace(sweep, process=lambda c, t: sweep.process(c, np.minimum(t + 1, spec.temp_code_max)))
    assert compare(up, got).mismatches > 0


def test_ctrl_c_ends_flann_sim_with_one_line(tmp_path, small_model):
    model = small_model(11)
    flann = Path(sys.executable).with_name("flann")
    build = tmp_path / "build"
    p = subprocess.Popen([str(flann), "sim", str(model), "--input-bits", "10", "--build", str(build)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                         cwd=tmp_path, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    # the state we interrupt: the build has started (its first files are in place); the whole
    # run takes seconds more, so the interrupt lands inside the build or the sweep
    deadline = time.monotonic() + 120
    while not (build.is_dir() and any(build.rglob("*"))):
        assert p.poll() is None and time.monotonic() < deadline, p.communicate()
        time.sleep(0.01)
    os.killpg(p.pid, signal.SIGINT)  # what Ctrl-C on a terminal does: the whole process group
    out, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert err.strip().splitlines() == ["error: interrupted"], err
