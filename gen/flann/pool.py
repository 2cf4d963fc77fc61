"""A batch over a process pool that stops promptly on Ctrl-C and keeps what was done.

Only ``jobs`` items are ever in flight (no queue of submitted work that would run on after
an interrupt); the workers ignore SIGINT (the terminal sends it to the whole process
group), so the parent alone decides: on Ctrl-C it submits nothing more, waits for the items
already running (each writes its output whole or not at all), and returns what finished
with ``interrupted`` set, so the caller can still write its summary before exiting 130.
"""

from __future__ import annotations

import os
import signal
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Callable, Iterable


def _worker_init() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def run_batch(fn: Callable, items: Iterable, jobs: int, on_result: Callable[[object, object], None]) -> bool:
    """Call ``fn(item)`` for every item (in this process when ``jobs == 1``) and
    ``on_result(item, result)`` as each finishes; True if Ctrl-C stopped the batch early."""
    items = list(items)
    if jobs <= 1 or len(items) <= 1:
        try:
            for item in items:
                on_result(item, fn(item))
        except KeyboardInterrupt:
            return True
        return False
    interrupted = False
    pending = iter(items)
    end = object()
    with ProcessPoolExecutor(max_workers=min(jobs, len(items)), initializer=_worker_init) as pool:
        running: dict = {}

        def fill() -> None:
            while not interrupted and len(running) < jobs:
                item = next(pending, end)
                if item is end:
                    return
                running[pool.submit(fn, item)] = item

        fill()
        while running:
            try:
                done, _ = wait(running, return_when=FIRST_COMPLETED)
            except KeyboardInterrupt:
                interrupted = True   # finish what is running (whole outputs), start nothing more
                continue
            for fut in done:
                on_result(running.pop(fut), fut.result())
            fill()
    return interrupted


__all__ = ["run_batch"]
