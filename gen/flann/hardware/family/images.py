"""Weight images of one sensor for a family design: a plain hex image for a loader on the
``cfg_*`` port, a Data2MEM ``.mem`` file and the ``.bmm`` template it needs (docs/production.md).

* ``weights.hex``: ``#`` comment lines first (provenance: sensor, design and model sha256,
  word count), then one word per line, ``DATA_BITS / 4`` hex digits, address 0 first, every
  address of the memory (``mem_depth`` word lines).  A loader skips the ``#`` lines and
  writes the k-th word line at ``cfg_addr = k`` with ``cfg_we = 1``, one word per clock
  (:func:`parse_hex` reads it so).
* ``weights.mem``: Data2MEM's format: ``@ADDR`` (hex) then the block RAM's 16-bit words in
  hex, whitespace separated, in block address order: the memory is one RAMB4_S16_S16 holding
  word k as bits 15:0 at 2k and bits 31:16 at 2k + 1 (:func:`flann.hardware.family.spec.bram_image`).
* ``weights.bmm``: that address space with placeholders for the RAMB4's instance name and
  LOC, to be filled from ISE's placement (``PLACED`` report or FPGA Editor); then
  ``data2mem -bm weights.bmm -bd weights.mem -bt top.bit -o b new.bit`` writes a bitstream
  with this sensor's memory, without synthesis, place or route.
"""

from __future__ import annotations

import re

from ...errors import FlannError
from ...inputs import read_text
from ..fixed.spec import acc_bound_for, lin_acc_reach
from .render import image_text
from .spec import DATA_BITS, HALF_BITS, FamilySpec, bram_image
from .twin import FlannFamilyMem

HEX_DIGITS = DATA_BITS // 4
MEM_DIGITS = HALF_BITS // 4
# flann calibrate's names for every sensor's image and model, in the sensor's own folder
IMAGE_FILE = "weights.hex"
MODEL_FILE = "model.json"


def hex_text(words, header: list[str] = ()) -> str:
    """``weights.hex``: ``#`` header lines, then the words as the design's own images hold them."""
    return "".join(f"# {h}\n" for h in header) + image_text(words)


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


def check_image(fam: FamilySpec, words: list[int], source: str = "<hex>") -> None:
    """Refuse, in one line, an image the design cannot compute with: a word holding more than
    its field (a field's words hold its value sign-extended), or values whose worst case (every
    term at its largest, as the design's widths were sized) overflows a format the hardware
    does not saturate in (the linear accumulator, the products, the running sum): the
    hardware would wrap where its twin saturates.  Every image flann calibrate or flann gen
    writes passes (their sensors were fitted to these formats)."""
    if len(words) > fam.mem_depth:
        raise FlannError(f"{source}: {len(words)} words, the design's memory holds {fam.mem_depth}")
    words = list(words) + [0] * (fam.mem_depth - len(words))
    for f in fam.fields:
        per = 1 if f.name == "weights" else f.words   # a weight is one word each
        for k in range(0, f.words, per):
            v = 0
            for w in words[f.addr + k:f.addr + k + per]:
                v = (v << DATA_BITS) | w
            top = per * DATA_BITS
            fits = (v < (1 << (f.bits - 1)) or v >= (1 << top) - (1 << (f.bits - 1))) if f.signed else v < (1 << f.bits)
            if not fits:
                raise FlannError(f"{source}: word {f.addr + k} ({f.name}) 0x{v:0{per * HEX_DIGITS}X} does not fit the "
                                 f"field's {'s' if f.signed else 'u'}int<{f.bits}> (the bits above it must repeat its sign)")
    s = FlannFamilyMem(fam, words).spec()
    e = fam.spec
    weights = [w for lane in s.weight_rom for w in lane]
    Gl = s.lin_guard
    lin_peak = max(abs((s.k1 * c + s.k0 + (1 << (Gl - 1))) >> Gl) for c in (s.clamp_lo, s.clamp_hi)) + 1
    wmax = max(abs(w) for w in weights)
    checks = (
        ("the clamp codes", 0 if e.code_min <= s.clamp_lo <= s.clamp_hi <= e.code_max else 1, 0),
        ("the linear accumulator", lin_acc_reach(s.k1, s.k0, e.input_bits), (1 << (e.lin_width - 2)) - 1),
        ("the linear part", lin_peak, e.lin_fmt.max_int),
        ("a product", (e.term_bound * wmax + (1 << (e.product_shift - 1))) >> e.product_shift, e.product_fmt.max_int),
        ("the running sum", acc_bound_for(lin_peak, weights, e.term_bound, e.product_shift), e.acc_fmt.max_int),
    )
    for what, need, have in checks:
        if need > have:
            why = (f"clamp codes {s.clamp_lo}..{s.clamp_hi} are not within the input codes {e.code_min}..{e.code_max}"
                   if what == "the clamp codes" else
                   f"{what} could reach {need}, the design holds {have}: its weights could overflow the hardware")
            raise FlannError(f"{source}: {why}; load only images flann calibrate wrote for this design")


