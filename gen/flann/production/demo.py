"""A simulated production batch: sensors of varied geometry from the physics simulator.

Each sensor is the paper's LVDT (``data/sensors/paper_lvdt.toml`` = :func:`default_sensor`)
with its winding and core geometry drawn within +-``spread`` (seeded; stroke kept monotonic), simulated as one
forward+reverse sweep of ``points`` samples with noise; its sensor TOML is written beside
the recordings so every sensor can be re-simulated.  ``bad_files`` adds recordings a line
would meet: unreadable, a missing column, a sensor far outside the family.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..fileio import atomic_write_text
from ..physics.sensor import default_sensor, format_sensor
from ..physics.simulate import fold_back_mm, simulate_recordings
from ..recordings import write_recordings

GEOMETRY = ("primary_length_mm", "secondary_length_mm", "secondary_gap_mm", "core_length_mm",
            "secondary_turns", "core_outer_diameter_mm")
NOISE_V = 0.2e-3


def varied_sensor(k: int, seed: int = 1, spread: float = 0.05):
    """The paper's LVDT with geometry drawn within +-spread; its rated stroke kept where the
    output is monotonic (90 % of the fold-back point), as a data sheet would rate it."""
    rng = np.random.default_rng([seed, k])
    s = default_sensor()
    changes = {f: float(getattr(s, f)) * float(rng.uniform(1 - spread, 1 + spread)) for f in GEOMETRY}
    s = s.replace(name=f"lvdt_{k:04d}", description=f"paper LVDT, geometry +-{spread:.0%} (seed {seed}, #{k})",
                  **changes)
    fold = fold_back_mm(s, (-s.stroke_mm, s.stroke_mm))
    if fold is not None:
        s = s.replace(stroke_mm=round(0.9 * fold, 1))
    return s


def write_batch(out_dir, n: int, *, seed: int = 1, points: int = 2000, spread: float = 0.05) -> list[Path]:
    """n recordings (+ their sensor TOMLs) in ``out_dir``; returns the CSV paths."""
    out = Path(out_dir)
    paths = []
    for k in range(n):
        s = varied_sensor(k, seed, spread)
        step = 2 * s.stroke_mm / (points / 2 - 1)  # forward + reverse: points samples in all
        rec = simulate_recordings(s, step_mm=step, noise_v=NOISE_V, seed=seed * 100003 + k)
        p = out / f"{s.name}.csv"
        write_recordings(p, rec, comments=(f"simulated by flann.physics: {s.description}",))
        atomic_write_text(out / f"{s.name}.toml", format_sensor(s))
        paths.append(p)
    return paths


def bad_files(out_dir) -> list[Path]:
    """Three recordings that must fail: not a CSV, no voltage column, a sensor outside the family."""
    out = Path(out_dir)
    garbage = out / "bad_garbage.csv"
    atomic_write_text(garbage, "this is not\x00 a recordings file\n\x01\x02\n")
    nocol = out / "bad_no_voltage.csv"
    atomic_write_text(nocol, "displacement_mm,temperature_c\n" + "".join(f"{x},20\n" for x in range(-5, 6)))
    s = default_sensor()
    big = s.replace(name="bad_out_of_family", excitation_amplitude_vpp=s.excitation_amplitude_vpp * 4)
    rec = simulate_recordings(big, step_mm=2 * s.stroke_mm / 199, noise_v=NOISE_V)
    far = out / "bad_out_of_family.csv"
    write_recordings(far, rec, comments=("simulated: 4x the excitation, outside the family's input range",))
    return [garbage, nocol, far]


__all__ = ["write_batch", "bad_files", "varied_sensor", "GEOMETRY"]
