"""Ctrl-C for compiled work: run a kernel in a worker thread, abort it through a flag.

A compiled call holds the main thread until it returns, so Python's SIGINT
handler cannot run and Ctrl-C would wait for the whole computation (or, inside
Numba's parallel region, surface as an opaque ``SystemError``). Every kernel
therefore takes an ``abort`` flag (int64[1]) that its driver polls once a step.
:func:`call_interruptible` runs the kernel (compiled with ``nogil=True``) in a
worker thread while the main thread waits in short, interruptible joins; on
Ctrl-C it sets the flag, waits for the kernel to stop (within one step of every
trajectory in flight: well under a second) and re-raises ``KeyboardInterrupt``.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import numba
import numpy as np

__all__ = ["new_abort_flag", "call_interruptible"]


def new_abort_flag() -> np.ndarray:
    """A fresh, unset abort flag for one kernel call."""
    return np.zeros(1, dtype=np.int64)


def call_interruptible(kernel: Callable[..., Any], *args: Any, abort: np.ndarray) -> Any:
    """Call ``kernel(*args, abort)`` so that Ctrl-C stops it within about a second.

    Parameters
    ----------
    kernel : callable
        A compiled kernel whose last argument is the abort flag.
    *args
        Its other arguments.
    abort : ndarray of int64, shape (1,)
        The flag; set to 1 on Ctrl-C.

    Returns
    -------
    Whatever the kernel returns.

    Raises
    ------
    KeyboardInterrupt
        After the kernel has stopped, when Ctrl-C arrived while it ran.
    """
    if threading.current_thread() is not threading.main_thread():
        # signals only reach the main thread: nothing to wait for here
        return kernel(*args, abort)
    box: dict[str, Any] = {}
    threads = numba.get_num_threads()  # thread-local: hand the caller's setting on

    def target() -> None:
        try:
            numba.set_num_threads(threads)
            box["value"] = kernel(*args, abort)
        except BaseException as exc:  # handed to the caller below
            box["error"] = exc

    worker = threading.Thread(target=target, name="stickslip-kernel", daemon=True)
    worker.start()
    try:
        while worker.is_alive():
            worker.join(0.1)
    except KeyboardInterrupt:
        abort[0] = 1
        worker.join()
        raise
    if "error" in box:
        raise box["error"]
    return box["value"]
