"""Parameter sweeps: bifurcation diagrams and 2-D period maps, streamed to HDF5.

The work is cut into *units*. A restart unit is a chunk of independent values;
a continuation unit is one segment of every unfinished chain (each chain
follows the values in order, starting from the previous value's final state).
A unit is computed by a pure function of (system, values, settings) --
:func:`compute_restart_chunk` or :func:`compute_continuation_chunk` -- so a
backend can run it anywhere; the driver alone writes the file.
"""

from __future__ import annotations

import contextlib
import hashlib
import sys
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numba
import numpy as np

from .interrupt import call_interruptible, new_abort_flag
from .io import ANALYSES, PER_VALUE_FIELDS, SweepFile, SweepLayout, read_sweep
from .poincare import ORBIT_STATUSES, STATUS_NAMES
from .simulate import (
    DEFAULT_DWELL,
    DEFAULT_EQUILIBRIUM_TOL,
    MAX_PERIOD,
    STOP_KINDS,
    resolve_settings,
)
from .status import ST_NOT_COMPUTED
from .system import PARAM_INDEX, SWEEPABLE, System
from .trajectory import METHODS, SWEEP_INT_FIELDS, continuation_chunk, sweep_chunk

__all__ = [
    "sweep",
    "SweepResult",
    "MODES",
    "compute_restart_chunk",
    "compute_continuation_chunk",
]

MODES = ("restart", "continuation", "continuation-both")
BACKENDS = ("local", "dask", "cuda")


# ----------------------------------------------------------------- pure chunks
def _param_rows(system: System, names: Sequence[str], values: np.ndarray) -> np.ndarray:
    """Packed parameter rows: ``values`` (..., len(names)) replace the named slots."""
    base = system.to_array()
    rows = np.broadcast_to(base, values.shape[:-1] + base.shape).copy()
    for k, name in enumerate(names):
        rows[..., PARAM_INDEX[name]] = values[..., k]
    return rows


def _kernel_args(system: System, settings: dict) -> tuple:
    return (
        system.n_oscillators,
        system.is_dc_motor,
        settings["t_end"],
        settings["t_transient"],
        settings["rtol"],
        settings["atol"],
        settings["h"],
        settings["max_steps"],
        settings["equilibrium_tol"],
        settings["period_tol"],
        MAX_PERIOD,
        settings["max_points"],
        STOP_KINDS.index(settings.get("stop", "fixed")),
        settings.get("dwell", DEFAULT_DWELL),
    )


def _checked(res: tuple) -> tuple:
    """Refuse kernel output with a value that was never computed (never stored as a result)."""
    status = res[2][..., SWEEP_INT_FIELDS.index("status")]
    if np.any(status == ST_NOT_COMPUTED):
        missing = int(np.count_nonzero(status == ST_NOT_COMPUTED))
        raise RuntimeError(
            f"internal error: {missing} value(s) of a chunk were not computed; nothing was stored"
        )
    return res


def _pack(res: tuple, settings: dict) -> dict[str, np.ndarray]:
    points, t_points, ints, t_converged, final_state = res
    out = {"points": points, "t_points": t_points, "final_state": final_state}
    if settings.get("stop", "fixed") == "converged":
        out["t_converged"] = t_converged
    for k, name in enumerate(SWEEP_INT_FIELDS):
        out[name] = ints[..., k]
    return out


def compute_restart_chunk(
    system: System, names: Sequence[str], values: np.ndarray, y0: np.ndarray, settings: dict
) -> dict[str, np.ndarray]:
    """Restart mode: trajectories from ``y0`` for each row of ``values`` (L, len(names)).

    A pure function: the same inputs give bit-identical outputs on any machine
    with the same compiled kernels, whatever the thread count.
    """
    rows = _param_rows(system, names, np.asarray(values, dtype=float))
    res = call_interruptible(
        sweep_chunk, METHODS.index(settings["method"]), y0, rows,
        *_kernel_args(system, settings), numba.get_num_threads(), abort=new_abort_flag(),
    )  # fmt: skip
    return _pack(_checked(res), settings)


def compute_continuation_chunk(
    system: System,
    names: Sequence[str],
    values: np.ndarray,
    y_starts: np.ndarray,
    y0: np.ndarray,
    settings: dict,
) -> dict[str, np.ndarray]:
    """Continuation mode: ``values`` (C, L, len(names)) are C chains run in parallel.

    Chain c starts from ``y_starts[c]``; each later value starts from the final
    state of the last value before it that did not fail (nonfinite,
    step-underflow, max-steps, error), ``y_starts[c]`` if none.
    """
    rows = _param_rows(system, names, np.asarray(values, dtype=float))
    res = call_interruptible(
        continuation_chunk, METHODS.index(settings["method"]), y0,
        np.ascontiguousarray(y_starts), rows, *_kernel_args(system, settings),
        abort=new_abort_flag(),
    )  # fmt: skip
    return _pack(_checked(res), settings)


