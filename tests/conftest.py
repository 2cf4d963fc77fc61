"""Shared fixtures: the repository's data files, located once; slow artefacts (designs, simulations)
made once per test run and shared by every xdist worker (:func:`once`)."""

import contextlib
import fcntl
import io
import json
import os
import pickle
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

# flann first: it keeps numpy's BLAS to one thread, which only takes before numpy loads (two
# workers of two BLAS threads each on two cores spin-wait: lstsq ran tens of times slower)
from flann import cache as flann_cache  # isort: skip
import numpy as np
import pytest

from flann.cli import main
from flann.golden.thermal_train import fit_thermal
from flann.golden.train import fit_lstsq
from flann.hardware.conditioner.datapath import write_conditioner
from flann.hardware.conditioner.spec import derive_conditioner
from flann.hardware.seed import render as seed_render
from flann.hardware.seed.spec import derive_seed_spec
from flann.production.demo import write_batch
from flann.recordings import prepare_for_fit, read_recordings

REPO = Path(__file__).resolve().parents[1]
DATA = REPO / "data"


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO


@pytest.fixture(scope="session")
def data_dir() -> Path:
    return DATA


@pytest.fixture(scope="session")
def table1_csv() -> Path:
    return DATA / "paper_table1.csv"


@pytest.fixture(scope="session")
def default_model_json() -> Path:
    return DATA / "default_model.json"


@pytest.fixture(scope="session")
def run_root(tmp_path_factory) -> Path:
    """A directory of this test run that every xdist worker shares (new each run)."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


@pytest.fixture(scope="session", autouse=True)
def tool_cache(run_root):
    """flann's cache of synthesised and compiled netlists (:mod:`flann.cache`), empty at the start
    of each run and shared by its workers and the flann processes they start: each design is
    synthesised once per run, as a user's synth then ise would."""
    path = run_root / "flann-cache"
    path.mkdir(exist_ok=True)
    os.environ[flann_cache.ENV] = str(path)
    return path


