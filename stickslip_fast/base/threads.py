"""Independent integrations run side by side on threads.

The compiled kernels release the GIL (``nogil``), so integrations that do not depend on
each other (the segments of multiple shooting; the Jacobian evaluations of a
two-parameter curve's step) can run at once on Python threads. Every one of them is the
same sequential computation whichever thread runs it, so the results do not depend on
the thread count. The number of threads is Numba's (``numba.get_num_threads()``:
``NUMBA_NUM_THREADS`` or all cores, ``numba.set_num_threads`` to change it), as for
sweeps. The pools are kept between calls and never used in a forked child (whose copy
holds no threads); a pool's worker never waits on the pool itself, so work nested in
work runs in its own thread, one call after the other.
"""

from __future__ import annotations

import contextvars
import os
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor, wait
from typing import Any

import numba
import numpy as np

__all__ = [
    "shared_pool",
    "in_worker",
    "numba_threads",
    "thread_count",
    "submit",
    "finish",
    "run_concurrently",
]

_PREFIX = "stickslip-worker"
_POOLS: dict[tuple[int, int], ThreadPoolExecutor] = {}
_LOCK = threading.Lock()


def shared_pool(workers: int) -> ThreadPoolExecutor:
    """The kept pool of ``workers`` threads of this process."""
    key = (os.getpid(), workers)
    with _LOCK:
        pool = _POOLS.get(key)
        if pool is None:
            pool = _POOLS[key] = ThreadPoolExecutor(workers, thread_name_prefix=_PREFIX)
    return pool


def in_worker() -> bool:
    """Whether the calling thread is one of the pools' workers."""
    return threading.current_thread().name.startswith(_PREFIX)


def numba_threads() -> int:
    """Numba's thread count in the calling thread (the pools' size; tests set it here
    rather than patching ``numba.get_num_threads``, which the kernels' callers use too)."""
    return numba.get_num_threads()


def thread_count(tasks: int) -> int:
    """Threads for ``tasks`` independent tasks: Numba's thread count, at most one per
    task, and 1 inside a pool's worker (which must not wait on the pool)."""
    return 1 if in_worker() else max(1, min(int(tasks), numba_threads()))


def submit(pool: ThreadPoolExecutor, fn: Callable[..., Any], *args: Any) -> Future:
    """``pool.submit`` in a copy of the caller's context (a checkpoint's journal in force
    reaches the worker)."""
    return pool.submit(contextvars.copy_context().run, fn, *args)


def finish(futures: Sequence[Future]) -> None:
    """Cancel the futures not started and wait for the others (after an error or Ctrl-C
    in the caller: nothing runs on behind its back)."""
    for f in futures:
        f.cancel()
    wait(futures)


def run_concurrently(
    calls: Sequence[Callable[[], Any]], abort: np.ndarray | None = None
) -> list[Any]:
    """``[call() for call in calls]``, the calls shared out between the calling thread and
    :func:`thread_count` - 1 workers (each takes the next call not yet taken).

    The calling thread runs its share itself, so a compiled kernel it runs stays
    interruptible by Ctrl-C. No call not yet taken is started after an error or Ctrl-C
    in the caller; a call running in a worker finishes first, unless the calls share an
    ``abort`` flag (:func:`~stickslip_fast.base.interrupt.new_abort_flag`): that is then
    set, so their kernels stop within a step, also where Ctrl-C landed in the caller's
    Python code between two kernels (where no kernel's watcher sets it) or while it
    waits for the workers. The first error of any call is raised after all have stopped.
    """
    threads = thread_count(len(calls))
    if threads == 1:
        return [call() for call in calls]
    results: list[Any] = [None] * len(calls)
    order = iter(range(len(calls)))
    stop = threading.Event()
    lock = threading.Lock()

    def share() -> None:
        while not stop.is_set():
            with lock:
                i = next(order, None)
            if i is None:
                return
            try:
                results[i] = calls[i]()
            except BaseException:
                stop.set()  # not the flag: a worker's error leaves the others' calls be
                raise

    futures = [submit(shared_pool(threads - 1), share) for _ in range(threads - 1)]
    try:
        share()
        finish(futures)  # a worker still busy elsewhere never started its share: cancelled
    except BaseException:  # Ctrl-C or an error in the caller's share: the workers stop
        stop.set()
        if abort is not None:
            abort[0] = 1
        finish(futures)
        raise
    for f in futures:
        if not f.cancelled():
            f.result()  # a worker's error
    return results
