"""GHDL + cocotb: the float18 blocks against their Python twins, bit-exact."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

from flann.numeric.float18 import FLOAT18
from flann.hardware.float18.render import BLOCKS, render_blocks

# random vectors per block bench; FLANN_F18_N=200000 for a long run
N_RANDOM = int(os.environ.get("FLANN_F18_N", "15000"))


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
    # the whole float18 design (shared front end, converter, blocks, top) analyses in order
    from flann.hardware.float18.render import generate
    from flann.golden.model import load_model

    man = generate(load_model(Path(__file__).resolve().parents[2] / "data" / "default_model.json"),
                   tmp_path / "design")
    assert man["top"] == "flann_f18_top" and man["files"][-1] == "flann_f18_top.vhd"
    work = tmp_path / "design_work"
    work.mkdir()
    r = subprocess.run(["ghdl", "-a", "--std=93c", f"--workdir={work}",
                        *[str(tmp_path / "design" / f) for f in man["files"]]],
                       capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    # VSG with the repository's configuration: no style violations in the float18 files
    from flann.implement.synth import lint_vhdl

    assert lint_vhdl(sorted((tmp_path / "design").glob("flann_f18_*.vhd"))) == []
    text = files["flann_f18_add.vhd"].read_text()
    assert "entity flann_f18_add is" in text and "constant bias_c" not in text
    assert "constant bias_c : integer := 31;" in files["flann_f18_mul.vhd"].read_text()


@pytest.mark.sim
@pytest.mark.parametrize("kind", sorted(BLOCKS))
def test_block_matches_twin_under_ghdl(kind, tmp_path):
    from flann.verify.runner import run_cocotb

    files = _write(tmp_path)
    entity = f"flann_f18_{kind}"
    spec = {"kind": kind, "format": FLOAT18.to_dict(), "n_random": N_RANDOM}
    r = run_cocotb([files[f"{entity}.vhd"]], entity, "test_f18_block", tmp_path / "sim_build", spec,
                   seed=1000 + sorted(BLOCKS).index(kind))
    assert r.ok, f"{entity}: {r.failed_tests} (see {tmp_path / 'sim_build'})"


# -- top level: every input code ------------------------------------------------------------
def _run_top(tmp_path, model, step: int, seed: int, **options):
    from flann.hardware.float18.verify import run_top
    from flann.hardware.float18.spec import FlannF18Top, derive_f18_spec

    codes = FlannF18Top(derive_f18_spec(model, **options)).all_codes()[::step]
    r = run_top(model, tmp_path, codes=codes, seed=seed, **options)
    assert not r["bench_failed"], "cocotb reported a failure (see sim.log)"
    assert r["mismatches"] == 0 and r["codes"].size == codes.size
    assert r["latency"] == [r["manifest"]["latency_cycles"]]
    return r["codes"]


@pytest.mark.sim
def test_top_every_input_code_matches_twin(tmp_path):
    """Default model, default 12-bit input: all 4096 codes, 0 mismatches (and the latency)."""
    from flann.golden.model import load_model

    model = load_model(Path(__file__).resolve().parents[2] / "data" / "default_model.json")
    codes = _run_top(tmp_path, model, step=1, seed=11)
    assert codes.size == 4096


@pytest.mark.sim
def test_top_other_widths_match_twin(tmp_path):
    """The paper's raw-volt model, 10-bit input, coarser table: every 8th code."""
    from flann.recordings import read_recordings
    from flann.golden.train import fit_lstsq

    rec = read_recordings(Path(__file__).resolve().parents[2] / "data" / "paper_table1.csv")
    model = fit_lstsq(rec.voltage_v, rec.displacement_mm, 51, norm="none")
    _run_top(tmp_path, model, step=8, seed=12, input_bits=10, table_addr_bits=6)
