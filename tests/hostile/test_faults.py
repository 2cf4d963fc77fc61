"""Faults: a full disk, a write error in the middle of a design directory and of a
calibrate batch, Ctrl-C during start-up and during a calibrate pool."""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from flann.cli import main

from test_hostile_inputs import snapshot


def as_on_a_terminal() -> None:
    """The child takes Ctrl-C as a program started from a terminal does, even when this suite
    runs as a background job of a script (which starts its children with SIGINT ignored)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)

FLANN = Path(sys.executable).with_name("flann")
FAM = ("--diagnosis-points", "40", "-j", "1")


@pytest.fixture
def small_disk(tmp_path):
    """A 200 kB tmpfs when root; otherwise skip (the patched-writer tests below cover it)."""
    mnt = tmp_path / "disk"
    mnt.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(mnt)],
                                            capture_output=True).returncode != 0:
        pytest.skip("a tmpfs needs root; the patched-writer tests cover a failing disk")
    yield mnt
    subprocess.run(["umount", str(mnt)], check=True)


def _one_error(err: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.startswith("error:")]
    assert "Traceback" not in err and len(lines) == 1, err
    return lines[0]


@pytest.mark.parametrize("argv", [
    ("gen", "{w}/m.json", "-o", "{d}/design", "--input-bits", "10"),
    ("gen", "--family", "{w}/s0.csv", "{w}/s1.csv", "-o", "{d}/fam", "--input-bits", "10"),
    ("ise", "{w}/design", "-o", "{d}/ise", "--no-timing-check"),   # the writes, not the synthesis
    ("calibrate", "{w}/s0.csv", "-o", "{d}/out", "--design", "{w}/fam", *FAM),
], ids=["gen", "gen-family", "ise", "calibrate"])
def test_disk_full_is_one_line_and_leaves_nothing_half(argv, world, small_disk, capsys):
    (small_disk / "filler").write_bytes(b"\0" * (200 * 1024 - 8192))   # leave ~8 kB
    before = snapshot(small_disk)
    rc = main([a.format(w=world, d=small_disk) for a in argv])
    line = _one_error(capsys.readouterr().err)
    assert rc == 2 and "No space left" in line, line
    after = snapshot(small_disk)
    # nothing but whole outputs: no temporary directory or file is left behind
    assert not [k for k in after if k not in before and Path(k).name.startswith(".")], after


def test_write_error_in_the_middle_of_a_design_keeps_the_old_design(world, capsys, monkeypatch):
    """The third file of a design fails to write: the old design stays whole and unchanged."""
    before = snapshot(world / "design")
    real = Path.write_text
    calls = {"n": 0}

    def failing(self, *a, **k):
        calls["n"] += 1
        if calls["n"] == 3:
            raise OSError(28, "No space left on device")
        return real(self, *a, **k)

    monkeypatch.setattr(Path, "write_text", failing)
    real_bytes = Path.write_bytes
    monkeypatch.setattr(Path, "write_bytes", lambda self, *a, **k: failing(self, "") if calls["n"] == 2
                        else real_bytes(self, *a, **k))
    # a different design (other input width) into the existing directory
    rc = main(["gen", str(world / "m.json"), "-o", str(world / "design"), "--input-bits", "11"])
    line = _one_error(capsys.readouterr().err)
    assert rc == 2 and calls["n"] >= 3, line
    assert snapshot(world / "design") == before
    assert not [p for p in world.iterdir() if p.name.startswith(".")]


def test_write_error_in_a_calibrate_batch_fails_that_sensor_and_goes_on(world, capsys, monkeypatch):
    real = Path.write_text

    def failing(self, *a, **k):
        if self.parent.name.startswith(".s0.new.") and self.name == "weights.mem":
            raise OSError(5, "Input/output error")   # the disk fails under this sensor only
        return real(self, *a, **k)

    monkeypatch.setattr(Path, "write_text", failing)
    rc = main(["calibrate", str(world / "s0.csv"), str(world / "s1.csv"), "-o", str(world / "out"),
               "--design", str(world / "fam"), *FAM])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err
    assert [ln for ln in err.splitlines() if ln.startswith("error:")] == \
        [ln for ln in err.splitlines() if ln.startswith("error: s0:")], err
    assert (world / "out" / "s1" / "certificate.html").is_file()
    # the failed sensor keeps only the certificate that says why: no weights a loader could pick up
    assert sorted(p.name for p in (world / "out" / "s0").iterdir()) == ["certificate.html"]
    summary = (world / "out" / "summary.csv").read_text()
    assert "s0,failed" in summary and "s1,ok" in summary, summary


@pytest.mark.parametrize("jobs, sig, group", [(1, signal.SIGINT, True), (2, signal.SIGINT, True),
                                              (1, signal.SIGTERM, False), (2, signal.SIGTERM, True)])
def test_ctrl_c_stops_a_calibrate_pool_promptly_and_writes_the_summary(world, jobs, sig, group):
    """Ctrl-C (the terminal signals the whole process group) and SIGTERM (to flann's process
    alone, or to its group as ``timeout`` and job schedulers send it) stop the batch the same
    way: the summary is written, with the sensors not calibrated as interrupted rows, and an
    earlier run's folders of those sensors are gone, so no old certificate or summary is left
    beside this run's."""
    import time

    recs = []
    for k in range(12):
        shutil.copy(world / ("s0.csv" if k % 2 else "s1.csv"), world / f"r{k:02d}.csv")
        recs.append(f"r{k:02d}.csv")
        old = world / "out" / f"r{k:02d}"   # an earlier run's folder (a sensor folder is replaced whole)
        old.mkdir(parents=True)
        (old / "certificate.html").write_text("PASS (an earlier run)")
        (old / "earlier_run").write_text("")

    def written():
        return [d for d in (world / "out").glob("*")
                if d.is_dir() and not d.name.startswith(".") and not (d / "earlier_run").exists()]

    p = subprocess.Popen([str(FLANN), "calibrate", *recs, "-o", "out", "--design", "fam", "-j", str(jobs),
                          "--diagnosis-points", "40"], stderr=subprocess.PIPE, stdout=subprocess.PIPE,
                         text=True, start_new_session=True, cwd=world, preexec_fn=as_on_a_terminal)
    # the state we interrupt in: the first sensor's folder of this run is in place
    deadline = time.monotonic() + 120
    while not written():
        assert p.poll() is None and time.monotonic() < deadline, p.communicate()
        time.sleep(0.02)
    if group:
        os.killpg(p.pid, sig)   # what Ctrl-C on a terminal and `timeout` do: the whole process group
    else:
        os.kill(p.pid, sig)
    at_interrupt = len(written())
    out, err = p.communicate(timeout=60)
    assert p.returncode == 128 + sig, err
    assert "Traceback" not in err
    assert err.strip().splitlines() == ["error: interrupted" if sig == signal.SIGINT else "error: terminated"], err
    summary = (world / "out" / "summary.csv").read_text().splitlines()
    done = [ln for ln in summary[1:] if ",ok," in ln]
    stopped = [ln for ln in summary[1:] if ",interrupted," in ln]
    assert len(summary) == 13 and len(done) + len(stopped) == 12, summary
    # prompt: after the interrupt only the sensors then running (one per worker) finish
    assert len(done) <= at_interrupt + jobs, (at_interrupt, summary)
    dirs = sorted(p.name for p in (world / "out").iterdir() if p.is_dir())
    assert dirs == sorted(ln.split(",")[0] for ln in done)
    assert not [p for p in (world / "out").iterdir() if p.name.startswith(".")]


