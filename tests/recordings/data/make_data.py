"""Writes the bench-export shapes of tests/recordings/test_bench_exports.py (run from this
directory; the files are committed beside it).  Each is a shape a bench or a spreadsheet
really exports; the numbers are closed-form LVDT curves with seeded noise."""

import numpy as np

rng = np.random.default_rng(46)


def s_curve(x, gain=1.0, half=22.0):
    return 5.0 * gain * np.tanh(1.6 * x / half)


def write(name, header, rows, sep=",", above=()):
    with open(name, "w", encoding="utf-8") as fh:
        for line in above:
            fh.write(line + "\n")
        fh.write(sep.join(header) + "\n")
        for r in rows:
            fh.write(sep.join(r) + "\n")


x = np.linspace(-20, 20, 41)
# four LVDTs of one rig, one file
rows = []
for k, sid in enumerate(("LV-101", "LV-102", "LV-103", "LV-104")):
    v = s_curve(x, 1.0 + 0.03 * k) + rng.normal(0, 0.002, x.size)
    rows += [(sid, f"{a:g}", f"{b:.6f}") for a, b in zip(x, v)]
write("four_sensors.csv", ("sensor_id", "displacement_mm", "voltage_v"), rows)
# both secondary amplitudes
r = 0.9 * np.tanh(x / 18.0)
a, b = 1.5 * (1 + r) / 2 + rng.normal(0, 5e-4, x.size), 1.5 * (1 - r) / 2 + rng.normal(0, 5e-4, x.size)
write("ab_export.csv", ("Position (mm)", "Secondary A (V)", "Secondary B (V)"),
      [(f"{p:g}", f"{u:.6f}", f"{w:.6f}") for p, u, w in zip(x, a, b)])
# clipped at an amplifier rail: 7 readings flat at +4.2 V
v = np.minimum(s_curve(x) + rng.normal(0, 0.002, x.size), 4.2)
v[-7:] = 4.2
write("clipped.csv", ("displacement_mm", "voltage_v"), [(f"{p:g}", f"{u:.6f}") for p, u in zip(x, v)])
# a clean cubic whose output turns back at +-15.8 mm
xc = np.arange(-20, 21, 2.0)
write("cubic.csv", ("displacement_mm", "voltage_v"),
      [(f"{p:g}", f"{0.3 * p - 0.0004 * p ** 3:.6f}") for p in xc])
# a title line and metadata above the header
v = s_curve(x) + rng.normal(0, 0.002, x.size)
write("title_export.csv", ("Displacement (mm)", "Voltage (V)"), [(f"{p:g}", f"{u:.6f}") for p, u in zip(x, v)],
      above=("LVDT calibration bench 3 - export", "Operator: QA; Date: 2026-11-02"))
# German headers, semicolons, decimal commas
write("german_export.csv", ("Weg (mm)", "Spannung (V)"),
      [(f"{p:g}".replace(".", ","), f"{u:.6f}".replace(".", ",")) for p, u in zip(x, v)], sep=";")
# one sweep, 36 positions over 0..44 mm, an S-curve with two rough readings
xs = np.linspace(0, 44, 36)
v = 5.0 * np.tanh((xs - 22.0) / 12.0) + rng.normal(0, 0.003, xs.size)
v[9] += 0.35
v[23] -= 0.5
write("rough_s_curve.csv", ("displacement_mm", "voltage_v"), [(f"{p:.4f}", f"{u:.6f}") for p, u in zip(xs, v)])
