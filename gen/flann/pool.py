"""A batch over a process pool that stops promptly on Ctrl-C and keeps what was done.

Only ``jobs`` items are ever in flight (no queue of submitted work that would run on after
an interrupt).  While the batch runs, Ctrl-C and SIGTERM only set a flag (the workers ignore
both: a terminal sends SIGINT, and ``timeout`` or a job scheduler SIGTERM, to the whole process
group), so no KeyboardInterrupt can land in the middle of recording a result: the parent
submits nothing more, lets the items already running finish (each writes its output whole or
not at all), and returns the signal that stopped it, so the caller can still write its
summary before exiting 130 (143: SIGTERM).  SIGTERM, or a second Ctrl-C, does not wait: the
items in flight are abandoned (their workers killed; in this process the item is left by an
exception), so an item that never finishes (a read from a FIFO nobody writes) cannot hold the
batch.  A worker that dies all the same (SIGKILL, the system out of memory) loses only the
items it had in flight: each is reported through ``on_lost`` and the batch goes on in a new pool.
"""

from __future__ import annotations

import os
import signal
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Callable, Iterable

POLL_S = 0.1   # how often the parent looks at the Ctrl-C flag while workers run
LOST = ("its worker process died before it finished (killed, or the system ran out of "
        "memory); run it again")


class _StopNow(BaseException):
    """Raised in this process's item when the batch must end without waiting for it."""


def _now(stop: list) -> bool:
    """End the batch without waiting for the items in flight: SIGTERM, or a second signal."""
    return signal.SIGTERM in stop or len(stop) > 1


def _worker_init() -> None:
    # the parent decides when the batch stops; a worker finishes the item it holds
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def run_batch(fn: Callable, items: Iterable, jobs: int, on_result: Callable[[object, object], None],
              on_lost: Callable[[object, str], None] | None = None) -> int:
    """Call ``fn(item)`` for every item (in this process when ``jobs == 1``) and
    ``on_result(item, result)`` as each finishes, ``on_lost(item, why)`` for an item whose
    worker died; the signal that stopped the batch early (SIGINT, SIGTERM), else 0."""
    items = list(items)
    stop = []
    busy = []   # non-empty while this process runs an item (jobs == 1)

    def on_signal(signum, frame) -> None:
        stop.append(signum)
        if busy and _now(stop):
            raise _StopNow

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
                busy.append(item)
                try:
                    res = fn(item)
                except _StopNow:
                    break
                finally:
                    busy.clear()
                on_result(item, res)
        else:
            _pool(fn, items, jobs, on_result, on_lost, stop)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return stop[0] if stop else 0


def _pool(fn, items, jobs, on_result, on_lost, stop) -> None:
    pending = iter(items)
    end = object()
    more = True
    while more and not stop:
        more = _one_pool(fn, pending, end, min(jobs, len(items)), on_result, on_lost, stop)


def _one_pool(fn, pending, end, jobs, on_result, on_lost, stop) -> bool:
    """Run items from ``pending`` until they end or a signal; True when the pool broke first."""
    running: dict = {}
    with ProcessPoolExecutor(max_workers=jobs, initializer=_worker_init) as pool:
        def fill() -> None:
            while not stop and len(running) < jobs:
                item = next(pending, end)
                if item is end:
                    return
                running[pool.submit(fn, item)] = item

        try:
            fill()
            while running:
                if _now(stop):   # the items in flight are abandoned, their workers ended
                    _end_workers(pool)
                    return False
                done, _ = wait(running, timeout=POLL_S, return_when=FIRST_COMPLETED)
                for fut in done:
                    res = fut.result()   # a broken pool raises here, the item still in running
                    on_result(running.pop(fut), res)
                fill()
        except BrokenProcessPool:
            for item in running.values():
                if on_lost is None:
                    raise
                on_lost(item, LOST)
            return True
    return False


def _end_workers(pool: ProcessPoolExecutor) -> None:
    procs = list((getattr(pool, "_processes", None) or {}).values())
    for proc in procs:
        proc.kill()
    for proc in procs:
        proc.join()
    pool.shutdown(wait=False, cancel_futures=True)


__all__ = ["run_batch"]