@pytest.mark.parametrize("delay", [0.02, 0.05, 0.1, 0.15, 0.2, 0.3])
def test_ctrl_c_during_start_up_is_one_line(delay, tmp_path):
    """Ctrl-C while the command's modules import: exit 130 and one line, never a traceback.
    The recording is a FIFO nobody writes, so the command can never finish before the
    interrupt: at any instant it is either starting up or waiting for its input."""
    import time

    os.mkfifo(tmp_path / "rec.csv")
    p = subprocess.Popen([str(FLANN), "train", str(tmp_path / "rec.csv"), "-o", str(tmp_path / "m.json")],
                         stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True, start_new_session=True,
                         preexec_fn=as_on_a_terminal)
    time.sleep(delay)   # the start-up has no state to wait for: several instants are tried
    os.killpg(p.pid, signal.SIGINT)
    out, err = p.communicate(timeout=60)
    assert not (tmp_path / "m.json").exists()
    if err.startswith("Fatal Python error: init_import_site"):
        # the interrupt reached the interpreter while it imported its own site module, before
        # the first line of flann or of the console script ran: nothing of ours to catch it
        return
    frames = re.findall(r'File "([^"]+)"', err)
    if (frames and frames[0] == str(FLANN) and all(f == str(FLANN) or f.startswith("<frozen ") for f in frames)
            and err.rstrip().endswith("KeyboardInterrupt")):
        # the same before the package's first line: the console script pip wrote was still
        # importing it (its frame, then only the interpreter's frozen import machinery: no
        # file of ours), and no code of ours had run to catch it
        return
    assert "Traceback" not in err, err
    if p.returncode == -signal.SIGINT:   # before Python installed its handler: killed silently
        assert err == ""
    else:
        assert p.returncode == 130 and err.strip().splitlines() == ["error: interrupted"], (p.returncode, err)
    assert not (tmp_path / "m.json").exists()


