"""GHDL + cocotb: the float18 blocks against their Python twins, bit-exact."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from flann.float18 import FLOAT18
from flann.float18_hdl import BLOCKS, render_blocks

SIM_DIR = Path(__file__).resolve().parent.parent / "sim"
N_RANDOM = {"mul": 15000, "add": 15000}


def _write(tmp_path: Path) -> dict[str, Path]:
    out = {}
    for name, text in render_blocks(FLOAT18).items():
        p = tmp_path / name
        p.write_text(text)
        out[name] = p
    return out


def test_rendered_blocks_analyse_and_are_deterministic(tmp_path):
    if shutil.which("ghdl") is None:
        pytest.fail("ghdl not installed (make tools)")
    files = _write(tmp_path)
    assert render_blocks(FLOAT18) == {n: p.read_text() for n, p in files.items()}
    for p in files.values():
        r = subprocess.run(["ghdl", "-a", "--std=93c", f"--workdir={tmp_path}", str(p)],
                           capture_output=True, text=True, cwd=tmp_path)
        assert r.returncode == 0, r.stderr
    text = files["flann_f18_add.vhd"].read_text()
    assert "entity flann_f18_add is" in text and "constant bias_c" not in text
    assert "constant bias_c : integer := 31;" in files["flann_f18_mul.vhd"].read_text()


@pytest.mark.sim
@pytest.mark.parametrize("kind", sorted(BLOCKS))
def test_block_matches_twin_under_ghdl(kind, tmp_path):
    from cocotb_test.simulator import run

    files = _write(tmp_path)
    entity = f"flann_f18_{kind}"
    spec = {"kind": kind, "format": FLOAT18.to_dict(), "seed": 1000 + sorted(BLOCKS).index(kind),
            "n_random": N_RANDOM[kind]}
    run(simulator="ghdl", toplevel=entity, toplevel_lang="vhdl", module=f"test_f18_{kind}",
        vhdl_sources=[str(files[f"{entity}.vhd"])], python_search=[str(SIM_DIR)],
        compile_args=["--std=93c"], sim_build=str(tmp_path / "sim_build"),
        extra_env={"FLANN_F18_SPEC": json.dumps(spec)})
