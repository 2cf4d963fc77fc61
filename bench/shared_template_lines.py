"""How much of the fixed top level (flann_top.vhd.j2) the other tops repeat.

Two counts over code lines (blank and comment lines left out, white space folded): every line
of flann_top that the other template also holds (a multiset intersection), and the lines of
flann_top in runs of six or more consecutive lines the other template repeats as they are.
What remains after the shared sequencer (flann_seq) are the entity ports and the port maps of
the shared blocks each top instantiates.

    .venv/bin/python bench/shared_template_lines.py [--base REV]
"""

from __future__ import annotations

import argparse
import collections
import subprocess
from difflib import SequenceMatcher
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
T = "gen/flann/hardware"
FIXED = f"{T}/fixed/templates/flann_top.vhd.j2"
OTHERS = (f"{T}/family/templates/flann_family_top.vhd.j2", f"{T}/float18/templates/f18_top.vhd.j2")


def code(text: str) -> list[str]:
    out = []
    for line in text.splitlines():
        s = " ".join(line.split())
        if s and not s.startswith("--") and not s.startswith("{#"):
            out.append(s)
    return out


def read(path: str, rev: str | None) -> str:
    if rev is None:
        return (ROOT / path).read_text()
    return subprocess.run(["git", "show", f"{rev}:{path}"], cwd=ROOT, check=True, capture_output=True,
                          text=True).stdout


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--base", default=None, help="a git revision to measure instead of the working tree")
    args = p.parse_args()
    base = code(read(FIXED, args.base))
    for other in OTHERS:
        o = code(read(other, args.base))
        a, b = collections.Counter(base), collections.Counter(o)
        shared = sum(min(n, b[k]) for k, n in a.items())
        runs = sum(m.size for m in SequenceMatcher(None, base, o, autojunk=False).get_matching_blocks()
                   if m.size >= 6)
        print(f"{Path(other).name}: shares {shared} of flann_top's {len(base)} code lines; "
              f"{runs} in runs of >= 6")


if __name__ == "__main__":
    main()
