"""Ctrl-C for compiled work: abort a running kernel through a flag.

A compiled call holds the main thread until it returns, so Python's SIGINT
handler cannot run and Ctrl-C would wait for the whole computation (or, inside
Numba's parallel region, surface as an opaque ``SystemError``). Every kernel
therefore takes an ``abort`` flag (int64[1]) that its driver polls once a step.
:func:`call_interruptible` arranges for Ctrl-C to set the flag, then re-raises
``KeyboardInterrupt`` once the kernel has stopped (within one step of every
trajectory in flight: well under a second). Kernels are compiled ``nogil=True``.

Two ways, the first whenever it applies:

- **In the calling thread.** Python's own C-level signal handler writes the
  signal's number to the *wakeup fd* (:func:`signal.set_wakeup_fd`) before any
  Python code can run. During the call that fd is one end of a socket pair whose
  other end a watcher thread reads (it sleeps in ``recv`` between calls); on
  SIGINT it sets the flag. The kernel then returns, and Python's default handler
  raises ``KeyboardInterrupt`` at once. This applies in the main thread when
  SIGINT has Python's default handler and no one else holds the wakeup fd (an
  asyncio loop with signal handlers does). It costs two system calls a call.
- **In a worker thread** otherwise (the first way's conditions unmet): the
  main thread waits in short, interruptible joins and sets the flag itself when
  its handler raises. Starting the thread, and the kernel running on a core whose
  caches the caller had warmed, cost ~0.1-0.25 ms a call (about 5 % of a
  3 ms ``simulate``; docs/performance.md, "Ctrl-C without a worker thread").
"""

from __future__ import annotations

import _thread
import contextlib
import os
import signal
import socket
import sys
import threading
from collections.abc import Callable, Iterator
from typing import Any

import numba
import numpy as np

__all__ = ["new_abort_flag", "call_interruptible", "lost_interrupts_raised"]


try:  # the C function: signal.getsignal's conversion to an enum costs ~2 us a call
    from _signal import getsignal as _getsignal
except ImportError:  # pragma: no cover - another Python implementation
    _getsignal = signal.getsignal


def new_abort_flag() -> np.ndarray:
    """A fresh, unset abort flag for one kernel call."""
    return np.zeros(1, dtype=np.int64)


class _SigintWatcher:
    """A socket pair for the wakeup fd and a daemon thread that turns SIGINT into a flag."""

    def __init__(self) -> None:
        self.pid = os.getpid()
        self.reader, self.writer = socket.socketpair()
        self.writer.setblocking(False)  # set_wakeup_fd requires it
        self.armed: np.ndarray | None = None  # the flag of the call in progress
        thread = threading.Thread(target=self._watch, name="stickslip-sigint", daemon=True)
        thread.start()

    def _watch(self) -> None:
        while True:
            try:
                data = self.reader.recv(64)
            except OSError:
                return
            if not data:
                return
            flag = self.armed
            if int(signal.SIGINT) in data and flag is not None:
                flag[0] = 1


_watcher: _SigintWatcher | None = None


def _sigint_watcher() -> _SigintWatcher:
    """This process's watcher (a forked child builds its own: threads do not survive a fork)."""
    global _watcher
    if _watcher is None or _watcher.pid != os.getpid():
        if _watcher is not None:
            _watcher.reader.close()
            _watcher.writer.close()
        _watcher = _SigintWatcher()
    return _watcher


def call_interruptible(kernel: Callable[..., Any], *args: Any, abort: np.ndarray) -> Any:
    """Call ``kernel(*args, abort)`` so that Ctrl-C stops it within about a second.

    Parameters
    ----------
    kernel : callable
        A compiled kernel whose last argument is the abort flag, or a Python
        function that runs such kernels (and waits for them before it returns).
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
        After the kernel has stopped, when Ctrl-C arrived while it ran: also when the
        ``KeyboardInterrupt`` that Python's handler raised was lost on the way (raised in
        a finaliser during a cold compile, which Python only prints), and in place of
        an error the interrupted call raised (chained to it as the cause). A result cut
        short by the flag is never returned as the call's answer.
    """
    if threading.current_thread() is not threading.main_thread():
        # signals only reach the main thread: nothing to wait for here
        return _checked(kernel(*args, abort), abort)
    if _getsignal(signal.SIGINT) is signal.default_int_handler:
        watcher = _sigint_watcher()
        fd = watcher.writer.fileno()
        previous = signal.set_wakeup_fd(fd, warn_on_full_buffer=False)
        if previous in (-1, fd):
            # fd already ours: a call nested in another one (restored after it), or
            # one left behind by an interrupted call (armed is None then)
            outer = watcher.armed
            watcher.armed = abort
            try:
                return _checked(_call_here(kernel, args, abort), abort)
            finally:
                watcher.armed = outer
                if outer is None:
                    signal.set_wakeup_fd(-1)
        signal.set_wakeup_fd(previous)  # someone else's (an asyncio loop): keep it
    return _checked(_call_in_worker(kernel, args, abort), abort)


