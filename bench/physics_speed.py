"""Speed of the LVDT physics on this machine: prints the figures quoted in docs/physics.md.

    .venv/bin/python bench/physics_speed.py

* ideal_output_v for 2000 distinct positions, new positions every call (same geometry:
  interpolated from the geometry's table),
* the same with a new geometry every call (table rebuilt), and 13 points (exact solve),
* the same call with the positions cached (a fit varying only electrical parameters),
* simulate_output_v with every catalogue effect on, 2000 points,
* Sensor.replace (validation) per call.
"""

import time

import numpy as np

from flann.physics import lvdt
from flann.physics.effects import EFFECTS
from flann.physics.sensor import default_sensor
from flann.physics.simulate import simulate_output_v


_CALLS = iter(range(10**9))


def per_call_ms(fn, repeat):
    """Best of 3 rounds; fn gets a call number that is never repeated (no cache hits)."""
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        for _i in range(repeat):
            fn(next(_CALLS))
        best = min(best, (time.perf_counter() - t0) / repeat)
    return best * 1e3


def main():
    s = default_sensor()
    x = np.linspace(-30, 30, 2000)
    print(f"ideal_output_v, 2000 new positions:   {per_call_ms(lambda i: lvdt.ideal_output_v(s, x + 1e-6 * (i + 1)), 50):.2f} ms/call")
    print(f"ideal_output_v, 2000 positions, new geometry every call (exact table build): "
          f"{per_call_ms(lambda i: lvdt.ideal_output_v(s.replace(secondary_gap_mm=13.0 + 1e-6 * i), x), 10):.2f} ms/call")
    print(f"ideal_output_v, 13 positions, new geometry every call (exact): "
          f"{per_call_ms(lambda i: lvdt.ideal_output_v(s.replace(secondary_gap_mm=12.0 + 1e-6 * i), x[::150]), 50):.2f} ms/call")
    lvdt.ideal_output_v(s, x)
    print(f"ideal_output_v, 2000 cached positions: {per_call_ms(lambda i: lvdt.ideal_output_v(s, x), 200):.3f} ms/call")
    full = s
    for name in EFFECTS:
        full = full.with_effect(name)
    d = np.where(np.arange(x.size) % 2 == 0, 1.0, -1.0)
    temp = np.linspace(20, 30, x.size)
    print(f"simulate_output_v, all {len(EFFECTS)} effects, 2000 points: "
          f"{per_call_ms(lambda i: simulate_output_v(full, x + 1e-6 * (i + 1), d, temp), 20):.2f} ms/call")
    print(f"Sensor.replace (validated):           {per_call_ms(lambda i: s.replace(demodulator_gain_ratio=1.0 + i), 500) * 1e3:.0f} us/call")


if __name__ == "__main__":
    main()