# ----------------------------------------------------------------- the result
_DATA_FIELDS = ("points", "t_points", "final_state", "done", *PER_VALUE_FIELDS)


@dataclass
class SweepResult:
    """Result of :func:`sweep`.

    Arrays have the value axes first: ``(n,)`` for a 1-D sweep, ``(n1, n2)``
    for a 2-D one, with a leading branch axis of 2 ("up", "down") for mode
    "continuation-both". When the sweep wrote a file, the arrays are read from
    it on first access.

    Attributes
    ----------
    param : str or tuple of str
    values : ndarray or tuple of ndarray
        The swept values (one array per axis).
    points : ndarray, (..., max_points, n_state)
        Poincare points in time order, NaN-padded; NaN where there is no orbit.
    t_points : ndarray, (..., max_points)
    count, period, n_steps, n_rejected, n_crossings : ndarray of int
    status : ndarray of str
        As in :class:`SimulationResult`.
    final_state : ndarray, (..., n_state)
    state_names : list of str
    path : Path or None
        The HDF5 file, if any.
    """

    param: str | tuple[str, str]
    values: np.ndarray | tuple[np.ndarray, np.ndarray]
    mode: str
    state_names: list[str]
    system: System
    settings: dict
    path: Path | None = None
    _data: dict = field(default_factory=dict, repr=False)

    def _get(self, name: str) -> np.ndarray:
        if name not in self._data:
            if self.path is None:
                raise AttributeError(name)
            import h5py

            with h5py.File(self.path, "r", libver="latest", swmr=True) as h5:
                if name not in h5:
                    raise AttributeError(f"{self.path} has no {name!r} dataset")
                self._data[name] = h5[name][...]
        return self._data[name]

    points = property(lambda self: self._get("points"))
    t_points = property(lambda self: self._get("t_points"))
    final_state = property(lambda self: self._get("final_state"))
    count = property(lambda self: self._get("count"))
    period = property(lambda self: self._get("period"))
    n_steps = property(lambda self: self._get("n_steps"))
    n_rejected = property(lambda self: self._get("n_rejected"))
    n_crossings = property(lambda self: self._get("n_crossings"))
    status_code = property(lambda self: self._get("status"))
    sync_error = property(lambda self: self._get("sync_error"))
    lyapunov = property(lambda self: self._get("lyapunov"))
    lyapunov_fit = property(lambda self: self._get("lyapunov_fit"))

    @property
    def status(self) -> np.ndarray:
        codes = self.status_code
        names = np.array(STATUS_NAMES + ("missing",), dtype=object)
        return names[np.where(codes < 0, len(STATUS_NAMES), codes)]

    @property
    def shape(self) -> tuple[int, ...]:
        return self.count.shape

    def column(self, name: str) -> np.ndarray:
        """One state variable of every point, shape (..., max_points)."""
        return self.points[..., self.state_names.index(name)]

    def summary(self) -> dict[str, int]:
        """How many values ended with each status."""
        st = self.status.ravel()
        return {s: int(np.sum(st == s)) for s in STATUS_NAMES if np.any(st == s)}

    def __repr__(self) -> str:
        return f"SweepResult(param={self.param!r}, shape={self.shape}, mode={self.mode!r}, status={self.summary()})"


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
    axes = []
    for name, vals in zip(names, axes_in):
        if name not in SWEEPABLE:
            raise ValueError(
                f"param {name!r} cannot be swept; choose one of {list(SWEEPABLE)} "
                "(n_oscillators and drive change the state layout)"
            )
        arr = np.asarray(vals, dtype=float)
        if arr.ndim != 1 or arr.size == 0:
            raise ValueError(f"values for {name!r} must be a non-empty 1-D array")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"values for {name!r} must be finite")
        for v in np.unique(arr):  # per-field constraints: check each value once
            try:
                system.replace(**{name: float(v)})
            except ValueError as exc:
                raise ValueError(f"value {v!r} of swept param {name!r} is invalid: {exc}") from None
        axes.append(arr)
    return names, tuple(axes)