@pytest.fixture(scope="session")
def once(run_root):
    """``once(key, make)``: ``make(directory)`` run once per test run, whichever worker asks
    first, in a fresh ``directory`` every worker sees; its (picklable) result returned to each.
    A slow property (a simulation, a synthesis) is checked once per design and the tests that
    look at its outputs share it.  A ``make`` that raises leaves nothing: the next asker tries
    again, and fails as the first did."""
    root = run_root / "once"
    root.mkdir(exist_ok=True)

    def run(key: str, make):
        directory, done = root / key, root / f"{key}.pickle"
        with open(root / f"{key}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # the other workers wait here while one makes it
            if done.is_file():
                return pickle.loads(done.read_bytes())
            if directory.exists():
                shutil.rmtree(directory)
            directory.mkdir()
            value = make(directory)
            done.write_bytes(pickle.dumps(value))
            return value
    return run


def run_cli(argv) -> tuple:
    """flann in process outside a test's capture: (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in argv])
        except SystemExit as exc:
            rc = exc.code
    return rc, out.getvalue(), err.getvalue()


@pytest.fixture(scope="session")
def in_process():
    """:func:`run_cli` as a fixture: ``in_process(argv)`` -> (exit code, stdout, stderr)."""
    return run_cli


@pytest.fixture(scope="session")
def flann():
    """flann in process, as the command line runs it: ``flann(*args)`` -> a
    ``subprocess.CompletedProcess`` (returncode, stdout, stderr), without a new interpreter."""
    def run(*args):
        rc, out, err = run_cli(args)
        return subprocess.CompletedProcess(["flann", *map(str, args)], rc, out, err)
    return run


@pytest.fixture
def cli(capsys):
    """flann in process: ``cli(argv)`` -> (exit code, stdout, stderr); a flag its argparse type
    refuses exits 2 through SystemExit, as on the command line."""
    def run(argv):
        try:
            rc = main([str(a) for a in argv])
        except SystemExit as exc:
            rc = exc.code
        out, err = capsys.readouterr()
        return rc, out, err
    return run


def thermal_sensor_v(x, t, gain: float = 1.0):
    """A closed-form sensor (not the project's physics) whose gain, null and roll-off move
    with temperature: volts at displacement ``x`` mm and temperature ``t`` degC."""
    u, k = np.asarray(x) / 8.0, 2.5 * (1 + 1e-4 * (np.asarray(t) - 25))
    return gain * (1.5 * (1 - 2.5e-4 * (t - 25)) * u / (1 + np.abs(u) ** k) ** (1 / k) + 6e-6 * (t - 25))


@pytest.fixture(scope="session")
def thermal_sensor():
    return thermal_sensor_v


SMALL_DESIGN_BITS = 8


@pytest.fixture(scope="session")
def small_designs(once) -> dict:
    """Small designs (4-5 terms, 8-bit input) of every datapath flann gen writes, by datapath
    name under ``dir``, made once per run (read them; copy one to change it); ``model`` the
    one-input model, ``rec`` a recording of its sensor, ``thermal`` the two-input model (of
    :func:`thermal_sensor_v`), ``held_thermal`` a held-out recording of that sensor.  Beside them:
    ``seed/`` (the paper's parallel architecture, which flann explore writes for comparison) and
    ``plain/`` (VHDL with a hand-written manifest, a design flann did not write) and
    ``conditioner/`` (the LVDT conditioner, written from a spec)."""
    return once("small_designs", _small_designs)


def _small_designs(d: Path) -> dict:
    recs = write_batch(d / "rec", 2, seed=11, points=400)
    rec = prepare_for_fit(read_recordings(recs[0]))
    model = d / "m5.json"
    model.write_text(fit_lstsq(rec.voltage_v, rec.displacement_mm, 5, norm="half").to_json())
    x, t = np.tile(np.linspace(-10, 10, 41), 3), np.repeat([-20.0, 25.0, 80.0], 41)
    thermal = d / "m_thermal.json"
    thermal.write_text(fit_thermal(thermal_sensor_v(x, t), t, x, (5, 3), norm="range").to_json())
    members = []
    for k, gain in enumerate((1.0, 1.04)):   # the second sensor 4 % more sensitive
        members.append(d / f"ft_{k}.csv")
        members[-1].write_text("displacement_mm,voltage_v,temperature_c\n" + "".join(
            f"{a:.12g},{b:.12g},{c:g}\n" for a, b, c in zip(x, thermal_sensor_v(x, t, gain), t)))
    for args in ((model, "-o", d / "fixed"), (model, "-o", d / "float18", "--format", "float18"),
                 ("--family", *recs, "--terms", 5, "-o", d / "family"),
                 (thermal, "-o", d / "thermal", "--temp-bits", 5, "--temp-lsb-c", 6),
                 # 4 terms, 4-bit temperature code: 10 calibrated codes
                 ("--family", *members, "--terms", 4, "-o", d / "family_thermal", "--temp-bits", 4,
                  "--temp-lsb-c", 12)):
        rc, _out, err = run_cli(["gen", *map(str, args), "--input-bits", str(SMALL_DESIGN_BITS)])
        if rc != 0:
            raise RuntimeError(f"flann gen {args} failed: {err}")
    # held out between and beside the calibration temperatures, for flann eval
    xh, th = np.tile(np.linspace(-9.5, 9.5, 39), 2), np.repeat([10.0, 65.0], 39)
    held = d / "held_thermal.csv"
    held.write_text("displacement_mm,voltage_v,temperature_c\n"
                    + "".join(f"{a:.12g},{b:.12g},{c:g}\n" for a, b, c in zip(xh, thermal_sensor_v(xh, th), th)))
    seed_render.write(derive_seed_spec(model, input_bits=SMALL_DESIGN_BITS), d / "seed")
    # the conditioner, written from a spec: one carrier period a window (its shortest benches)
    write_conditioner(derive_conditioner(carrier_hz=5000.0, output_rate_hz=5000.0), d / "conditioner", 5.0)
    shutil.copytree(REPO / "tests" / "implement" / "fixtures" / "synth" / "good", d / "plain")
    return {"dir": d, "model": model, "rec": recs[0], "thermal": thermal, "held_thermal": held}


@dataclass
class SimRun:
    """One ``flann sim`` of a small design, run in process: exit code, the text report, stderr, the
    summary (``--summary-json``), the PNG ``--plot`` wrote and what each of its figures held, axis
    by axis (title, y label, lines as (label, x, y))."""

    argv: list
    rc: int
    out: str
    err: str
    summary: dict | None
    png: Path
    figures: list


# the one simulation of each small design the tests share: the family's with its mapped netlist
# (its weight image loaded through the cfg port); the family with temperature with both sensors'
# images given, the design's last member first
SIM_FLAGS = {"fixed": (), "float18": (), "family": ("--netlist",), "thermal": (), "family_thermal": "images",
             "conditioner": ()}


def _captured_figures(run):
    """run() with every figure matplotlib saves recorded; (its result, the figures)."""
    from matplotlib.figure import Figure

    seen, save = [], Figure.savefig

    def keep(fig, *args, **kw):
        seen.append([{"title": ax.get_title(), "ylabel": ax.get_ylabel(),
                      "lines": [(ln.get_label(), np.asarray(ln.get_xdata(), dtype=float),
                                 np.asarray(ln.get_ydata(), dtype=float)) for ln in ax.get_lines()]}
                     for ax in fig.axes])
        return save(fig, *args, **kw)

    Figure.savefig = keep
    try:
        return run(), seen
    finally:
        Figure.savefig = save


def family_thermal_images(design: Path) -> list[Path]:
    """The weight images a family design keeps, in the manifest's order."""
    return [design / im["hex"] for im in json.loads((design / "manifest.json").read_text())["images"]]


@pytest.fixture(scope="session")
def small_sims(small_designs, once):
    """``small_sims(datapath)``: the :class:`SimRun` of that small design (``flann sim DIR --plot
    --summary-json`` with :data:`SIM_FLAGS`), simulated once per test run."""
    def make(datapath: str, d: Path) -> SimRun:
        design = small_designs["dir"] / datapath
        flags = SIM_FLAGS[datapath]
        if flags == "images":
            flags = [a for h in family_thermal_images(design)[::-1] for a in ("--image", h)]
        png, summary = d / "sim.png", d / "summary.json"
        argv = ["sim", design, "--plot", png, "--summary-json", summary, "--build", d / "build", *flags]
        (rc, out, err), figures = _captured_figures(lambda: run_cli(argv))
        # a plain dict in the shared store: pickle finds no class of a conftest module by name
        return {"argv": [str(a) for a in argv], "rc": rc, "out": out, "err": err, "png": png, "figures": figures,
                "summary": json.loads(summary.read_text()) if summary.is_file() else None}

    return lambda datapath: SimRun(**once(f"sim_{datapath}", lambda d: make(datapath, d)))


@pytest.fixture(scope="session")
def small_synths(small_designs, once):
    """``small_synths(datapath)``: ``flann synth DIR --json FILE`` of that small design (lint on, the
    mapped netlist checked against the twin), run once per test run: (exit code, text, stderr,
    the JSON report or None)."""
    def make(datapath: str, d: Path) -> tuple:
        report = d / "synth.json"
        rc, out, err = run_cli(["synth", small_designs["dir"] / datapath, "--json", report])
        return rc, out, err, json.loads(report.read_text()) if report.is_file() else None

    return lambda datapath: once(f"synth_{datapath}", lambda d: make(datapath, d))
