"""Parameter sweeps: bifurcation diagrams and 2-D period maps, streamed to HDF5.

:func:`sweep` validates its arguments into a :class:`_Plan` (what to compute),
opens a store for the results (:class:`~stickslip_fast.io.SweepFile`, or its
in-memory twin :class:`~stickslip_fast.io.MemoryStore`), cuts the work into
units (:mod:`stickslip_fast.backends.local`), hands them to a backend (local, Dask
in :mod:`stickslip_fast.backends`, or the GPU in
:mod:`stickslip_fast.backends.cuda`) and writes each computed unit to the store.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import sys
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
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
from ..core.settings import DEFAULT_EQUILIBRIUM_TOL, Settings, check_memory
from ..io import ANALYSES, PER_VALUE_FIELDS, MemoryStore, SweepFile, SweepLayout
from ..model.system import SWEEPABLE, System
from .simulate import WORKSPACE_VECTORS
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

MODES = ("restart", "continuation", "continuation-both")
BACKENDS = ("local", "dask", "cuda")


# ----------------------------------------------------------------- validation
def _normalise_params(
    system: System, param, values
) -> tuple[tuple[str, ...], tuple[np.ndarray, ...]]:
    if isinstance(param, str):
        names = (param,)
        axes_in = (values,)
    elif (
        isinstance(param, (tuple, list))
        and len(param) == 2
        and all(isinstance(p, str) for p in param)
    ):
        names = tuple(param)
        if not isinstance(values, (tuple, list)) or len(values) != 2:
            raise ValueError("a 2-D sweep needs values as a tuple of two arrays, one per parameter")
        axes_in = tuple(values)
        if names[0] == names[1]:
            raise ValueError(f"the two swept parameters must differ, got {names}")
    else:
        raise ValueError(f"param must be a field name or a tuple of two, got {param!r}")
    return names, tuple(_check_axis(system, n, v) for n, v in zip(names, axes_in))


def _check_axis(system: System, name: str, vals: Any) -> np.ndarray:
    """The values of one swept field as a float array, checked vectorised.

    Every per-field rule of :class:`System` is an interval (m > 0, eta in
    [1, 10], mu >= 0, ...), so checking the smallest and the largest value
    checks them all: 1e7 values take ~0.5 s, not ~5 min of one System() per value.
    """
    if name not in SWEEPABLE:
        raise ValueError(
            f"param {name!r} cannot be swept; choose one of {list(SWEEPABLE)} "
            "(n_oscillators and drive change the state layout)"
        )
    if isinstance(vals, (list, tuple)) and any(isinstance(v, (bool, np.bool_)) for v in vals):
        raise ValueError(f"values for {name!r} must be numbers, got a boolean in {plain(vals)}")
    arr = np.asarray(vals)
    if arr.dtype.kind not in "iuf":  # strings, booleans, objects: not silently converted
        raise ValueError(f"values for {name!r} must be numbers, got an array of {arr.dtype}")
    arr = arr.astype(float)
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"values for {name!r} must be a non-empty 1-D array")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"values for {name!r} must be finite")
    for v in (float(arr.min()), float(arr.max())):
        try:
            system.replace(**{name: v})
        except ValueError as exc:
            raise ValueError(
                f"value {plain(v)} of swept param {name!r} is invalid: {exc}"
            ) from None
    return arr


def _normalise_analyses(analyses) -> tuple[str, ...]:
    if isinstance(analyses, str):
        analyses = (analyses,)
    try:
        items = tuple(analyses)
    except TypeError:
        raise ValueError(f"analyses must be a sequence of names, got {analyses!r}") from None
    unknown = [a for a in items if a not in ANALYSES]
    if unknown:
        raise ValueError(f"unknown analyses {unknown}; choose from {sorted(ANALYSES)}")
    return tuple(a for a in ANALYSES if a in items)  # canonical order, no duplicates


def _warn_order(name: str, values: np.ndarray, mode: str) -> None:
    """Continuation follows the values in array order: say so when that order is odd."""
    step = np.diff(values)
    if mode == "continuation-both" and not np.all(step > 0):
        what = "has duplicates" if np.any(step == 0) else "is not increasing"
    elif mode == "continuation" and not (np.all(step > 0) or np.all(step < 0)):
        what = "has duplicates" if np.any(step == 0) else "is not monotonic"
    else:
        return
    warnings.warn(
        f"values for {name!r} {what}; mode {mode!r} follows them in the given order "
        + ("(the 'up' branch is array order, 'down' its reverse)" if mode != "continuation" else "")
        + ", so each value starts from the previous one in that order. Sort them "
        "(np.unique) for a branch that follows the parameter.",
        UserWarning,
        stacklevel=4,
    )


def _values_digest(axes: tuple[np.ndarray, ...]) -> list[str]:
    return [
        hashlib.sha256(np.ascontiguousarray(a, dtype="<f8").tobytes()).hexdigest() for a in axes
    ]


@dataclass(frozen=True)
class _Plan:
    """Everything that determines a sweep's results, validated."""

    system: System
    names: tuple[str, ...]
    axes: tuple[np.ndarray, ...]
    mode: str
    settings: Settings
    y0: np.ndarray
    analyses: tuple[str, ...]
    backend: str = "local"

    @property
    def layout(self) -> SweepLayout:
        branches = self.mode == "continuation-both"
        return SweepLayout(
            self.names, self.axes, branches, self.settings.max_points, self.system.state_names,
            self.analyses, converged=self.settings.stop == "converged",
        )  # fmt: skip

    def config(self) -> dict[str, Any]:
        """The configuration stored in (and hashed into) the result file."""
        base = self.system.to_dict()
        for name in self.names:
            base[name] = None  # the base value of a swept field does not affect results
        config = {
            "system": base,
            "param": list(self.names),
            "n_values": [len(a) for a in self.axes],
            "values_sha256": _values_digest(self.axes),
            "mode": self.mode,
            "settings": self.settings.to_dict(),
            "y0": self.y0.tolist(),
        }
        if self.analyses:  # absent when empty, so files made before analyses existed resume
            config["analyses"] = list(self.analyses)
        if self.backend == "cuda":  # GPU points differ from the CPU's at ~1e-9: never mixed
            config["backend"] = "cuda"
        return config