def _values_digest(axes: tuple[np.ndarray, ...]) -> list[str]:
    return [
        hashlib.sha256(np.ascontiguousarray(a, dtype="<f8").tobytes()).hexdigest() for a in axes
    ]


# ----------------------------------------------------------------- work units
@dataclass
class _Unit:
    kind: str  # "restart" | "continuation"
    values: np.ndarray  # (L, k) or (C, L, k)
    targets: list  # restart: (grid index, slice of the unit); continuation: one segment per chain
    y_starts: np.ndarray | None = None
    axis: int = 0  # continuation: grid axis the chains follow (1 when there is a branch axis)


def _restart_units(axes, done: np.ndarray, chunk: int) -> Iterator[_Unit]:
    grid = tuple(len(a) for a in axes)
    todo = np.flatnonzero(~done.reshape(-1))
    for a in range(0, todo.size, chunk):
        flat = todo[a : a + chunk]
        idx = np.unravel_index(flat, grid)
        vals = np.stack([axes[k][idx[k]] for k in range(len(axes))], axis=-1)
        # group into contiguous runs along the last axis, for efficient HDF5 writes
        targets = []
        start = 0
        for j in range(1, flat.size + 1):
            if j == flat.size or flat[j] != flat[j - 1] + 1 or (flat[j] % grid[-1]) == 0:
                lead = tuple(int(i[start]) for i in idx[:-1])
                last = slice(int(idx[-1][start]), int(idx[-1][j - 1]) + 1)
                targets.append((lead + (last,), slice(start, j)))
                start = j
        yield _Unit("restart", vals, targets)


def _chains(axes, branches: bool) -> list[list[tuple]]:
    """Every chain: a list of grid indices in the order the values are followed."""
    n1 = len(axes[0])
    others = [()] if len(axes) == 1 else [(j,) for j in range(len(axes[1]))]
    chains = []
    for b in (0, 1) if branches else (None,):
        for rest in others:
            order = range(n1) if b in (None, 0) else range(n1 - 1, -1, -1)
            lead = () if b is None else (b,)
            chains.append([lead + (i,) + rest for i in order])
    return chains


# ------------------------------------------------------------------- backends
def _run_local(units: Iterator[_Unit], system, names, y0, settings) -> Iterator[tuple[_Unit, dict]]:
    for unit in units:
        if unit.kind == "restart":
            res = compute_restart_chunk(system, names, unit.values, y0, settings)
        else:
            res = compute_continuation_chunk(
                system, names, unit.values, unit.y_starts, y0, settings
            )
        yield unit, res


