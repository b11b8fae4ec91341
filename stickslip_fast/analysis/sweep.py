"""Parameter sweeps: bifurcation diagrams and 2-D period maps, streamed to HDF5.

:func:`sweep` validates its arguments into a plan (what to compute:
:mod:`.sweep_plan`), opens a store for the results (:class:`~stickslip_fast.io.SweepFile`, or its
in-memory twin :class:`~stickslip_fast.io.MemoryStore`), cuts the work into
units (:mod:`stickslip_fast.backends.local`), hands them to a backend (local, Dask
in :mod:`stickslip_fast.backends`, or the GPU in
:mod:`stickslip_fast.backends.cuda`) and writes each computed unit to the store.
"""

from __future__ import annotations

import contextlib
import dataclasses
import warnings
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numba
import numpy as np

from ..backends.local import (
    WorkUnit,
    compute_continuation_chunk,
    compute_restart_chunk,
    continuation_units,
    restart_units,
    run_local,
    unit_starts,
    write_unit,
)
from ..base.messages import plain
from ..base.terminal import show_progress
from ..core.settings import CoarseToleranceWarning, Settings, system_defaults
from ..io import MemoryStore, SweepFile
from ..model.system import System
from .sweep_plan import (  # noqa: F401  (_normalise_params: census checks its axes with it)
    BACKENDS,
    MODES,
    _check_backend,
    _check_chunk_size,
    _check_sweep_memory,
    _checked_params,
    _normalise_params,
    _Plan,
    _plan,
)
from .sweep_result import SweepResult, load_sweep, warn_no_orbit

__all__ = [
    "sweep",
    "SweepResult",
    "load_sweep",
    "MODES",
    "BACKENDS",
    "compute_restart_chunk",
    "compute_continuation_chunk",
]


# ------------------------------------------------------------------ the driver
@contextlib.contextmanager
def _numba_threads(threads: int | None):
    if threads is None:
        yield numba.get_num_threads()
        return
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads must be an integer >= 1, got {plain(threads)}")
    if threads > numba.config.NUMBA_NUM_THREADS:
        raise ValueError(
            f"threads={threads} exceeds the {numba.config.NUMBA_NUM_THREADS} available"
        )
    old = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        yield threads
    finally:
        numba.set_num_threads(old)


def _open_store(plan: _Plan, out, title: str, notes: str) -> SweepFile | MemoryStore:
    if out is None:
        return MemoryStore(plan.layout)
    from ..base.version import package_version

    return SweepFile.open(
        out, plan.config(), plan.layout, title=title, notes=notes, package_version=package_version()
    )


def _progress_bar(stack: contextlib.ExitStack, progress, done: np.ndarray, names):
    """A tqdm bar over all values (None when not shown or nothing is left)."""
    n_total = done.size
    n_todo = int(n_total - done.sum())
    show = show_progress(progress)
    if not (show and n_todo):
        return None
    from tqdm.auto import tqdm

    return stack.enter_context(
        tqdm(
            total=n_total,
            initial=n_total - n_todo,
            unit="value",
            desc=f"sweep {','.join(names)}",
            dynamic_ncols=True,
            smoothing=0.1,
        )  # fmt: skip
    )


def _units(plan: _Plan, done: np.ndarray, chunk_size: int, store) -> Iterator[WorkUnit]:
    if plan.mode == "restart":
        return restart_units(plan.axes, done, chunk_size)
    branches = plan.mode == "continuation-both"
    return continuation_units(plan.axes, branches, done, chunk_size, plan.y0, store.final_state_at)


def _run_analyses(unit: WorkUnit, res: dict, plan: _Plan) -> dict:
    """Add the requested analysis fields to a unit's results (values axes first)."""
    from . import largest_lyapunov, sync_error  # not needed by most sweeps

    system, names, s = plan.system, plan.names, plan.settings
    res = dict(res)
    shape = res["count"].shape
    vals = np.asarray(unit.values, dtype=float).reshape(-1, len(names))
    if "sync" in plan.analyses:
        pts = res["points"].reshape(-1, *res["points"].shape[-2:])
        res["sync_error"] = np.array(
            [sync_error(p, system.n_oscillators) for p in pts], dtype=float
        ).reshape(shape)
    if "lyapunov" in plan.analyses:
        starts = unit_starts(unit, res, plan.y0).reshape(-1, plan.y0.size)
        lam = np.full(len(vals), np.nan)
        fit = np.full(len(vals), np.nan)
        with warnings.catch_warnings():  # the sweep warned of a coarse atol once already
            warnings.simplefilter("ignore", CoarseToleranceWarning)
            for i, (row, start) in enumerate(zip(vals, starts)):
                sys_i = system.replace(**{n: float(v) for n, v in zip(names, row)})
                ly = largest_lyapunov(
                    sys_i, s.t_end, s.t_transient, y0=start, rtol=s.rtol, atol=s.atol
                )
                lam[i], fit[i] = ly.exponent, ly.exponent_fit
        res["lyapunov"] = lam.reshape(shape)
        res["lyapunov_fit"] = fit.reshape(shape)
    return res


