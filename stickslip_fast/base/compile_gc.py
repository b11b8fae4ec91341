"""No full garbage collections while Numba compiles.

A first ``simulate`` or ``find_orbit`` makes Numba build and drop millions of Python
objects (its IR, types and LLVM handles, many of them in reference cycles). Python's
cyclic collector walks every live object of the process at each full collection, and
during a cold compile those took about a tenth of it (``gc.callbacks``: 1.6 s of a
14.6 s first ``simulate``, 1.36 s of that in 12 full collections; docs/performance.md,
"The first run"). :func:`install` registers a listener on Numba's ``numba:compile``
event (Numba's event API; it fires only when a function is compiled, not when one is
loaded from the cache). From the start of the outermost compile to its end the
collector runs its young collections only, every :data:`YOUNG_THRESHOLD` allocations;
then its thresholds are restored. The cycles that outlive two young collections wait
for the next full collection after the compile: about 30-60 MB more at the peak of a
first ``find_orbit`` (turning the collector off altogether saved no more time and
held 190 MB more).

Nothing computed depends on it. Numba compiles under its global compiler lock, so one
thread at a time runs inside the listener. A collector that is off is left alone. Set
``STICKSLIP_FAST_PAUSE_GC=0`` before the import to leave the collector alone always.
"""

from __future__ import annotations

import gc
import os

from numba.core import event

__all__ = ["CompileGCPause", "install", "installed"]

ENV_VAR = "STICKSLIP_FAST_PAUSE_GC"
EVENT = "numba:compile"


#: The young generation's threshold during a compile (Python's default is 700).
YOUNG_THRESHOLD = 10_000
#: A threshold of the oldest generation that a compile never reaches: no full collection.
NEVER = 2**30


class CompileGCPause(event.Listener):
    """Holds off full collections (and thins young ones) for the outermost compile."""

    def __init__(self) -> None:
        self.depth = 0  # nested compiles: a caller compiles its callees within its own
        self.saved: tuple[int, ...] | None = None  # thresholds to restore, if changed

    def on_start(self, ev: event.Event) -> None:  # noqa: ARG002 - the Listener API
        young, middle, _ = gc.get_threshold()
        # a young threshold 0 turns collection off, as gc.disable() does: keep it so
        if self.depth == 0 and gc.isenabled() and young > 0:
            self.saved = gc.get_threshold()
            gc.set_threshold(max(young, YOUNG_THRESHOLD), middle, NEVER)
        self.depth += 1

    def on_end(self, ev: event.Event) -> None:  # noqa: ARG002 - also after a failed compile
        self.depth -= 1
        if self.depth == 0:
            self.restore()

    def restore(self) -> None:
        """Put back the thresholds this listener changed."""
        if self.saved is not None:
            gc.set_threshold(*self.saved)
            self.saved = None


_LISTENER: CompileGCPause | None = None


def install() -> bool:
    """Register the listener once per process, unless ``STICKSLIP_FAST_PAUSE_GC=0``.

    Returns
    -------
    bool
        True if the listener is registered after the call.
    """
    global _LISTENER
    if _LISTENER is None and os.environ.get(ENV_VAR, "1") != "0":
        _LISTENER = CompileGCPause()
        event.register(EVENT, _LISTENER)
    return _LISTENER is not None


def installed() -> bool:
    """Whether the listener is registered in this process."""
    return _LISTENER is not None
