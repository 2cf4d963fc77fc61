"""The conditioner's block benches: each entity rendered from a spec beside the build
directory, built and run by the project's cocotb runner with the bench module of
``flann.verify.benches`` (the one ``flann sim`` runs); pass/fail from cocotb's results."""

from pathlib import Path

import numpy as np
import pytest

from flann.golden.train import fit_lstsq
from flann.hardware.fixed import render as fixed_render
from flann.hardware.options import GenOptions
from flann.hardware.conditioner.render import render
from flann.hardware.conditioner.verify import run_block


def write_sources(texts: dict, src: Path) -> list[Path]:
    """{file name: VHDL} written into ``src``; the paths in compile order (the dict's)."""
    src.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, text in texts.items():
        paths.append(src / name)
        paths[-1].write_text(text)
    return paths


def render_and_run(spec, entity: str, bench: str, build_dir: Path, seed: int = 1, **config):
    """Render ``spec`` next to ``build_dir`` and run the cocotb module ``bench`` against ``entity``."""
    build_dir = Path(build_dir).resolve()
    # every entity, in compile order: a top needs its blocks
    paths = write_sources(render(spec), build_dir.parent / f"{build_dir.name}_hdl")
    return run_block(paths, spec, entity, bench, build_dir, seed=seed, **config)


@pytest.fixture
def sources():
    return write_sources


@pytest.fixture
def block():
    return render_and_run


def _flann_behind(cond, terms: int = 5):
    """A FLANN of a monotonic LVDT curve over the ratio +-0.8, generated as flann gen does behind
    the conditioner: the ratio code its converter."""
    x = np.linspace(-25.0, 25.0, 101)
    model = fit_lstsq(0.8 * np.tanh(x / 20.0) / np.tanh(25.0 / 20.0), x, terms, norm="half")
    return fixed_render.load(model, GenOptions(input_bits=cond.ratio_bits, input_lsb_v=2.0 ** -cond.ratio_frac_bits))


@pytest.fixture(scope="session")
def flann_behind():
    """The one-input FLANN behind a conditioner's spec, as a function of it."""
    return _flann_behind
