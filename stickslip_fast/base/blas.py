"""One BLAS thread for the dense linear algebra around the package's own threads.

OpenBLAS, which NumPy ships, runs a matrix product or factorisation of a few hundred
rows on all cores, and its threads then busy-wait for the next call for a while
(OpenBLAS's thread timeout) instead of sleeping. A multiple-shooting walk calls it
between its segment integrations, on matrices of 100-600 rows: the waiting threads took
a whole core for the length of the walk and the segments' own threads
(:meth:`~stickslip_fast.bifurcation.multishoot.MultiShooting.segment_flows`) had to
share what was left. Measured on the 2-core AMD EPYC VM (docs/performance.md, "Multiple
shooting and two-parameter curves on threads"): a walk of 9.9 s took 19.5 s of CPU with
its segments on one thread; with BLAS on one thread it took 10.2 s and 10.2 s of CPU, and
with its segments on two threads 5.8 s (before: 7.5-9.4 s).
One thread also makes the linear algebra's last bits independent of the machine's
core count (a threaded factorisation may add in another order).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from threadpoolctl import threadpool_limits

__all__ = ["one_blas_thread"]


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """BLAS and LAPACK on one thread inside (also usable as a decorator); the limits in
    force before are restored on the way out."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield
