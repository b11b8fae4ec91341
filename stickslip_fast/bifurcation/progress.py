"""A progress bar over the points of a continuation.

A branch of orbits takes seconds to minutes (multiple shooting, re-meshing), and a
two-parameter curve can take much longer: a Neimark-Sacker curve of 450 points ran for
40 minutes on one core (docs/orbits.md). :func:`points_bar`, entered by
:func:`~stickslip_fast.continue_orbit`, :func:`~stickslip_fast.continue_equilibrium` and
:func:`~stickslip_fast.continue_bifurcation`, shows a tqdm bar of the accepted points (of
``max_points``) with the parameter values of the last one. The walk itself
(:func:`.arclength.pseudo_arclength`) reports each accepted point through
:func:`walk_reporter`. Walks one after the other (a branch that goes on with multiple
shooting, or on a new mesh) report to the same bar; a walk run inside another one would
report nothing. Nothing computed depends on it.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Sequence
from contextvars import ContextVar

import numpy as np

from ..base.terminal import show_progress

__all__ = ["points_bar", "walk_reporter"]

#: The reporter of the bar in force (None: no bar, or inside a walk).
_REPORTER: ContextVar[Callable[[np.ndarray], None] | None] = ContextVar(
    "stickslip_fast_points_bar", default=None
)


def _shown(progress: bool | None) -> bool:
    """True, False, or None: shown when standard error is a terminal (as for sweeps)."""
    if progress is not None and not isinstance(progress, (bool, np.bool_)):
        raise ValueError(f"progress must be True, False or None, got {progress!r}")
    return show_progress(progress)


@contextlib.contextmanager
def points_bar(
    progress: bool | None, total: int, desc: str, names: Sequence[str]
) -> Iterator[None]:
    """Show a bar of the points that the walks inside accept (``progress`` as for sweeps).

    ``names`` are the parameters, the last coordinates of a point (one for a branch, two
    for a curve), shown with their values after the count.
    """
    if not _shown(progress):
        yield
        return
    from tqdm.auto import tqdm

    k = len(names)
    with tqdm(total=int(total), initial=1, desc=desc, unit="point", dynamic_ncols=True) as bar:

        def report(x: np.ndarray) -> None:
            values = ", ".join(f"{n}={v:.10g}" for n, v in zip(names, x[-k:], strict=True))
            try:
                bar.set_postfix_str(values, refresh=False)
                bar.update(1)
            except (OSError, ValueError):  # a closed or broken terminal: the walk goes on
                pass

        token = _REPORTER.set(report)
        try:
            yield
        finally:
            _REPORTER.reset(token)
        # the walk ended (a bound, a fold it could not pass): max_points was only a cap
        bar.total = bar.n
        bar.refresh()


@contextlib.contextmanager
def walk_reporter() -> Iterator[Callable[[np.ndarray], None] | None]:
    """The bar's reporter for one walk (None without a bar); walks inside it get None."""
    report = _REPORTER.get()
    token = _REPORTER.set(None)
    try:
        yield report
    finally:
        _REPORTER.reset(token)
