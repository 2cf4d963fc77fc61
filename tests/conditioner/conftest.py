"""The conditioner's block benches: each entity rendered from a spec, built by the project's
GHDL runner (``flann.verify.runner.build``, VHDL-93) and run by cocotb with the bench module of
its test folder; pass/fail from cocotb's results file."""

import json
from pathlib import Path

import pytest

from flann.hardware.conditioner.render import render
from flann.verify import runner
from flann.verify.benches import CONFIG_ENV


def run_block(spec, entity: str, bench: str, build_dir: Path, seed: int = 1, **config) -> runner.BenchResult:
    """Render ``spec``, build ``entity`` and run the cocotb module ``bench`` (on sys.path: the
    test folder's) against it; the bench reads the spec and ``config`` from the JSON config."""
    build_dir = Path(build_dir).resolve()
    src = build_dir / "hdl"
    src.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, text in render(spec).items():   # every entity, in compile order: a top needs its blocks
        paths.append(src / name)
        paths[-1].write_text(text)
    backend = runner.build(paths, entity, build_dir)
    cfg_path = build_dir / "bench_config.json"
    cfg_path.write_text(json.dumps({"spec": spec.to_dict(), "seed": seed, **config}))
    results = build_dir / "results.xml"
    try:
        runner._runner(backend).test(
            test_module=bench, hdl_toplevel=entity, hdl_toplevel_lang="vhdl", build_dir=build_dir,
            plusargs=["--ieee-asserts=disable"], seed=seed, results_xml=str(results),
            log_file=build_dir / "sim.log", extra_env={CONFIG_ENV: str(cfg_path), "GHDL_BACKEND": backend})
    except (RuntimeError, SystemExit):
        pass   # failures are read from the results file
    return runner._result(entity, [results], build_dir / "records", 0.0)


@pytest.fixture
def block():
    return run_block