@contextlib.contextmanager
def _numba_threads(threads: int | None):
    if threads is None:
        yield numba.get_num_threads()
        return
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads must be an integer >= 1, got {threads!r}")
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
        restart sweeps one trajectory per GPU thread (N <= 4, Rodas5P; the rest
        falls back to the CPU with a warning); it raises a RuntimeError without
        a GPU. Its status and period equal the CPU's, its points agree to
        ~1e-9 (not bit-identical), so it is part of the configuration: a file
        is all-CPU or all-GPU. See docs/gpu.md. ``"dask"`` (extra ``stickslip_fast[dask]``) uses
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

    Returns
    -------
    SweepResult

    Warns
    -----
    UserWarning
        When some values give no orbit (equilibrium, stall, no crossings) or fail.
    """
    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    names, axes = _normalise_params(system, param, values)
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if backend != "dask" and (scheduler is not None or n_workers is not None):
        raise ValueError("scheduler and n_workers are only used with backend='dask'")
    settings = resolve_settings(
        method, t_end, t_transient, rtol, atol, h, max_points, max_steps, equilibrium_tol,
        period_tol,
    )  # fmt: skip
    y_init = system.initial_state(y0)
    analyses = _normalise_analyses(analyses)
    branches = mode == "continuation-both"
    layout = SweepLayout(
        names, axes, branches, settings["max_points"], system.state_names, analyses
    )
    base = system.to_dict()
    for name in names:
        base[name] = None  # the base value of a swept field does not affect results
    from . import __version__

    config = {
        "system": base,
        "param": list(names),
        "n_values": [len(a) for a in axes],
        "values_sha256": _values_digest(axes),
        "mode": mode,
        "settings": {k: v for k, v in settings.items()},
        "y0": y_init.tolist(),
    }
    if analyses:  # absent when empty, so files made before analyses existed still resume
        config["analyses"] = list(analyses)
    if backend == "cuda":  # GPU points differ from the CPU's at ~1e-9: never mixed in a file
        config["backend"] = "cuda"
    grid = layout.grid_shape
    n_total = int(np.prod(grid))
    # resolved before any file is touched: a missing extra or a bad address fails first
    if backend == "cuda":
        runner = _cuda_runner(system, settings, mode)
    else:
        runner = _run_local if backend == "local" else _dask_runner(scheduler, n_workers)

    with contextlib.ExitStack() as stack:
        nthreads = stack.enter_context(_numba_threads(threads))
        if chunk_size is None:
            chunk_size = getattr(runner, "default_chunk_size", 32 * nthreads)
        elif isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1:
            raise ValueError(f"chunk_size must be an integer >= 1, got {chunk_size!r}")
        if out is not None:
            file = stack.enter_context(
                SweepFile.open(
                    out, config, layout, title=title, notes=notes, package_version=__version__
                )
            )
            done = file.done_mask()
        else:
            file = None
            done = np.zeros(grid, dtype=bool)
            mem = {
                "points": np.full(grid + (settings["max_points"], system.n_state), np.nan),
                "t_points": np.full(grid + (settings["max_points"],), np.nan),
                "final_state": np.full(grid + (system.n_state,), np.nan),
                "done": np.zeros(grid, dtype="u1"),
                **{
                    k: np.full(grid, -1 if k == "status" else 0, dtype=v)
                    for k, v in PER_VALUE_FIELDS.items()
                },
                **{k: np.full(grid, np.nan) for k in layout.analysis_fields},
            }

        def write(index, data):
            if file is not None:
                file.write(index, data)
            else:
                for k, v in data.items():
                    mem[k][index] = v
                mem["done"][index] = 1

        def final_state_at(index):
            return file.final_state_at(index) if file is not None else mem["final_state"][index]

        n_todo = int(n_total - done.sum())
        show = sys.stderr.isatty() if progress is None else bool(progress)
        bar = None
        if show and n_todo:
            from tqdm.auto import tqdm

            bar = stack.enter_context(
                tqdm(
                    total=n_total,
                    initial=n_total - n_todo,
                    unit="value",
                    desc=f"sweep {','.join(names)}",
                    dynamic_ncols=True,
                    smoothing=0.1,
                )  # fmt: skip
            )

        if mode == "restart":
            units = _restart_units(axes, done, chunk_size)
        else:
            units = _continuation_units(axes, branches, done, chunk_size, y_init, final_state_at)

        # closing(): a failure while writing also stops the backend (cancels its tasks)
        results = stack.enter_context(
            contextlib.closing(runner(units, system, names, y_init, settings))
        )
        for unit, res in results:
            if analyses:
                res = _run_analyses(unit, res, analyses, system, names, y_init, settings)
            n_written = _write_unit(unit, res, write)
            if bar is not None:
                bar.update(n_written)

    result = SweepResult(
        param=names[0] if len(names) == 1 else names,
        values=axes[0] if len(axes) == 1 else axes,
        mode=mode,
        state_names=system.state_names,
        system=system,
        settings=settings,
        path=Path(out) if out is not None else None,
        _data={} if file is not None else mem,
    )
    _warn_no_orbit(result, names, axes, branches)
    return result


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


def _unit_starts(unit: _Unit, res: dict, y0: np.ndarray) -> np.ndarray:
    """The initial state of every trajectory of a unit (shape of the value axes + state)."""
    if unit.kind == "restart":
        return np.broadcast_to(y0, (len(unit.values), y0.size))
    final = res["final_state"]
    starts = np.empty_like(final)
    starts[:, 0] = unit.y_starts
    starts[:, 1:] = final[:, :-1]
    bad = ~np.all(np.isfinite(starts), axis=-1)
    starts[bad] = y0  # as the continuation kernel: restart from y0 after a failure
    return starts


def _run_analyses(unit: _Unit, res: dict, analyses, system, names, y0, settings) -> dict:
    """Add the requested analysis fields to a unit's results (values axes first)."""
    from .analysis import largest_lyapunov, sync_error

    res = dict(res)
    shape = res["count"].shape
    vals = np.asarray(unit.values, dtype=float).reshape(-1, len(names))
    if "sync" in analyses:
        pts = res["points"].reshape(-1, *res["points"].shape[-2:])
        res["sync_error"] = np.array(
            [sync_error(p, system.n_oscillators) for p in pts], dtype=float
        ).reshape(shape)
    if "lyapunov" in analyses:
        starts = _unit_starts(unit, res, y0).reshape(-1, y0.size)
        lam = np.full(len(vals), np.nan)
        fit = np.full(len(vals), np.nan)
        for i, (row, start) in enumerate(zip(vals, starts)):
            sys_i = system.replace(**{n: float(v) for n, v in zip(names, row)})
            ly = largest_lyapunov(
                sys_i, settings["t_end"], settings["t_transient"], y0=start,
                rtol=settings["rtol"], atol=settings["atol"],
            )  # fmt: skip
            lam[i], fit[i] = ly.exponent, ly.exponent_fit
        res["lyapunov"] = lam.reshape(shape)
        res["lyapunov_fit"] = fit.reshape(shape)
    return res