def _cuda_runner(system: System, settings: Settings, mode: str):
    """The CUDA runner (:func:`stickslip_fast.backends.cuda.cuda_runner`), imported on demand."""
    from ..backends.cuda import cuda_runner

    return cuda_runner(system, settings, mode)


def _dask_runner(scheduler: str | None, n_workers: int | None):
    """The Dask runner; imported on demand because importing distributed is slow."""
    from ..backends.dask import dask_runner

    return dask_runner(scheduler, n_workers)


# ------------------------------------------------------------------------ API
#: :func:`sweep`'s docstring (kept out of the function body, as for
#: :func:`~stickslip_fast.analysis.census.census`: the layout rule counts a
#: function's lines, and its parameters take more lines than its code).
_SWEEP_DOC = """Sweep one or two System fields and record the Poincare points of every value.

Parameters
----------
system : System
    Base parameters; the swept field(s) are overwritten per value.
param : str or (str, str)
    Field(s) to sweep: any float field of :class:`System` (``"eta"``,
    ``"k12"``, ``"vb"``, ``"vb0"``, ``"beta"``, ``"mu"``, ``"m"``, ``"c"``, ...).
    Two names sweep the 2-D grid (a period map of the parameter plane).
values : array_like or (array_like, array_like)
    The values, one array per parameter.
t_end, t_transient : float
    Each trajectory runs to ``t_end``; points are kept after ``t_transient``.
y0 : array_like, optional
    Initial state (default zeros; v_b(0) = 0 for the DC motor; with N >= 2
    disks on a DC motor a :class:`~stickslip_fast.SynchronousStartWarning`: see :func:`simulate`).
mode : {"restart", "continuation", "continuation-both"}
    ``"restart"``: every value starts from ``y0`` (the paper's method).
    ``"continuation"``: values are followed in order along the first
    parameter, each starting from the previous final state.
    ``"continuation-both"``: up, then down, keeping both branches (a leading
    axis of 2), so hysteresis and coexisting attractors show.
method, rtol, atol, h, max_steps, equilibrium_tol, period_tol
    As for :func:`simulate`.
max_points : int
    Points kept per value (the most recent).
out : path, optional
    HDF5 file to stream into (see docs/file-format.md). Re-running the same
    sweep on the same file resumes it; a different configuration is refused.
chunk_size : int, optional
    Values per unit of work (default 32 per thread; 8 per task with
    ``backend="dask"``); results do not depend on it.
threads : int, optional
    Numba threads for this sweep (default: all). Results do not depend on it.
progress : bool, optional
    tqdm progress bar; default: only when stderr is a terminal.
backend : {"local", "dask", "cuda"}
    Where units run. ``"cuda"`` (extra ``stickslip_fast[cuda]``) runs
    restart sweeps one trajectory per GPU thread (N <= 4, Rodas5P, stop
    "fixed"; the rest falls back to the CPU with a warning); it raises a
    RuntimeError without a GPU. Its status and period equal the CPU's, its
    points agree to ~1e-9 (not bit-identical), so it is part of the
    configuration: a file is all-CPU or all-GPU. See docs/gpu.md. ``"dask"`` (extra ``stickslip_fast[dask]``) uses
    ``scheduler`` (an address such as ``"tcp://host:8786"``) or starts a
    LocalCluster of ``n_workers`` single-threaded processes (default: one
    per core) for this sweep. Results arrive in any order and only this
    process writes ``out``; continuation rounds run one after another.
    Results are bit-identical to ``"local"``. See docs/distributed.md.
title, notes : str
    Stored in the file.
analyses : sequence of {"sync", "lyapunov"}
    Extra per-value results, stored as extra datasets (see
    :mod:`stickslip_fast.io`) and available as ``result.sync_error``,
    ``result.lyapunov``, ``result.lyapunov_fit``. ``"sync"``:
    :func:`analysis.sync_error` of the value's Poincare points (cheap; only
    meaningful for N >= 2). ``"lyapunov"``: :func:`analysis.largest_lyapunov`
    of the value's trajectory (same start state, t_end, t_transient, rtol,
    atol); expensive (~2-5x the sweep) and computed in this process after
    each unit. The list is part of the configuration (and its hash); the
    other results do not depend on it.
stop, dwell
    As for :func:`simulate`: ``stop="converged"`` ends each trajectory once
    it has converged (``t_end`` is the cap) and stores ``t_converged`` per
    value (NaN where t_end came first). Part of the configuration.

Returns
-------
SweepResult

Warns
-----
UserWarning
    When some values give no orbit (equilibrium, stall, no crossings) or fail.
"""