def _checked(out: Any, abort: np.ndarray) -> Any:
    """``out``, unless the flag says the call was cut short by Ctrl-C."""
    if abort[0]:
        # SIGINT arrived, but no KeyboardInterrupt reached this frame: Python's handler
        # raised it inside a finaliser (``__del__``) or a callback during the call,
        # where Python prints it and goes on (seen during cold compiles), and the
        # kernel then stopped on the flag with its runs marked "interrupted"
        raise KeyboardInterrupt
    return out


def _call_here(kernel: Callable[..., Any], args: tuple, abort: np.ndarray) -> Any:
    """``kernel(*args, abort)`` in the calling (main) thread, Ctrl-C raised as itself.

    SIGINT's handler runs at the first Python code after the kernel stops; where that is
    Numba boxing the kernel's result (its arrays' dtypes come from a Python callback,
    ``_numba_unpickle``), the dispatcher reports the KeyboardInterrupt as the cause of a
    SystemError ("returned a result with an exception set"). It is re-raised as the
    KeyboardInterrupt it is. Any other error of a call during which Ctrl-C arrived is
    raised as a KeyboardInterrupt too, with the error as its cause: SIGINT landing
    inside Numba's compiler leaves it half done, and the error that follows (seen: a
    ``RuntimeError: no compiled object yet for <Library ...>``) is the interruption's
    consequence, not the call's answer.
    """
    try:
        return kernel(*args, abort)
    except Exception as exc:
        cause = exc.__cause__ if isinstance(exc, SystemError) else None
        while isinstance(cause, SystemError):  # one per Python frame between them
            cause = cause.__cause__
        if isinstance(cause, KeyboardInterrupt):
            raise KeyboardInterrupt from None
        if abort[0]:
            raise KeyboardInterrupt from exc
        raise


def _call_in_worker(kernel: Callable[..., Any], args: tuple, abort: np.ndarray) -> Any:
    """Run the kernel in a worker thread; the main thread waits and sets the flag on Ctrl-C."""
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


#: How long after a lost Ctrl-C :func:`lost_interrupts_raised` signals the main thread
#: again: time for the hook that arms it to return (a signal that lands inside the hook
#: is caught there and sent once more), and short enough that a command stops at once
#: (20 ms let the CLI print its result first).
_AGAIN_AFTER = 0.001


@contextlib.contextmanager
def lost_interrupts_raised() -> Iterator[None]:
    """Within: a Ctrl-C that Python reports as ignored is raised again.

    SIGINT's ``KeyboardInterrupt`` can be raised inside a finaliser (``__del__``;
    Numba's compiler runs many), where Python prints "Exception ignored" and goes on.
    Inside a kernel call the watcher has set the flag all the same
    (:func:`call_interruptible`), but between calls nothing was armed and the command
    went on as if no key had been pressed. Here Python's hook for such exceptions
    (:data:`sys.unraisablehook`) still reports it, and then has another thread signal
    the main thread again a millisecond later (:func:`_thread.interrupt_main`, which
    also writes the wakeup fd, so a kernel in flight stops on its flag). Signalled
    from the hook itself, the interrupt would be raised inside the report and lost
    again; one that lands in a finaliser once more is caught here once more. On the
    way out the signals still due are waited for, so they land inside the block. The
    command line uses it around each command; the hook is the process's, so a
    library call does not install it.
    """
    previous = sys.unraisablehook
    due: list[threading.Timer] = []

    def again() -> None:
        while True:
            timer = threading.Timer(_AGAIN_AFTER, _thread.interrupt_main)
            timer.daemon = True
            try:
                timer.start()  # waits until the thread runs
            except KeyboardInterrupt:
                # it fired before start() returned, inside this hook, where it would be
                # lost again (seen on a loaded 2-core VM, 3 of 8 runs): once more
                if timer.ident is not None:  # started: joined on the way out
                    due.append(timer)
                continue
            due.append(timer)
            return

    def hook(unraisable: Any) -> None:
        lost = isinstance(unraisable.exc_value, KeyboardInterrupt)
        try:
            previous(unraisable)
        except KeyboardInterrupt:
            lost = True  # a Ctrl-C, or the one signalled again, landed in the report
        if lost:
            again()

    sys.unraisablehook = hook
    try:
        yield
    finally:
        if sys.unraisablehook is hook:  # unless someone replaced it meanwhile
            sys.unraisablehook = previous
        for timer in due:
            timer.join()
