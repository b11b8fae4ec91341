"""``stickslip-fast compile``: compile the kernels ahead of the first run, into Numba's cache.

A fresh install compiles each kernel the first time a process uses it (15-35 s for a
first ``simulate`` on two cores; docs/performance.md, "The first run"); Numba then
caches it on disk, and later processes load it in about a second. This command pays
the compile once, ahead, where that suits: while a container image is built, in a CI
step whose cache is kept, on a new cluster node. It runs each requested kernel on a
tiny problem through the public functions, so with the argument types of real runs,
and it runs the kernels in parallel processes (Numba compiles one function at a time
in a process).
"""

from __future__ import annotations

import argparse
import itertools
import multiprocessing
import os
import time
import warnings
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor

from ..model.system import DRIVES

#: What can be compiled: one trajectory (``simulate``), the sweep kernels (``sweep``:
#: restart and continuation chunks, which ``census`` and ``basins`` run too), and the
#: variational kernels of periodic orbits (``orbits``: ``find_orbit``, ``continue_orbit``).
KERNELS = ("simulate", "sweep", "orbits")

#: The defaults: what the README's first examples and most configs in data/ use.
DEFAULT_METHODS = ("rodas5p",)
DEFAULT_OSCILLATORS = (1,)
DEFAULT_DRIVES = DRIVES


def compile_jobs(
    kernels: Sequence[str], methods: Sequence[str], oscillators: Sequence[int],
    drives: Sequence[str],
) -> list[tuple[str, str, int, str]]:  # fmt: skip
    """The (kernel, method, N, drive) jobs; ``orbits`` once per (N, drive), since the
    variational problem is always integrated by Rodas5P."""
    jobs = []
    for kernel, n, drive in itertools.product(kernels, oscillators, drives):
        for method in ("rodas5p",) if kernel == "orbits" else methods:
            jobs.append((kernel, method, n, drive))
    return jobs


def run_job(job: tuple[str, str, int, str]) -> dict:
    """Compile (or load) one job's kernels by running them on a tiny problem."""
    import numpy as np

    from ..analysis.simulate import simulate
    from ..analysis.sweep import sweep
    from ..bifurcation.returnmap import _field, return_map
    from ..model.system import System

    kernel, method, n, drive = job
    # the tiny problems' labels (no orbit, disks in step) are not what the user runs
    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    system = System.preset("asymmetric", drive=drive, n_oscillators=n)
    kw = dict(method=method, h=1e-3 if method == "dopri5-fixed" else None)
    if kernel == "simulate":  # long enough for a few minima: the period detection too
        simulate(system, 60.0, **kw)
    elif kernel == "sweep":
        for mode in ("restart", "continuation"):
            sweep(system, "eta", np.array([5.0, 6.0]), t_end=1.0, mode=mode,
                  progress=False, **kw)  # fmt: skip
    else:  # the variational kernel: its sensitivity off (find_orbit) and on (continue_orbit)
        z = system.initial_state(None) + 1e-3
        _field(system, z)  # the vector field from Python (find_orbit's start and checks)
        return_map(system, z, 1, t_max=1.0)
        return_map(system, z, 1, t_max=1.0, param="eta")
    return dict(job=job, seconds=time.perf_counter() - t0, pid=os.getpid())


def cache_location() -> str:
    """Where Numba keeps the cache: ``NUMBA_CACHE_DIR``; else the ``__pycache__`` folders
    next to the package's modules where they are writable; else Numba's user-wide folder."""
    import numba
    from numba.misc.appdirs import AppDirs

    if numba.config.CACHE_DIR:
        return str(numba.config.CACHE_DIR)
    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    if os.access(package, os.W_OK):
        return os.path.join(package, "*", "__pycache__")
    return AppDirs(appname="numba", appauthor=False).user_cache_dir


def precompile(
    kernels: Sequence[str] = KERNELS,
    methods: Sequence[str] = DEFAULT_METHODS,
    oscillators: Sequence[int] = DEFAULT_OSCILLATORS,
    drives: Sequence[str] = DEFAULT_DRIVES,
    jobs: int | None = None,
    say=print,
) -> list[dict]:
    """Compile the kernels of every (kernel, method, N, drive) into Numba's cache.

    Parameters
    ----------
    kernels : sequence of {"simulate", "sweep", "orbits"}
    methods : sequence of str
        Integration methods (``stickslip_fast.METHODS``).
    oscillators : sequence of int
        Numbers of disks N >= 1 (one disk has kernels of its own for each drive; any
        N >= 2 runs the generic ones, so one N >= 2 stands for all).
    drives : sequence of {"constant", "dc-motor"}
    jobs : int, optional
        Processes compiling side by side (default: the number of cores).
    say : callable
        Receives one line per finished job.

    Returns
    -------
    list of dict
        Per job: ``job`` (kernel, method, N, drive), ``seconds``, ``pid``.

    Raises
    ------
    ValueError
        For an unknown kernel, method or drive, or an N or ``jobs`` that is not an
        integer >= 1, naming it.
    """
    from ..core.settings import check_integer
    from ..core.trajectory import METHODS

    for name, given, allowed in (("kernel", kernels, KERNELS), ("method", methods, METHODS),
                                 ("drive", drives, DRIVES)):  # fmt: skip
        bad = [g for g in given if g not in allowed]
        if bad or not given:
            raise ValueError(f"{name} must be one or more of {list(allowed)}, got {bad or given}")
    if not oscillators:
        raise ValueError("oscillators must be one or more integers >= 1, got none")
    oscillators = [check_integer("oscillators", n, 1) for n in oscillators]
    if jobs is not None:
        jobs = check_integer("jobs", jobs, 1)
    todo = compile_jobs(kernels, methods, oscillators, drives)
    workers = max(1, min(jobs or os.cpu_count() or 1, len(todo)))
    out = []
    # spawn: each worker imports the package afresh (no forked Numba state)
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        for rec in pool.map(run_job, todo):
            kernel, method, n, drive = rec["job"]
            say(f"{kernel:<9} {method:<12} N = {n:<3} {drive:<9} {rec['seconds']:6.1f} s")
            out.append(rec)
    return out


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The ``compile`` subcommand."""
    p = sub.add_parser(
        "compile", help="compile the kernels ahead of the first run (into Numba's cache)"
    )
    p.add_argument("--kernels", nargs="+", default=list(KERNELS), metavar="KERNEL",
                   help=f"of {', '.join(KERNELS)} (default: all)")  # fmt: skip
    p.add_argument("--methods", nargs="+", default=list(DEFAULT_METHODS), metavar="METHOD",
                   help="integration methods (default: rodas5p)")  # fmt: skip
    p.add_argument("--oscillators", nargs="+", type=int, default=list(DEFAULT_OSCILLATORS),
                   metavar="N", help="numbers of disks (default: 1)")  # fmt: skip
    p.add_argument("--drives", nargs="+", default=list(DEFAULT_DRIVES), metavar="DRIVE",
                   help="constant and/or dc-motor (default: both)")  # fmt: skip
    p.add_argument("--jobs", type=int, help="processes side by side (default: all cores)")
    p.set_defaults(func=_cmd_compile)


def _cmd_compile(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    done = precompile(args.kernels, args.methods, args.oscillators, args.drives, args.jobs)
    print(f"compiled {len(done)} jobs in {time.perf_counter() - t0:.1f} s; "
          f"cache: {cache_location()}")  # fmt: skip
    return 0
