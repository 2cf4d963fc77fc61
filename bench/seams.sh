#!/bin/bash
# Every command's output into the next, as a user would, on a sensor the project did not make
# (an asymmetric erf S-curve plus a cubic, 12-bit converter, two sweeps): train -> gen -> sim DIR
# -> synth -> ise for the fixed and float18 datapaths, and gen --family -> calibrate ->
# sim --image -> synth -> ise for a family.  Prints each command's exit code and its figures.
# Usage: bench/seams.sh [WORKDIR]   (from the repository root, after `make venv tools`)
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 PATH="$ROOT/.venv/bin:$PATH"
W=${1:-$(mktemp -d)}; mkdir -p "$W"; cd "$W"; echo "work $W"
rec() {  # rec OUT SEED GAIN
  python - "$@" <<'PY'
import sys
import numpy as np
from scipy.special import erf
out, seed, gain = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
rng, lsb = np.random.default_rng(seed), 5.0 / 4096
xs = np.arange(-25, 25.0001, 0.5)
x = np.concatenate([xs, xs[::-1]])
d = np.concatenate([np.ones(xs.size), -np.ones(xs.size)])
u = x - 1.3
v = 1.9 * gain * erf(u / 11) + 0.012 * (u / 10) ** 3 - 0.0004 * u ** 2 + 0.045 + rng.normal(0, 8e-4, x.size)
with open(out, "w") as f:
    f.write("displacement_mm,voltage_v,direction\n")
    f.writelines(f"{a:g},{b:.6f},{int(c)}\n" for a, b, c in zip(x, np.round(v / lsb) * lsb, d))
PY
}
js() { python -c "import json,sys; d=json.load(open(sys.argv[1])); print(*[d[k] for k in sys.argv[2:]])" "$@"; }
rec rec.csv 5 1.0
flann train rec.csv -o m.json --input-bits 12 --input-lsb-v 0.001220703125 > /dev/null 2>&1; echo "train rc $?"
for dp in fixed float18; do
  flann gen m.json -o $dp --input-bits 10 --format $dp > /dev/null 2>&1; echo "gen $dp rc $?"
  flann sim $dp --json --build b_$dp > sim_$dp.json; echo "sim $dp rc $?: codes, mismatches, max_err_mm $(js sim_$dp.json codes_tested mismatches max_err_mm)"
  flann synth $dp --json > syn_$dp.json 2> /dev/null; echo "synth $dp rc $?: luts, brams, smallest $(js syn_$dp.json luts brams smallest_device)"
  flann ise $dp -o ise_$dp --device "$(js syn_$dp.json smallest_device)" > /dev/null 2>&1; echo "ise $dp rc $?"
done
for s in 11 12 13 15; do rec f$s.csv $s 1.0$((s % 3)); done
flann gen --family f11.csv f12.csv f13.csv -o fam --input-bits 10 > /dev/null 2>&1; echo "gen --family rc $?"
flann calibrate f11.csv f15.csv -o cal --design fam -j 2 > /dev/null 2>&1; echo "calibrate rc $?: $(cut -d, -f1,2,4 cal/summary.csv | tail -n +2 | tr '\n' ' ')"
flann sim fam --image cal/f15/weights.hex --json --build b_fam > sim_fam.json; echo "sim --image rc $?: codes, mismatches, image_max_err_mm $(js sim_fam.json codes_tested mismatches image_max_err_mm)"
flann synth fam --json > syn_fam.json 2> /dev/null; echo "synth fam rc $?: luts, brams, smallest $(js syn_fam.json luts brams smallest_device)"
flann ise fam -o ise_fam --device "$(js syn_fam.json smallest_device)" > /dev/null 2>&1; echo "ise fam rc $?"