def _continuation_units(axes, branches, done, chunk, y0, final_state_at) -> Iterator[_Unit]:
    """Rounds of chain segments; each round holds the next segment of every open chain."""
    chains = _chains(axes, branches)
    # resume: each chain continues after its last written value
    pos = []
    for chain in chains:
        k = 0
        while k < len(chain) and done[chain[k]]:
            k += 1
        pos.append(k)
    while True:
        open_ = [c for c, chain in enumerate(chains) if pos[c] < len(chain)]
        if not open_:
            return
        length = min(chunk, min(len(chains[c]) - pos[c] for c in open_))
        vals = []
        starts = []
        targets = []
        for c in open_:
            seg = chains[c][pos[c] : pos[c] + length]
            vals.append(
                [
                    [axes[k][idx[k + (len(idx) - len(axes))]] for k in range(len(axes))]
                    for idx in seg
                ]
            )
            starts.append(y0 if pos[c] == 0 else final_state_at(chains[c][pos[c] - 1]))
            targets.append(seg)
            pos[c] += length
        yield _Unit(
            "continuation", np.asarray(vals, dtype=float), targets, np.asarray(starts, dtype=float),
            axis=1 if branches else 0,
        )  # fmt: skip


def _write_unit(unit: _Unit, res: dict, write) -> int:
    if unit.kind == "restart":
        for index, sl in unit.targets:
            write(index, {k: v[sl] for k, v in res.items()})
        return len(unit.values)
    n = 0
    for c, seg in enumerate(unit.targets):
        # the segment runs along the first parameter axis, downwards on the "down" branch
        ax = unit.axis
        lo = min(idx[ax] for idx in seg)
        hi = max(idx[ax] for idx in seg)
        order = slice(None) if seg[0][ax] <= seg[-1][ax] else slice(None, None, -1)
        index = list(seg[0])
        index[ax] = slice(lo, hi + 1)
        write(tuple(index), {k: v[c][order] for k, v in res.items()})
        n += len(seg)
    return n


def _warn_no_orbit(result: SweepResult, names, axes, branches) -> None:
    status = result.status
    bad = ~np.isin(status, ORBIT_STATUSES)
    if not np.any(bad):
        return
    counts = {s: int(np.sum(status == s)) for s in np.unique(status[bad])}
    detail = ", ".join(f"{n} {s}" for s, n in sorted(counts.items()))
    example = ""
    if len(axes) == 1 and not branches:
        vals = axes[0][bad][:5]
        example = f" (e.g. {names[0]} = {', '.join(f'{v:g}' for v in vals)})"
    warnings.warn(
        f"{int(bad.sum())} of {status.size} values gave no orbit: {detail}{example}. "
        "Their points are NaN; see result.status.",
        UserWarning,
        stacklevel=3,
    )


def _dask_runner(scheduler: str | None, n_workers: int | None):
    """The Dask runner (:func:`stickslip_fast.backends.dask_runner`), imported on demand."""
    from .backends import dask_runner

    return dask_runner(scheduler, n_workers)


def _cuda_runner(system: System, settings: dict, mode: str):
    """The CUDA runner (:func:`stickslip_fast.cuda_backend.cuda_runner`), imported on demand."""
    from .cuda_backend import cuda_runner

    return cuda_runner(system, settings, mode)


def load_sweep(path: str | Path) -> SweepResult:
    """Open a sweep file written by :func:`sweep` as a :class:`SweepResult`."""
    data = read_sweep(path)
    cfg = data["config"]
    sysd = {k: v for k, v in cfg["system"].items() if v is not None}
    system = System.from_dict(sysd)
    names = tuple(cfg["param"])
    return SweepResult(
        param=names[0] if len(names) == 1 else names,
        values=data["axes"][0] if len(names) == 1 else data["axes"],
        mode=cfg["mode"],
        state_names=data["state_names"],
        system=system,
        settings=cfg["settings"],
        path=Path(path),
        _data={**{k: data[k] for k in _DATA_FIELDS}, **data["analyses"]},
    )