def test_ctrl_c_in_imports_is_caught_by_the_entry_point(monkeypatch, capsys):
    """Deterministic form of the start-up race: KeyboardInterrupt raised while importing."""
    from flann import cli

    def interrupted(name):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_load", interrupted)
    try:
        rc = cli.main(["train", "x.csv", "-o", "m.json"])
    except KeyboardInterrupt:
        pytest.fail("KeyboardInterrupt escaped flann.cli.main")
    assert rc == 130
    assert capsys.readouterr().err == "error: interrupted\n"


def test_an_ignored_ctrl_c_stays_ignored(monkeypatch):
    """A background job of a script runs with SIGINT ignored: flann keeps it so."""
    from flann import cli

    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        seen = []
        monkeypatch.setattr(cli, "_main", lambda argv: seen.append(signal.getsignal(signal.SIGINT)) or 0)
        assert cli.main([]) == 0
        assert seen == [signal.SIG_IGN] and signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, previous)


SWALLOWED = """
import os, sys
import flann.cli

class LockCallback:   # a KeyboardInterrupt raised where it cannot propagate (a weakref's
    def __del__(self):   # callback, a __del__): Python only reports it as unraisable
        raise KeyboardInterrupt

LockCallback()
sys.exit(flann.cli.main(["train", sys.argv[1], "-o", sys.argv[2]]))
"""


def test_ctrl_c_swallowed_by_a_callback_is_one_line(tmp_path):
    """A Ctrl-C that Python could not raise (it arrived inside a callback) still stops the
    command before it waits for input: one line, exit 130, no traceback. The recording is a
    FIFO nobody writes, so a lost interrupt shows as a command that never ends."""
    os.mkfifo(tmp_path / "rec.csv")
    p = subprocess.run([sys.executable, "-c", SWALLOWED, str(tmp_path / "rec.csv"), str(tmp_path / "m.json")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 130, (p.returncode, p.stderr)
    assert p.stderr.strip().splitlines() == ["error: interrupted"], p.stderr
    assert not (tmp_path / "m.json").exists()


def test_sigterm_is_one_line_and_leaves_nothing(tmp_path):
    """SIGTERM (timeout, a scheduler) killed the process where it stood: temporary directories
    stayed behind.  It now unwinds as Ctrl-C does: one line, exit 143, no output file, no
    temporary directory.  The recording is a FIFO: opening it for writing returns once flann
    has opened it, i.e. once the command is running."""
    fifo = tmp_path / "rec.csv"
    os.mkfifo(fifo)
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    p = subprocess.Popen([str(FLANN), "train", str(fifo), "-o", str(tmp_path / "m.json")],
                         stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                         env={**os.environ, "TMPDIR": str(tmp)})
    with open(fifo, "w") as fh:      # blocks until flann reads: the command is under way
        fh.write("displacement_mm,voltage_v\n")
        fh.flush()
        p.send_signal(signal.SIGTERM)
    # the writer closed: a signal that landed before flann's read() began (the read then blocks
    # with the handler pending) is handled when the read returns, instead of waiting forever
    out, err = p.communicate(timeout=60)
    assert p.returncode == 128 + signal.SIGTERM, (p.returncode, err)
    assert err.strip().splitlines() == ["error: terminated"], err
    assert not (tmp_path / "m.json").exists() and list(tmp.iterdir()) == []


def _square_or_die(item):
    if item == 3:
        os.kill(os.getpid(), signal.SIGKILL)   # the system's out-of-memory killer, say
    return item * item


def test_a_worker_that_dies_loses_only_its_items_and_the_batch_goes_on():
    from flann.pool import run_batch

    done, lost = {}, {}
    stopped = run_batch(_square_or_die, range(8), 2, done.__setitem__, lost.__setitem__)
    assert stopped == 0
    assert 3 in lost and "worker process died" in lost[3]
    # every item is accounted for once: the ones in flight with 3 are lost, the rest done
    assert sorted([*done, *lost]) == list(range(8)) and not set(done) & set(lost)
    assert all(done[i] == i * i for i in done) and len(lost) <= 2