# the provenance lines of the ``#`` header flann calibrate writes: the design, the word count
_HEADER_DESIGN = re.compile(r"#\s*design sha256 ([0-9a-f]{64})\b")
_HEADER_WORDS = re.compile(r"#\s*(\d+) words x (\d+) bits\b")
_HEADER_MODEL = re.compile(r"#\s*model sha256 ([0-9a-f]{64})\b")


def provenance_header(tool: str, sensor: str, design_sha256: str, model_sha256: str, words: int,
                      layout: str = "address 0 first") -> list[str]:
    """The ``#`` header lines of a calibrated image, as :func:`header_fields` reads them back:
    who wrote it for which sensor, the design and model it belongs to, its size and layout."""
    return [f"{tool}: sensor {sensor}", f"design sha256 {design_sha256}", f"model sha256 {model_sha256}",
            f"{words} words x {DATA_BITS} bits, {layout}"]


def header_fields(text: str) -> tuple[str | None, int | None]:
    """(design sha256, word count) an image's ``#`` header states (None where it states none)."""
    design = words = None
    for line in (ln.strip() for ln in text.splitlines()):
        if not line.startswith("#"):
            continue
        if design is None and (m := _HEADER_DESIGN.match(line)):
            design = m.group(1)
        if words is None and (m := _HEADER_WORDS.match(line)):
            words = int(m.group(1))
    return design, words


def header_model_sha256(text: str) -> str | None:
    """The sha256 of the model.json an image's ``#`` header names (None where it names none)."""
    found = (_HEADER_MODEL.match(ln.strip()) for ln in text.splitlines() if ln.strip().startswith("#"))
    return next((m.group(1) for m in found if m), None)


def read_image(path) -> list[int]:
    """The words of a weight image file (``weights.hex``), or one error line."""
    return parse_hex(read_text(path, FlannError, "a weight image (.hex)"), str(path))


def mem_text(words, header: list[str] = ()) -> str:
    """Data2MEM .mem: the block RAM's 16-bit words from address 0, 8 a line."""
    halves = bram_image(words)
    lines = [f"// {h}" for h in header] + ["@0000"]
    for k in range(0, len(halves), 8):
        lines.append(" ".join(format(h, f"0{MEM_DIGITS}X") for h in halves[k:k + 8]))
    return "\n".join(lines) + "\n"


def bmm_text(fam: FamilySpec, header: list[str] = ()) -> str:
    """Data2MEM block memory map of the weight memory (instance names and LOCs to fill in)."""
    top = (fam.mem_depth * DATA_BITS // 8) - 1  # bytes: 2 x mem_depth halves of 16 bits
    lines = [f"// {h}" for h in header] + [
        "// Fill in the RAMB4 instance path and LOC from ISE's placement of i_mem",
        "// (e.g. from the .ncd with FPGA Editor, or the PLACED lines of `data2mem -bm ... -bx`).",
        f"// Word k of the memory map is bits {HALF_BITS - 1}:0 at 16-bit address 2k, bits {DATA_BITS - 1}:{HALF_BITS} at 2k + 1.",
        f"ADDRESS_SPACE flann_family_mem RAMB4 [0x00000000:0x{top:08X}]",
        "  BUS_BLOCK",
        f"    <INSTANCE> [{HALF_BITS - 1}:0] LOC = <LOC>;",
        "  END_BUS_BLOCK;",
        "END_ADDRESS_SPACE;",
    ]
    return "\n".join(lines) + "\n"


__all__ = ["check_image", "IMAGE_FILE", "MODEL_FILE", "hex_text", "header_fields", "header_model_sha256", "provenance_header", "parse_hex", "read_image", "mem_text", "bmm_text", "HEX_DIGITS", "MEM_DIGITS"]
