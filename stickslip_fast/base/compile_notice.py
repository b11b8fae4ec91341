"""A line on the terminal while a kernel compiles, so that a first run does not look hung.

On a fresh install (or a new Numba cache folder) the first call of each kernel makes Numba
compile it: 13-35 s for a first ``simulate`` on two cores, with nothing on the screen and
a sweep's progress bar at 0 % (docs/performance.md, "The first run"). :func:`install`
registers a listener on Numba's ``numba:compile`` event, which fires only when a function
is compiled, never when it is loaded from the cache. When the outermost compile is one of
this package's functions and lasts longer than :data:`DELAY_S`, a timer thread writes

    stickslip_fast: compiling the trajectory kernel (integrate), first use only ...

and the end of the compile adds ``stickslip_fast: compiled the trajectory kernel
(integrate) in 14.2 s; cached for later runs`` (or ``... stopped after 3.1 s`` when the
compile fails or is interrupted). The lines go through ``tqdm.write``,
which lifts a progress bar above them. Short compiles (an entry twin, a small helper)
write nothing.

Every finished compile of the package is also logged at INFO on the
``stickslip_fast.compile`` logger, whatever the terminal (for cluster logs).

When the lines are written: :func:`set_enabled` decides if it was called (the CLI's
``--quiet`` turns them off); else ``STICKSLIP_FAST_COMPILE_NOTICE=1`` always, ``=0``
never; else only in the main process (not in Dask or ``stickslip-fast compile`` workers)
and when standard error is a terminal, as for the progress bars. Nothing computed depends
on it.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import sys
import threading
import time

from numba.core import event

from .terminal import on_terminal

__all__ = ["CompileNotice", "install", "installed", "set_enabled"]

ENV_VAR = "STICKSLIP_FAST_COMPILE_NOTICE"
EVENT = "numba:compile"
PACKAGE = "stickslip_fast"
#: Seconds a compile runs before its line is written (shorter ones stay silent).
DELAY_S = 1.0
LOGGER = logging.getLogger(f"{PACKAGE}.compile")
#: Words for the kernels that users meet (other functions go by their own names).
KERNEL_WORDS = {
    "integrate": "the trajectory kernel (integrate)",
    "run_lane": "the sweep kernel (run_lane)",
    "propagate_sensitivity": "the orbit kernel (propagate_sensitivity)",
    "lyapunov_kernel": "the Lyapunov kernel (lyapunov_kernel)",
}

_ENABLED: bool | None = None


def set_enabled(enabled: bool | None) -> None:
    """Write the lines always (True), never (False), or by the default rule (None)."""
    global _ENABLED
    _ENABLED = None if enabled is None else bool(enabled)


def _wanted(stream) -> bool:
    """Whether to write the lines now (:func:`set_enabled`, then the variable, then the rule)."""
    if _ENABLED is not None:
        return _ENABLED
    env = os.environ.get(ENV_VAR, "").strip()
    if env in ("0", "1"):
        return env == "1"
    if multiprocessing.parent_process() is not None:
        return False  # a worker: its parent speaks for it
    return on_terminal(stream)


def _package_function(data) -> str | None:
    """The qualified name of the compiled function if it is this package's, else None."""
    dispatcher = (data or {}).get("dispatcher")
    func = getattr(dispatcher, "py_func", None)
    module = getattr(func, "__module__", "") or ""
    if module == PACKAGE or module.startswith(PACKAGE + "."):
        name = getattr(func, "__qualname__", None) or getattr(func, "__name__", "?")
        return KERNEL_WORDS.get(name, name)
    return None


def _write(line: str, stream) -> None:
    try:
        from tqdm import tqdm

        tqdm.write(line, file=stream)
    except (OSError, ValueError):  # a closed or broken stream: the compile goes on
        pass


class CompileNotice(event.Listener):
    """Writes a line when one of the package's compiles runs long, and logs its time.

    Parameters
    ----------
    stream : file-like, optional
        Where the lines go (default: ``sys.stderr`` at the time of the compile).
    delay : float, optional
        Seconds before the line is written (default: :data:`DELAY_S` at the time).
    """

    def __init__(self, stream=None, delay: float | None = None) -> None:
        self.stream = stream
        self.delay = delay
        self.depth = 0  # nested compiles: a caller compiles its callees within its own
        self.name: str | None = None  # the outermost compile, if the package's
        self.t0 = 0.0
        self.timer: threading.Timer | None = None
        self.shown = False
        self.lock = threading.Lock()  # the timer thread against the compile's end

    def _stream(self):
        return self.stream if self.stream is not None else sys.stderr

    def on_start(self, ev: event.Event) -> None:
        self.depth += 1
        if self.depth > 1:
            return
        try:
            self._begin(ev)
        except Exception:  # noqa: BLE001 - a notice must never break a compile
            self.name = None

    def _begin(self, ev: event.Event) -> None:
        self.name = _package_function(ev.data)
        if self.name is None:
            return
        self.t0 = time.perf_counter()
        self.shown = False
        if _wanted(self._stream()):
            delay = DELAY_S if self.delay is None else self.delay
            self.timer = threading.Timer(delay, self._show)
            self.timer.daemon = True
            self.timer.start()

    def _show(self) -> None:
        with self.lock:
            if self.timer is not threading.current_thread():
                return  # its compile ended meanwhile
            self.shown = True
            _write(
                f"{PACKAGE}: compiling {self.name}, first use only ...",
                self._stream(),
            )

    def on_end(self, ev: event.Event) -> None:  # also after a failed compile
        self.depth = max(self.depth - 1, 0)
        if self.depth or self.name is None:
            return
        try:
            self._finish(ev)
        except Exception:  # noqa: BLE001 - a notice must never break a compile
            self.name = self.timer = None

    def _finish(self, ev: event.Event) -> None:
        seconds = time.perf_counter() - self.t0
        with self.lock:
            timer, self.timer = self.timer, None
            shown, self.shown = self.shown, False
            name, self.name = self.name, None
        if timer is not None:
            timer.cancel()
        # an error, or Ctrl-C, which raises next. Numba 0.68's Event.is_failed reads the
        # other way round, so the event's exception is looked at (None when it is renamed:
        # then a failed compile is reported as compiled, nothing worse)
        failed = getattr(ev, "_exc_details", None) is not None
        if failed:
            line = f"compiling {name} stopped after {seconds:.1f} s"
        else:
            line = f"compiled {name} in {seconds:.1f} s"
        if shown:
            tail = "" if failed else "; cached for later runs"
            _write(f"{PACKAGE}: {line}{tail}", self._stream())
        LOGGER.info(line)


_LISTENER: CompileNotice | None = None


def install() -> bool:
    """Register the listener once per process.

    Returns
    -------
    bool
        True (the listener is registered after the call).
    """
    global _LISTENER
    if _LISTENER is None:
        _LISTENER = CompileNotice()
        event.register(EVENT, _LISTENER)
    return True


def installed() -> bool:
    """Whether the listener is registered in this process."""
    return _LISTENER is not None
