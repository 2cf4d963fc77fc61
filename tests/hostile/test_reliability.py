"""Reliability beyond one command's exit line: hangs end, interrupted runs leave nothing behind,
the family hardware saturates on every image its loader accepts.  Each table row is one defect
an outside tester found; each fails without its fix."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from flann.cli import main
from flann.errors import FlannError
from flann.fileio import atomic_directory
from flann.hardware.family.images import check_image, hex_text, read_image
from flann.hardware.family.render import load_design
from flann.hardware.design import from_directory
from flann.hardware.family.twin import FlannFamilyTop
from flann.pool import run_batch
from flann.verify.netlist import check_netlist

REPO = Path(__file__).resolve().parents[2]
WAIT_S = 60.0   # the longest any state here may take to arrive before the test gives up


def wait_for(cond, what: str, limit: float = WAIT_S) -> None:
    end = time.monotonic() + limit
    while not cond():
        if time.monotonic() > end:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.05)


# ------------------------------------------------------------------ an interrupted directory swap
def _killed_swap(root: Path, dead_pid: int) -> None:
    """What a SIGKILL between the two renames of a swap leaves: no out/, the old one aside."""
    (root / f".out.old.{dead_pid}.abc" / "d").mkdir(parents=True)
    (root / f".out.old.{dead_pid}.abc" / "d" / "old.txt").write_text("old\n")
    (root / f".out.new.{dead_pid}.xyz").mkdir()
    (root / f".out.new.{dead_pid}.xyz" / "new.txt").write_text("new\n")


def _killed_before_swap(root: Path, dead_pid: int) -> None:
    """Killed while writing the new directory: out/ intact, a half-written sibling."""
    (root / "out").mkdir()
    (root / "out" / "old.txt").write_text("old\n")
    (root / f".out.new.{dead_pid}.xyz").mkdir()


def _live_writer(root: Path, dead_pid: int) -> None:
    """Another run writing out/ right now (this process): its sibling is not touched."""
    (root / "out").mkdir()
    (root / "out" / "old.txt").write_text("old\n")
    (root / f".out.new.{os.getpid()}.live").mkdir()


SWAPS = [
    # (what was left, the siblings left after the next run, what out/ holds before it writes)
    (_killed_swap, [], ["old.txt"]),
    (_killed_before_swap, [], ["old.txt"]),
    (_live_writer, [".out.new.{me}.live"], ["old.txt"]),
]


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


@pytest.mark.parametrize("left, siblings, seen", SWAPS, ids=[s[0].__name__.strip("_") for s in SWAPS])
def test_the_next_run_recovers_an_interrupted_swap(tmp_path, left, siblings, seen):
    left(tmp_path, _dead_pid())
    found = []
    with pytest.warns(UserWarning) if left is not _live_writer else _nothing():
        with atomic_directory(tmp_path / "out", lambda d: True) as tmp:
            found = sorted(p.name for p in (tmp_path / "out").iterdir())
            (tmp / "fresh.txt").write_text("fresh\n")
    assert found == seen
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["fresh.txt"]
    assert sorted(p.name for p in tmp_path.iterdir() if p.name != "out") == \
        [s.format(me=os.getpid()) for s in siblings]


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


# ---------------------------------------------------------------- a batch item that never ends
def _block_on_fifo(item):
    marker, fifo = item
    Path(marker).write_text("started\n")
    with open(fifo):   # nobody ever writes: blocks until the batch ends it
        return "read"


STOPS = [  # (jobs, the signals sent, the signal the batch reports)
    (1, (signal.SIGTERM,), signal.SIGTERM),
    (2, (signal.SIGTERM,), signal.SIGTERM),
    (1, (signal.SIGINT, signal.SIGINT), signal.SIGINT),
    (2, (signal.SIGINT, signal.SIGINT), signal.SIGINT),
]


@pytest.mark.parametrize("jobs, signals, reported", STOPS, ids=[f"j{j}-{'+'.join(s.name for s in sig)}"
                                                                 for j, sig, _ in STOPS])
def test_a_batch_blocked_in_an_item_ends_on_sigterm_or_a_second_ctrl_c(tmp_path, jobs, signals, reported):
    items = []
    for k in range(2):
        os.mkfifo(tmp_path / f"f{k}")
        items.append((str(tmp_path / f"m{k}"), str(tmp_path / f"f{k}")))
    got = []

    def send():
        wait_for(lambda: (tmp_path / "m0").exists(), "the first item to start")
        for sig in signals:
            os.kill(os.getpid(), sig)
            time.sleep(0.2)

    sender = threading.Thread(target=send, daemon=True)
    sender.start()
    t0 = time.monotonic()
    stopped = run_batch(_block_on_fifo, items, jobs, lambda item, res: got.append(item))
    sender.join(WAIT_S)
    assert stopped == reported
    assert got == []   # the blocked items are not reported as done
    assert time.monotonic() - t0 < WAIT_S


# ----------------------------------------------------------------- the sweep harness's stop time
@pytest.mark.sim
def test_a_design_that_never_answers_ends_at_the_sweeps_stop_time(small_designs, tmp_path):
    from flann.hardware.design import open_design
    from flann.verify.runner import sweep

    d = tmp_path / "mute"
    shutil.copytree(small_designs["dir"] / "fixed", d)
    top = d / "flann_top.vhd"
    text = top.read_text()
    assert "out_valid   => out_valid," in text
    top.write_text(text.replace("out_valid   => out_valid,", "out_valid   => open,"))
    design = open_design(str(d), tmp_path / "build")
    res = sweep(design, tmp_path / "build", codes=(0, 3))   # without a stop time: never returns
    assert not res["bench"].ok
    assert res["codes"].size == 0


# --------------------------------------------------------------------- SIGTERM to flann alone
def _children(pid: int) -> set[int]:
    from flann.verify.shards import _children as kids

    return set(kids(pid))


@pytest.mark.sim
def test_sigterm_to_flann_sim_ends_its_simulators(small_designs, tmp_path):
    env = {**os.environ, "PYTHONPATH": str(REPO / "gen")}
    p = subprocess.Popen([sys.executable, "-m", "flann.cli", "sim", str(small_designs["dir"] / "fixed"),
                          "--build", str(tmp_path / "b")], env=env, stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True)
    seen: set[int] = set()
    try:
        wait_for(lambda: bool(seen.update(_children(p.pid)) or seen), "flann to start a simulator")
        os.kill(p.pid, signal.SIGTERM)
        p.wait(WAIT_S)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 143, p.stderr.read()
    wait_for(lambda: not any(Path(f"/proc/{pid}").exists() and _parent(pid) in (1, p.pid) for pid in seen),
             "the simulators to end", 10)


def _parent(pid: int) -> int:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return -1
    return int(stat[stat.rfind(")") + 2:].split()[1])


# ------------------------------------------------------------------------ GHDL missing, zero weights
def test_sim_without_ghdl_says_ghdl_is_missing(small_designs, tmp_path, monkeypatch, capsys):
    bare = tmp_path / "bin"
    bare.mkdir()
    monkeypatch.setenv("PATH", str(bare))
    rc = main(["sim", str(small_designs["dir"] / "fixed"), "--build", str(tmp_path / "b")])
    err = capsys.readouterr().err
    assert rc == 2
    assert [ln for ln in err.splitlines() if ln.startswith("error:")] == \
        ["error: ghdl not found on PATH (Debian package ghdl; `make tools` installs it)"]


def test_gen_of_a_two_input_model_with_all_zero_weights(small_designs, tmp_path, capsys):
    d = json.loads(Path(small_designs["thermal"]).read_text())
    d["weights"] = [[0.0] * len(w) for w in d["weights"]]
    d["bias"] = [0.0] * len(d["bias"])
    (tmp_path / "z.json").write_text(json.dumps(d))
    rc = main(["gen", str(tmp_path / "z.json"), "-o", str(tmp_path / "z"), "--temp-bits", "5", "--temp-lsb-c", "6",
               "--input-bits", "8"])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert rc == 0, err


# ----------------------------------------------------- the family hardware saturates, never wraps
def _extreme_accepted(fam, words: list[int], sign: int) -> list[int]:
    """The image with every weight at the largest magnitude of ``sign`` the loader accepts."""
    field = next(f for f in fam.fields if f.name == "weights")

    def image(v: int) -> list[int]:
        w = list(words)
        w[field.addr:field.addr + field.words] = [(sign * v) & 0xFFFFFFFF] * field.words
        return w

    lo, hi = 0, (1 << (field.bits - 1)) - 1
    while lo < hi:
        mid = (lo + hi + 1) // 2
        try:
            check_image(fam, image(mid))
            lo = mid
        except FlannError:
            hi = mid - 1
    return image(lo)


@pytest.mark.sim
def test_the_extreme_images_the_loader_accepts_agree_and_saturate(small_designs, tmp_path, capsys):
    """Every weight at the largest (then most negative) value the loader accepts: the HDL and the
    mapped netlist agree with the twin over every code, and the outputs saturate."""
    d = small_designs["dir"] / "family"
    fam = load_design(d)
    man = json.loads((d / "manifest.json").read_text())
    base = read_image(d / man["images"][0]["hex"])
    paths = []
    for sign, name in ((1, "max"), (-1, "min")):
        words = _extreme_accepted(fam, base, sign)
        out, sat = FlannFamilyTop(fam, words).process(np.arange(fam.spec.code_min, fam.spec.code_max + 1))
        assert sat.sum() > 0, f"{name}: the extreme image does not drive the output to saturation"
        assert out.max() == (1 << (fam.spec.out_fmt.width - 1)) - 1 or out.min() == -(1 << (fam.spec.out_fmt.width - 1))
        paths.append(tmp_path / f"{name}.hex")
        paths[-1].write_text(hex_text(words))
    # the HDL over every code with both images, one loaded over the other; the netlist loads the last
    rc = main(["sim", str(d), *(a for p in paths for a in ("--image", str(p))), "--netlist",
               "--build", str(tmp_path / "b"), "--json", str(tmp_path / "sim.json")])
    summary = json.loads((tmp_path / "sim.json").read_text())
    assert rc == 0, capsys.readouterr().err
    assert summary["mismatches"] == 0 and summary["all_passed"]
    assert summary["netlist"]["mismatches"] == 0 and summary["netlist"]["codes_tested"] > 0
    assert summary["images"] == ["max", "min"]     # both loaded, the HDL checked with each
    # and the netlist with the first image loaded
    nl = check_netlist(from_directory(d), tmp_path / "nl_max", image={"name": "max", "hex": str(paths[0])})
    assert nl.passed and nl.codes_tested == summary["netlist"]["codes_tested"]


IMAGE_CASES = [   # (datapath, the word every weight of the first memory holds, the error line)
    ("family", lambda bits: (1 << (bits - 1)) - 1, "could overflow the hardware"),
    ("family", lambda bits: (1 << 32) - (1 << (bits - 1)), "could overflow the hardware"),
    ("family", lambda bits: 0x7FFFFFFF, "does not fit the field's sint<"),
    ("family_thermal", lambda bits: (1 << (bits - 1)) - 1, "(temperature order 0)"),
    ("family_thermal", lambda bits: 0x7FFFFFFF, "does not fit the field's sint<"),
]


@pytest.mark.parametrize("datapath, word, says", IMAGE_CASES,
                         ids=[f"{c[0]}-{k}" for k, c in enumerate(IMAGE_CASES)])
def test_the_loader_refuses_an_image_the_hardware_would_wrap_with(small_designs, tmp_path, capsys,
                                                                    datapath, word, says):
    d = small_designs["dir"] / datapath
    man = json.loads((d / "manifest.json").read_text())
    field = next(f for f in man["family"]["memory"]["fields"] if f["name"] == "weights")
    words = read_image(d / man["images"][0]["hex"])
    words[field["addr"]:field["addr"] + field["words"]] = [word(field["bits"])] * field["words"]
    (tmp_path / "big.hex").write_text(hex_text(words))
    rc = main(["sim", str(d), "--image", str(tmp_path / "big.hex"), "--build", str(tmp_path / "b")])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("error:")]
    assert rc == 2 and len(err) == 1 and says in err[0], err
    assert not (tmp_path / "b").exists() or not any((tmp_path / "b").iterdir())
