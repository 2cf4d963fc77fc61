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
    .venv/bin/python bench/small_parts.py --rows OUT.json     # print again, no synthesis

Columns right of "|" are a PROJECTION (see ``projection``): "shared" is built since (the spec's
``table_style`` "shared": the column equals the measured block RAMs of such designs, up to
Yosys keeping a bit out of the block RAMs); "2nd" (second-order interpolation) is not built.
"""

from __future__ import annotations

import argparse
import json
import math
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


BRAM_BITS = 4096  # DS001: one Spartan-II block RAM
XC2S30_BRAMS = 6


def blocks(width: int, addr_bits: int) -> int:
    """Block RAMs of a 2^addr_bits x width ROM (RAMB4 aspect ratios 4096x1 .. 256x16), as the
    generator's estimate counts them."""
    per_block = min(16, max(1, BRAM_BITS >> addr_bits))
    return math.ceil(width / per_block) * max(1, (1 << addr_bits) // BRAM_BITS)


def projection(row: dict) -> dict:
    """Block RAMs of the design with a shared table (built: ``table_style`` "shared") and with
    second-order interpolation (not built; docs/synthesis.md):

    shared: the slope read from the value table itself (slope(k) = pi/2 cos(mid_k) = pi/2 value(N-1-k),
            the second port of the same dual-port RAMB4 reads the mirrored address);
    second: second-order interpolation sin(mid + d) ~ s + c d - s d^2/2 with s, c both from that one
            shared table, its residual h^3/6 (h = pi/2 2^-(A+1)) held to the first-order budget e_t/4,
            e_t = 2^-Tf (term fraction bits Tf: the narrowest e_t the spec's rounding allows).
    """
    value_bits, slope_bits, a = row["value_bits"], row["slope_bits"], row["table_addr_bits"]
    tf = value_bits - 1
    e_t = 2.0 ** -tf
    a2 = max(2, math.ceil(math.log2((math.pi / 2) / (6 * e_t / 4) ** (1 / 3)) - 1))
    other = row["brams"] - row["table_brams"]
    return {"now_table": blocks(value_bits, a) + blocks(slope_bits, a),
            "shared": other + blocks(value_bits, a),
            "second_addr_bits": a2, "second": other + blocks(value_bits, a2)}


def _fmt_bits(fmt: str) -> int:
    return int(fmt.split("<")[1].split(",")[0])  # "ufix<22,1,rnd,sat>" -> 22


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
        "value_bits": _fmt_bits(spec["value"]), "slope_bits": _fmt_bits(spec["slope"]),
        "luts": rep["luts"], "ffs": rep["ffs"], "brams": rep["brams"],
        "table_brams": rep["entities"].get("flann_expansion", {}).get("brams"),
        "fits": rep["fits"], "smallest": rep["smallest_device"],
        "fmax_mhz_estimate": (rep.get("timing") or {}).get("fmax_mhz_estimate"),
        "estimate": man.get("analysis", {}).get("estimate"),
        "entities": {k: v["luts"] for k, v in rep["entities"].items()},
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("root", type=Path, nargs="?", help="directory holding e2e_*/hdl (or one design directory)")
    ap.add_argument("--device", default="xc2s30-pq208-5")
    ap.add_argument("--json", type=Path, default=None, help="also write the rows here")
    ap.add_argument("--rows", type=Path, default=None, help="print the rows of an earlier --json run (no synthesis)")
    a = ap.parse_args()
    if (a.root is None) == (a.rows is None):
        ap.error("give ROOT or --rows")
    print(f"{'#':>2} {'in':>3} {'out':>3} {'LSB mm':>8} {'terms':>5} {'addr':>4} {'val':>3} {'slp':>3} {'LUT4':>5} "
          f"{'FF':>5} {'BRAM':>4} {'table':>5} {'fits':>5} {'smallest':>16} {'Fmax':>5} | {'shared':>6} "
          f"{'2nd (addr)':>10}")
    rows = json.loads(a.rows.read_text()) if a.rows else []
    todo = [None] * len(rows) if a.rows else designs(a.root)
    for i, hdl in enumerate(todo):
        row = rows[i] if a.rows else measure(hdl, a.device)
        if "value_bits" not in row and "error" not in row:  # rows of an older run: widths from the manifest
            spec = json.loads((Path(row["design"]) / "manifest.json").read_text())["spec"]
            row.update(value_bits=_fmt_bits(spec["value"]), slope_bits=_fmt_bits(spec["slope"]))
        if not a.rows:
            rows.append(row)
        if "error" in row:
            print(f"{i:>2} error: {row['error']}")
            continue
        pr = projection(row)
        print(f"{i:>2} {row['input_bits']:>3} {row['output_bits']:>3} {row['output_lsb_mm']:>8.3g} {row['terms']:>5} "
              f"{row['table_addr_bits']:>4} {row['value_bits']:>3} {row['slope_bits']:>3} {row['luts']:>5} "
              f"{row['ffs']:>5} {row['brams']:>4} {row['table_brams']:>5} {'yes' if row['fits'] else 'no':>5} "
              f"{row['smallest'] or 'none':>16} {row['fmax_mhz_estimate']:>5} | {pr['shared']:>6} "
              f"{pr['second']:>5} ({pr['second_addr_bits']:>2})", flush=True)
    ok = [r for r in rows if "error" not in r]
    print(f"measured: {sum(r['fits'] for r in ok)}/{len(rows)} designs fit {a.device}; block RAMs "
          f"min {min((r['brams'] for r in ok), default=0)}, max {max((r['brams'] for r in ok), default=0)}; "
          f"LUT4 max {max((r['luts'] for r in ok), default=0)}")
    for key, what in (("shared", "one shared sin/slope table"), ("second", "second order, one shared table")):
        n = sum(projection(r)[key] <= XC2S30_BRAMS for r in ok)
        print(f"projected ({what}, block RAMs only): {n}/{len(rows)} within the XC2S30's "
              f"{XC2S30_BRAMS} block RAMs; max {max((projection(r)[key] for r in ok), default=0)}")
    if a.json and not a.rows:
        a.json.write_text(json.dumps(rows, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
