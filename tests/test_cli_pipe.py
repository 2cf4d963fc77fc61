"""A command whose reader has gone (``flann ... | head``) exits quietly, without a traceback."""

import os
import subprocess
import sys


def test_closed_pipe_exits_quietly(default_model_json, tmp_path):
    r, w = os.pipe()
    os.close(r)  # the reader is gone before the first write
    try:
        p = subprocess.run([sys.executable, "-m", "flann.cli", "gen", str(default_model_json), "-o",
                            str(tmp_path / "d"), "--json"], stdout=w, stderr=subprocess.PIPE, text=True,
                           timeout=120)
    finally:
        os.close(w)
    assert p.returncode == 141
    assert "Traceback" not in p.stderr and "BrokenPipe" not in p.stderr, p.stderr


def test_train_writes_its_model_even_when_stderr_is_gone(table1_csv, tmp_path):
    # `flann train ... 2>&1 | head -1`: the summary's reader leaves; the model is the product
    r, w = os.pipe()
    os.close(r)
    out = tmp_path / "m.json"
    try:
        p = subprocess.run([sys.executable, "-m", "flann.cli", "train", str(table1_csv), "-o", str(out)],
                           stdout=subprocess.DEVNULL, stderr=w, timeout=120)
    finally:
        os.close(w)
    assert out.is_file(), p.returncode
