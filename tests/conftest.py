"""Shared fixtures: the repository's data files, located once."""

from pathlib import Path

import numpy as np
import pytest

from flann.cli import main
from flann.golden.thermal_train import fit_thermal
from flann.golden.train import fit_lstsq
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
def small_designs(tmp_path_factory) -> dict:
    """Small designs (4-5 terms, 8-bit input) of every datapath flann gen writes, by datapath
    name under ``dir``; ``model`` the one-input model, ``rec`` a recording of its sensor,
    ``thermal`` the two-input model (of :func:`thermal_sensor_v`)."""
    d = tmp_path_factory.mktemp("small_designs")
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
        if main(["gen", *map(str, args), "--input-bits", str(SMALL_DESIGN_BITS)]) != 0:
            raise RuntimeError(f"flann gen {args} failed")
    return {"dir": d, "model": model, "rec": recs[0], "thermal": thermal}