def _plan(system, param, values, mode, y0, analyses, settings: Settings) -> _Plan:
    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    names, axes = _normalise_params(system, param, values)
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    if mode != "restart":
        _warn_order(names[0], axes[0], mode)
    if settings.max_points == 0:
        warnings.warn(
            "max_points = 0: no Poincare points are kept, so no period is detected "
            "(period 0 for every value); only status and final state are recorded",
            UserWarning,
            stacklevel=4,
        )
    return _Plan(
        system, names, axes, mode, settings, system.initial_state(y0), _normalise_analyses(analyses)
    )


def _check_backend(backend: str, scheduler, n_workers) -> None:
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if backend != "dask" and (scheduler is not None or n_workers is not None):
        raise ValueError("scheduler and n_workers are only used with backend='dask'")


def _check_chunk_size(chunk_size) -> None:
    if chunk_size is not None and (
        isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1
    ):
        raise ValueError(f"chunk_size must be an integer >= 1, got {plain(chunk_size)}")


def _check_sweep_memory(plan: _Plan, in_memory: bool, chunk_size: int, threads: int) -> None:
    """Refuse, before allocating, a sweep whose result arrays cannot fit in memory."""
    n_state, kp = plan.system.n_state, plan.settings.max_points
    per_value = 8 * (n_state * (kp + 1) + kp + len(PER_VALUE_FIELDS) + 1)
    if in_memory:
        n_values = int(np.prod(plan.layout.grid_shape))
        what = "the in-memory results (give out= to stream them to a file)"
    else:  # a continuation unit holds a segment of chunk_size values of every chain
        n_chains = int(np.prod(plan.layout.grid_shape)) // len(plan.axes[0])
        n_values = chunk_size * (1 if plan.mode == "restart" else n_chains)
        what = f"one unit of {n_values} values (lower chunk_size)"
    check_memory(
        n_values * per_value + threads * 8 * n_state * WORKSPACE_VECTORS,
        f"{what} with n_oscillators = {plan.system.n_oscillators} and max_points = {kp}",
    )


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
    show = sys.stderr.isatty() if progress is None else bool(progress)
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
        for i, (row, start) in enumerate(zip(vals, starts)):
            sys_i = system.replace(**{n: float(v) for n, v in zip(names, row)})
            ly = largest_lyapunov(sys_i, s.t_end, s.t_transient, y0=start, rtol=s.rtol, atol=s.atol)
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
    equilibrium_tol: float = DEFAULT_EQUILIBRIUM_TOL,
    period_tol: float | None = None,
    title: str = "",
    notes: str = "",
    analyses: Sequence[str] = (),
    stop: str = "fixed",
    dwell: float | None = None,
) -> SweepResult:
    """Sweep one or two System fields and record the Poincare points of every value.

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
        Initial state (default zeros; v_b(0) = 0 for the DC motor).
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
    settings = Settings.resolve(
        method, t_end, t_transient, rtol, atol, h, max_points, max_steps, equilibrium_tol,
        period_tol, stop=stop, dwell=dwell,
    )  # fmt: skip
    plan = _plan(system, param, values, mode, y0, analyses, settings)
    _check_backend(backend, scheduler, n_workers)
    _check_chunk_size(chunk_size)
    if backend == "cuda":
        plan = dataclasses.replace(plan, backend="cuda")
        runner = _cuda_runner(system, settings, mode)
    else:
        # resolved before any file is touched: a missing extra or a bad address fails first
        runner = run_local if backend == "local" else _dask_runner(scheduler, n_workers)

    data = _run_units(plan, runner, system, settings, out, title, notes, chunk_size, threads,
                      progress)  # fmt: skip
    result = SweepResult(
        param=plan.names[0] if len(plan.names) == 1 else plan.names,
        values=plan.axes[0] if len(plan.axes) == 1 else plan.axes,
        mode=mode,
        state_names=system.state_names,
        system=system,
        settings=settings,
        path=Path(out) if out is not None else None,
        _data=data,
    )
    warn_no_orbit(result, plan.names, plan.axes, mode == "continuation-both")
    return result


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
