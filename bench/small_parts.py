"""Do realistic sensors' default designs fit the small Spartan-II parts?  Block RAMs and LUT4 per design.

Synthesises every design directory given (``flann synth DIR --device xc2s30-pq208-5 --json``:
GHDL + Yosys synth_xilinx -family xcv, with the timing estimate) and prints one row per design:
input/output bits and LSB, terms, LUT4, FF, block RAMs, the block RAMs of the sin/cos table
entity (``flann_expansion``), the table's address and word bits, the smallest Spartan-II that
fits, whether it fits an XC2S30 (864 LUT4, 6 block RAMs), and the Fmax estimate.

The designs are those ``../shared/checks/e2e_sensors.py`` writes and keeps (one temporary
directory per sensor, ``e2e_*/hdl``, in sensor order); run it with TMPDIR pointing at an
empty directory, then pass that directory:

    TMPDIR=/tmp/e2e .venv/bin/python ../shared/checks/e2e_sensors.py --n 20 --seed 7
    .venv/bin/python bench/small_parts.py /tmp/e2e [--device xc2s30-pq208-5] [--json OUT.json]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

FLANN = Path(sys.executable).with_name("flann")


def designs(root: Path) -> list[Path]:
    dirs = [d / "hdl" for d in root.glob("e2e_*") if (d / "hdl" / "manifest.json").is_file()]
    if not dirs and (root / "manifest.json").is_file():
        dirs = [root]
    return sorted(dirs, key=lambda d: d.parent.stat().st_mtime)


def measure(hdl: Path, device: str) -> dict:
    man = json.loads((hdl / "manifest.json").read_text())
    spec = man.get("spec", {})
    r = subprocess.run([str(FLANN), "synth", str(hdl), "--device", device, "--json", "--no-lint",
                        "--no-netlist-check"], capture_output=True, text=True,
                       env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    if not r.stdout.strip():
        return {"design": str(hdl), "error": (r.stderr.strip().splitlines() or ["?"])[-1]}
    rep = json.loads(r.stdout)
    return {
        "design": str(hdl),
        "input_bits": man["input_bits"], "output_bits": man["output_bits"], "output_lsb_mm": man["output_lsb_mm"],
        "terms": spec.get("terms"), "table_addr_bits": spec.get("table_addr_bits"),
        "luts": rep["luts"], "ffs": rep["ffs"], "brams": rep["brams"],
        "table_brams": rep["entities"].get("flann_expansion", {}).get("brams"),
        "fits": rep["fits"], "smallest": rep["smallest_device"],
        "fmax_mhz_estimate": (rep.get("timing") or {}).get("fmax_mhz_estimate"),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("root", type=Path, help="directory holding e2e_*/hdl (or one design directory)")
    ap.add_argument("--device", default="xc2s30-pq208-5")
    ap.add_argument("--json", type=Path, default=None, help="also write the rows here")
    a = ap.parse_args()
    rows = []
    print(f"{'#':>2} {'in':>3} {'out':>3} {'LSB mm':>8} {'terms':>5} {'addr':>4} {'LUT4':>5} {'FF':>5} {'BRAM':>4} "
          f"{'table':>5} {'fits':>5} {'smallest':>16} {'Fmax est':>8}")
    for i, hdl in enumerate(designs(a.root)):
        row = measure(hdl, a.device)
        rows.append(row)
        if "error" in row:
            print(f"{i:>2} error: {row['error']}")
            continue
        print(f"{i:>2} {row['input_bits']:>3} {row['output_bits']:>3} {row['output_lsb_mm']:>8.3g} {row['terms']:>5} "
              f"{row['table_addr_bits']:>4} {row['luts']:>5} {row['ffs']:>5} {row['brams']:>4} {row['table_brams']:>5} "
              f"{'yes' if row['fits'] else 'no':>5} {row['smallest'] or 'none':>16} {row['fmax_mhz_estimate']:>8}",
              flush=True)
    ok = [r for r in rows if "error" not in r]
    print(f"{sum(r['fits'] for r in ok)}/{len(rows)} designs fit {a.device}; block RAMs: "
          f"min {min((r['brams'] for r in ok), default=0)}, max {max((r['brams'] for r in ok), default=0)}")
    if a.json:
        a.json.write_text(json.dumps(rows, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