def sweep(
    system: System,
    param: str | tuple[str, str],
    values,
    *,
    t_end: float,
    t_transient: float = 0.0,
    y0=None,
    mode: str = "restart",
    method: str = "rodas5p",
    rtol: float | None = None,
    atol: float | None = None,
    h: float | None = None,
    max_points: int = 256,
    out: str | Path | None = None,
    chunk_size: int | None = None,
    threads: int | None = None,
    progress: bool | None = None,
    backend: str = "local",
    scheduler: str | None = None,
    n_workers: int | None = None,
    max_steps: int | None = None,
    equilibrium_tol: float | None = None,
    period_tol: float | None = None,
    title: str = "",
    notes: str = "",
    analyses: Sequence[str] = (),
    stop: str = "fixed",
    dwell: float | None = None,
) -> SweepResult:
    names, axes = _checked_params(system, param, values)
    atol, equilibrium_tol, dwell = system_defaults(
        system, names, axes, atol=atol, equilibrium_tol=equilibrium_tol, dwell=dwell
    )
    settings = Settings.resolve(
        method, t_end, t_transient, rtol, atol, h, max_points, max_steps, equilibrium_tol,
        period_tol, stop=stop, dwell=dwell,
    )  # fmt: skip
    plan = _plan(system, names, axes, mode, y0, analyses, settings)
    _check_backend(backend, scheduler, n_workers)
    _check_chunk_size(chunk_size)
    plan, runner = _backend_runner(plan, backend, scheduler, n_workers)
    data = _run_units(plan, runner, system, settings, out, title, notes, chunk_size, threads,
                      progress)  # fmt: skip
    result = _result(plan, data, out)
    warn_no_orbit(result, plan.names, plan.axes, mode == "continuation-both")
    return result


sweep.__doc__ = _SWEEP_DOC


def _backend_runner(plan: _Plan, backend: str, scheduler, n_workers) -> tuple[_Plan, Any]:
    """The plan (marked for the GPU with ``backend="cuda"``: part of the configuration) and
    the runner of its units.

    Resolved before any file is touched: a missing extra or a bad address fails first."""
    if backend == "cuda":
        plan = dataclasses.replace(plan, backend="cuda")
        return plan, _cuda_runner(plan.system, plan.settings, plan.mode)
    return plan, run_local if backend == "local" else _dask_runner(scheduler, n_workers)


def _result(plan: _Plan, data: dict, out) -> SweepResult:
    """The :class:`SweepResult` of a sweep run by ``plan`` (``data``: the in-memory
    results, or ``{}`` for a file read lazily from ``out``)."""
    return SweepResult(
        param=plan.names[0] if len(plan.names) == 1 else plan.names,
        values=plan.axes[0] if len(plan.axes) == 1 else plan.axes,
        mode=plan.mode,
        state_names=plan.system.state_names,
        system=plan.system,
        settings=plan.settings,
        path=Path(out) if out is not None else None,
        _data=data,
    )


def _run_units(plan, runner, system, settings, out, title, notes, chunk_size, threads, progress):
    """Run and store the units not done yet; the in-memory results (``{}`` with a file)."""
    with contextlib.ExitStack() as stack:
        nthreads = stack.enter_context(_numba_threads(threads))
        if chunk_size is None:
            chunk_size = getattr(runner, "default_chunk_size", 32 * nthreads)
        _check_sweep_memory(plan, out is None, chunk_size, nthreads)
        fresh = out is None or not Path(out).exists()
        store = stack.enter_context(_open_store(plan, out, title, notes))
        # a new store has nothing done: no need to read the mask back (~1.3 s per 1e7 values)
        done = np.zeros(plan.layout.grid_shape, dtype=bool) if fresh else store.done_mask()
        bar = _progress_bar(stack, progress, done, plan.names)
        units = _units(plan, done, chunk_size, store)
        # closing(): a failure while writing also stops the backend (cancels its tasks)
        results = stack.enter_context(
            contextlib.closing(runner(units, system, plan.names, plan.y0, settings))
        )
        for unit, res in results:
            if plan.analyses:
                res = _run_analyses(unit, res, plan)
            n_written = write_unit(unit, res, store.write)
            if bar is not None:
                bar.update(n_written)
    return store.data if out is None else {}
