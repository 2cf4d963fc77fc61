"""Weight images of one sensor for a family design: a plain hex image for a loader on the
``cfg_*`` port, a Data2MEM ``.mem`` file and the ``.bmm`` template it needs (docs/production.md).

* ``weights.hex``: one word per line, ``DATA_BITS / 4`` hex digits, line k = address k, every
  address of the memory (``mem_depth`` lines); ``#`` lines are comments.  A loader writes
  line k at ``cfg_addr = k`` with ``cfg_we = 1``, one word per clock.
* ``weights.mem``: Data2MEM's format: ``@ADDR`` (hex) then the words in hex, whitespace
  separated.  The 32-bit word is split over two RAMB4_S16 (bits 31:16 and 15:0), which the
  ``.bmm`` describes as one bus of two block RAMs.
* ``weights.bmm``: the address space with placeholders for the two RAMB4 instance names
  and their LOCs, to be filled from ISE's placement (``PLACED`` report or FPGA Editor); then
  ``data2mem -bm weights.bmm -bd weights.mem -bt top.bit -o b new.bit`` writes a bitstream
  with this sensor's memory, without synthesis, place or route.
"""

from __future__ import annotations

from ..errors import FlannError
from ..hardware.family.spec import DATA_BITS, FamilySpec

HEX_DIGITS = DATA_BITS // 4


def hex_text(words, header: list[str] = ()) -> str:
    lines = [f"# {h}" for h in header]
    lines += [format(int(w), f"0{HEX_DIGITS}x") for w in words]
    return "\n".join(lines) + "\n"


def parse_hex(text: str, source: str = "<hex>") -> list[int]:
    words = []
    for n, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        try:
            w = int(line, 16)
        except ValueError:
            raise FlannError(f"{source}:{n}: {line!r} is not a hex word") from None
        if not 0 <= w < (1 << DATA_BITS):
            raise FlannError(f"{source}:{n}: {line} does not fit {DATA_BITS} bits")
        words.append(w)
    return words


def mem_text(words, header: list[str] = ()) -> str:
    """Data2MEM .mem: word addresses of the 32-bit bus, 8 words a line."""
    lines = [f"// {h}" for h in header] + ["@0000"]
    for k in range(0, len(words), 8):
        lines.append(" ".join(format(int(w), f"0{HEX_DIGITS}X") for w in words[k:k + 8]))
    return "\n".join(lines) + "\n"


def bmm_text(fam: FamilySpec, header: list[str] = ()) -> str:
    """Data2MEM block memory map of the weight memory (instance names and LOCs to fill in)."""
    top = (fam.mem_depth * DATA_BITS // 8) - 1
    lines = [f"// {h}" for h in header] + [
        "// Fill in the two RAMB4 instance paths and LOCs from ISE's placement of i_mem",
        "// (e.g. from the .ncd with FPGA Editor, or the PLACED lines of `data2mem -bm ... -bx`).",
        f"ADDRESS_SPACE flann_family_mem RAMB4 [0x00000000:0x{top:08X}]",
        "  BUS_BLOCK",
        "    <INSTANCE_HI> [31:16] LOC = <LOC_HI>;",
        "    <INSTANCE_LO> [15:0] LOC = <LOC_LO>;",
        "  END_BUS_BLOCK;",
        "END_ADDRESS_SPACE;",
    ]
    return "\n".join(lines) + "\n"


__all__ = ["hex_text", "parse_hex", "mem_text", "bmm_text", "HEX_DIGITS"]
