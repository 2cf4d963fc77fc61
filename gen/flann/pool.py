"""A batch over a process pool that stops promptly on Ctrl-C and keeps what was done.

Only ``jobs`` items are ever in flight (no queue of submitted work that would run on after
an interrupt).  While the batch runs, Ctrl-C and SIGTERM only set a flag (the workers ignore
SIGINT: the terminal sends it to the whole process group), so no KeyboardInterrupt can land in
the middle of recording a result: the parent submits nothing more, lets the items already
running finish (each writes its output whole or not at all), and returns the signal that
stopped it, so the caller can still write its summary before exiting 130 (143: SIGTERM).
"""

from __future__ import annotations

import os
import signal
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Callable, Iterable

POLL_S = 0.1   # how often the parent looks at the Ctrl-C flag while workers run


def _worker_init() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # a forked worker inherits flann's SIGTERM handler; the parent unwinds the batch, a worker
    # told to stop just stops
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def run_batch(fn: Callable, items: Iterable, jobs: int, on_result: Callable[[object, object], None]) -> int:
    """Call ``fn(item)`` for every item (in this process when ``jobs == 1``) and
    ``on_result(item, result)`` as each finishes; the signal that stopped the batch early
    (SIGINT, SIGTERM), else 0."""
    items = list(items)
    stop = []

    def on_signal(signum, frame) -> None:
        stop.append(signum)

    previous = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            previous[sig] = signal.signal(sig, on_signal)
        except ValueError:   # not the main thread: the signals keep their meaning
            break
    try:
        if jobs <= 1 or len(items) <= 1:
            for item in items:
                if stop:
                    break
                on_result(item, fn(item))
        else:
            _pool(fn, items, jobs, on_result, stop)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return stop[0] if stop else 0


def _pool(fn, items, jobs, on_result, stop) -> None:
    pending = iter(items)
    end = object()
    running: dict = {}
    with ProcessPoolExecutor(max_workers=min(jobs, len(items)), initializer=_worker_init) as pool:
        def fill() -> None:
            while not stop and len(running) < jobs:
                item = next(pending, end)
                if item is end:
                    return
                running[pool.submit(fn, item)] = item

        fill()
        while running:
            done, _ = wait(running, timeout=POLL_S, return_when=FIRST_COMPLETED)
            for fut in done:
                on_result(running.pop(fut), fut.result())
            fill()


__all__ = ["run_batch"]
