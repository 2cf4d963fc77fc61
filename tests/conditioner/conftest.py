"""The conditioner's block benches: each entity rendered from a spec beside the build
directory, built and run by the project's cocotb runner with the bench module of
``flann.verify.benches`` (the one ``flann sim`` runs); pass/fail from cocotb's results."""

from pathlib import Path

import pytest

from flann.hardware.conditioner.render import render
from flann.hardware.conditioner.verify import run_block


def render_and_run(spec, entity: str, bench: str, build_dir: Path, seed: int = 1, **config):
    """Render ``spec`` next to ``build_dir`` and run the cocotb module ``bench`` against ``entity``."""
    build_dir = Path(build_dir).resolve()
    src = build_dir.parent / f"{build_dir.name}_hdl"
    src.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, text in render(spec).items():   # every entity, in compile order: a top needs its blocks
        paths.append(src / name)
        paths[-1].write_text(text)
    return run_block(paths, spec, entity, bench, build_dir, seed=seed, **config)


@pytest.fixture
def block():
    return render_and_run
