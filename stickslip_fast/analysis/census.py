"""Attractor census: every attractor at every parameter value, with basin fractions.

A census runs many initial states (*starts*) at each value of one parameter,
in parallel over all (value, start) pairs, and groups the runs of each value
into attractors: periodic orbits (identified by their Poincare points up to a
cyclic shift), equilibria (steady sliding; identified by their state), stalled
motors, and runs with no period <= 64 ("unresolved": chaos, quasi-periodicity,
a long period or a transient longer than the run). The attractors of
neighbouring values are then matched into *tracks* (as Attractors.jl's global
continuation does), so one attractor keeps one id along the sweep and the
births and deaths of tracks tell bifurcations apart from the zero-state start
merely crossing a basin boundary.

The raw runs (the expensive part) stream to HDF5 and resume after a kill; the
grouping and tracking (cheap, deterministic) are recomputed from the raw runs
and stored in the same file (schema in :mod:`stickslip_fast.io`, census
section, and docs/file-format.md).

Each pair runs through :func:`stickslip_fast.sweep.compute_continuation_chunk`
(chains of length one, one per pair), the same pure function the sweeps and the
Dask backend use, so a census run of (value, start) is bit-identical to
``simulate(system.replace(param=value), y0=start, ...)`` with the same settings.
"""

from __future__ import annotations

import contextlib
import hashlib
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..base.messages import plain
from ..core.settings import DEFAULT_EQUILIBRIUM_TOL, Settings
from ..io import CensusFile, CensusLayout, read_census, write_census_classification
from ..model.system import SWEEPABLE, System
from .census_classify import (  # noqa: F401  (re-exported)
    _BACKENDS,
    _ST_EQ,
    _ST_OK,
    _ST_STALLED,
    DEFAULT_CENSUS_POINTS,
    DEFAULT_TRACK_THRESHOLD,
    IDENTITY_FACTOR,
    KINDS,
    STOP_RULES,
    Attractor,
    CensusResult,
    Track,
    classify_census,
)


# ------------------------------------------------------------------ the starts
def default_box(system: System, param: str | None = None, values=None) -> np.ndarray:
    """The default box of initial states, one (low, high) row per state variable.

    Physical reasoning (docs/census.md): with the belt sliding under a disk at
    rest, the friction force is mu (one unit of kinetic friction) and torque
    zero, so the steady-sliding state is x_s = mu / (1 - k12^2),
    phi_s = -k12 x_s. Sticking can hold the spring up to the static friction,
    eta times the kinetic one, so positions within D = max(eta - 1, 1) mu of
    the sliding state can stick; the box is x_i in [x_s - D, x_s + D], phi_i in
    [phi_s - D, phi_s + D], and speeds dx_i, dphi_i in [-D, D] (the speed of a
    unit-frequency swing of amplitude D). The DC motor's belt speed v_b is in
    [0, v_b0]. When ``param`` is swept, the box is the union of the boxes of
    every value, so one set of starts serves the whole sweep.

    Parameters
    ----------
    system : System
    param : str, optional
        The swept field.
    values : array_like, optional
        Its values.

    Returns
    -------
    ndarray, shape (n_state, 2)
    """
    systems = [system]
    if param is not None and values is not None:
        systems = [system.replace(**{param: float(v)}) for v in np.unique(values)]
    lows = []
    highs = []
    for s in systems:
        xs = s.mu / (1.0 - s.k12**2)
        ps = -s.k12 * xs
        d = max(s.eta - 1.0, 1.0) * s.mu
        lo = []
        hi = []
        for _ in range(s.n_oscillators):
            lo += [xs - d, -d, ps - d, -d]
            hi += [xs + d, d, ps + d, d]
        if s.is_dc_motor:
            lo.append(0.0)
            hi.append(s.vb0)
        lows.append(lo)
        highs.append(hi)
    return np.stack([np.min(lows, axis=0), np.max(highs, axis=0)], axis=-1)


def sample_starts(
    system: System, n_starts: int, box, seed: int = 0, include_zero: bool = True
) -> np.ndarray:
    """Seeded uniform starts in ``box`` (n_state x 2), the zero state first if asked.

    ``numpy.random.default_rng(seed).random((n, n_state))`` scaled into the box
    (NumPy's PCG64 stream, stable across NumPy versions); with ``include_zero``
    start 0 is the paper's initial condition (the zero state, v_b(0) = 0) and
    ``n_starts - 1`` starts are random. The same seed gives the same starts.
    """
    box = np.asarray(box, dtype=float)
    n_random = n_starts - 1 if include_zero else n_starts
    rng = np.random.default_rng(seed)
    u = rng.random((n_random, system.n_state))
    random = box[:, 0] + u * (box[:, 1] - box[:, 0])
    if include_zero:
        return np.concatenate([system.initial_state(None)[None, :], random], axis=0)
    return random


# ------------------------------------------------------------------ the driver
@dataclass
class _Unit:
    """A unit of work in the contract of the sweep runners: length-1 chains."""

    kind: str
    values: np.ndarray  # (C, 1, 1)
    targets: list  # flat pair indices, one per chain
    y_starts: np.ndarray  # (C, n_state)
    axis: int = 0


def _units(
    values: np.ndarray, starts: np.ndarray, done: np.ndarray, chunk: int, nthreads: int
) -> Iterator[_Unit]:
    n_s = len(starts)
    todo = np.flatnonzero(~done.reshape(-1))
    for a in range(0, todo.size, chunk):
        flat = todo[a : a + chunk]
        # interleave over the threads, whose share of a prange is contiguous: each
        # thread gets pairs from the whole unit (costs vary smoothly with the value)
        flat = np.concatenate([flat[t::nthreads] for t in range(nthreads)])
        vi, si = np.divmod(flat, n_s)
        yield _Unit(
            "continuation", values[vi][:, None, None], [int(f) for f in flat],
            np.ascontiguousarray(starts[si]),
        )  # fmt: skip


def _values_digest(a: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(a, dtype="<f8").tobytes()).hexdigest()


def _check_starts(system: System, n_starts, box, starts, seed, include_zero, param, values):
    if starts is not None:
        if box is not None:
            raise ValueError("give box or starts, not both")
        arr = np.asarray(starts, dtype=float)
        if arr.ndim != 2 or arr.shape[1] != system.n_state or arr.shape[0] < 1:
            raise ValueError(
                f"starts must have shape (n_starts, {system.n_state}) "
                f"({', '.join(system.state_names)}), got {arr.shape}"
            )
        if not np.all(np.isfinite(arr)):
            raise ValueError("starts must be finite (found NaN or inf)")
        return arr.copy(), None
    if isinstance(n_starts, bool) or not isinstance(n_starts, (int, np.integer)) or n_starts < 1:
        raise ValueError(f"n_starts must be an integer >= 1, got {n_starts!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {plain(seed)}")
    if box is None:
        box_arr = default_box(system, param, values)
    else:
        box_arr = np.asarray(box, dtype=float)
        if box_arr.shape != (system.n_state, 2):
            raise ValueError(
                f"box must have shape ({system.n_state}, 2): one (low, high) pair per state "
                f"variable ({', '.join(system.state_names)}), got {box_arr.shape}"
            )
        if not np.all(np.isfinite(box_arr)) or np.any(box_arr[:, 0] > box_arr[:, 1]):
            raise ValueError("box must be finite with low <= high in every row")
    return sample_starts(system, int(n_starts), box_arr, int(seed), bool(include_zero)), box_arr


def census(
    system: System,
    param: str,
    values,
    *,
    t_end: float,
    t_transient: float = 0.0,
    n_starts: int = 64,
    box=None,
    starts=None,
    seed: int = 0,
    include_zero: bool = True,
    stop: str = "converged",
    out: str | Path | None = None,
    threads: int | None = None,
    backend: str = "local",
    scheduler: str | None = None,
    n_workers: int | None = None,
    progress: bool | None = None,
    chunk_size: int | None = None,
    method: str = "rodas5p",
    rtol: float | None = None,
    atol: float | None = None,
    h: float | None = None,
    max_points: int = DEFAULT_CENSUS_POINTS,
    max_steps: int | None = None,
    equilibrium_tol: float = DEFAULT_EQUILIBRIUM_TOL,
    period_tol: float | None = None,
    dwell: float | None = None,
    identity_tol: float | None = None,
    track_threshold: float = DEFAULT_TRACK_THRESHOLD,
    title: str = "",
    notes: str = "",
    _config_extra: dict | None = None,
    _desc: str | None = None,
) -> CensusResult:
    """Every attractor at every value of ``param``, with its basin fraction.

    Runs every start at every value (in parallel over the (value, start)
    pairs), groups the runs of each value into attractors, and matches the
    attractors of neighbouring values into tracks.

    Parameters
    ----------
    system : System
        Base parameters; ``param`` is overwritten per value.
    param : str
        The swept field (``"eta"``, ``"k12"``, ...).
    values : array_like
        Its values, in the order tracks follow (sorted is what you want).
    t_end, t_transient : float
        Each run lasts ``t_end``; points are kept after ``t_transient``.
    n_starts : int
        Number of starts, the zero state included when ``include_zero``.
    box : array_like (n_state, 2), optional
        (low, high) per state variable for the seeded uniform sampler; default
        :func:`default_box` (docs/census.md gives the physical reasoning).
    starts : array_like (n_starts, n_state), optional
        Explicit starts instead of the sampler (not together with ``box``).
    seed : int
        Seed of the sampler.
    include_zero : bool
        Make start 0 the zero state (the paper's initial condition).
    stop : {"converged", "fixed"}
        Stop rule of every run, as for :func:`simulate`: "converged" (the
        default) ends a run once its Poincare points repeat or it has come to
        rest (``t_end`` is the cap), records only points after that, and
        stores each run's ``t_converged``; "fixed" integrates to ``t_end``.
        Converged stopping is the default because the census groups runs by
        their points: with "fixed" and ``t_transient = 0`` a run's points
        include its transient, and each run costs the full ``t_end``.
    out : path, optional
        HDF5 file to stream into (docs/file-format.md, census file); running
        the same census on it again resumes, a different one is refused.
    threads, chunk_size, backend, scheduler, n_workers, progress
        As for :func:`sweep`; ``chunk_size`` counts (value, start) pairs per
        unit of work (default 32 per thread; 64 with ``backend="dask"``, each
        unit split over the workers; with ``backend="cuda"`` one launch of
        about the threads the GPU holds, docs/gpu.md). Results do not depend
        on them, except that GPU points differ from the CPU's at ~1e-9, so a
        file is all-CPU or all-GPU (the backend is part of its configuration).
    method, rtol, atol, h, max_points, max_steps, equilibrium_tol, period_tol, dwell
        As for :func:`sweep`; ``max_points`` defaults to 128 (enough to
        detect any period <= 64).
    identity_tol, track_threshold : float
        See :func:`classify_census`; they do not change the runs, so a finished
        file can be re-classified with other values (:func:`load_census`).
    title, notes : str
        Stored in the file.

    Returns
    -------
    CensusResult

    Raises
    ------
    ValueError
        For bad input, naming the argument.
    """
    from ..base.version import package_version
    from .sweep import _numba_threads

    vals = _check_census_args(
        system, param, values, stop, backend, scheduler, n_workers, track_threshold, identity_tol
    )
    start_arr, box_arr = _check_starts(
        system, n_starts, box, starts, seed, include_zero, param, vals
    )
    settings = Settings.resolve(
        method=method, t_end=t_end, t_transient=t_transient, rtol=rtol, atol=atol, h=h,
        max_points=max_points, max_steps=max_steps, equilibrium_tol=equilibrium_tol,
        period_tol=period_tol, stop=stop, dwell=dwell,
    )  # fmt: skip
    config = _census_config(system, param, vals, start_arr, stop, settings, backend)
    if _config_extra:  # callers built on the census (basins) add their own fields
        config.update(_config_extra)
    layout = CensusLayout(
        param, vals, start_arr, settings.max_points, system.state_names, stop == "converged"
    )
    y0 = system.initial_state(None)
    n_v, n_s = len(vals), len(start_arr)
    runner = _census_runner(backend, scheduler, n_workers, system, settings)

    with contextlib.ExitStack() as stack:
        nthreads = stack.enter_context(_numba_threads(threads))
        chunk_size = _census_chunk_size(chunk_size, backend, runner, nthreads)
        if out is not None:
            file = stack.enter_context(
                CensusFile.open(
                    out, config, layout, title=title, notes=notes, package_version=package_version()
                )
            )
            done = file.done_mask()
            mem = None
        else:
            file = None
            done = np.zeros((n_v, n_s), dtype=bool)
            mem = CensusFile.empty_arrays(layout)
        bar = _census_bar(stack, progress, done, _desc or f"census {param}")
        units = _units(vals, start_arr, done, chunk_size, nthreads)
        results = stack.enter_context(
            contextlib.closing(runner(units, system, (param,), y0, settings))
        )
        for unit, res in results:
            n_written = _store_unit(unit, res, file, mem, n_s)
            if bar is not None:
                bar.update(n_written)

    if out is not None:
        return load_census(
            out, identity_tol=identity_tol, track_threshold=track_threshold, _write=True
        )
    labels, attractors, tracks = classify_census(
        vals, mem, period_tol=settings.period_tol, identity_tol=identity_tol,
        track_threshold=track_threshold,
    )  # fmt: skip
    return CensusResult(
        param=param, values=vals, starts=start_arr, labels=labels, status_code=mem["status"],
        period=mem["period"], attractors=attractors, tracks=tracks,
        state_names=system.state_names, system=system, settings=settings.to_dict(),
        raw=mem,
    )  # fmt: skip


def _check_census_args(
    system, param, values, stop, backend, scheduler, n_workers, track_threshold, identity_tol
) -> np.ndarray:
    """Check :func:`census`'s arguments other than the starts and settings; the values."""
    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    if not isinstance(param, str) or param not in SWEEPABLE:
        raise ValueError(f"param must be one of {list(SWEEPABLE)}, got {param!r}")
    vals = np.asarray(values, dtype=float)
    if vals.ndim != 1 or vals.size == 0 or not np.all(np.isfinite(vals)):
        raise ValueError("values must be a non-empty 1-D array of finite numbers")
    for v in np.unique(vals):
        try:
            system.replace(**{param: float(v)})
        except ValueError as exc:
            raise ValueError(f"value {plain(v)} of param {param!r} is invalid: {exc}") from None
    if stop not in STOP_RULES:
        raise ValueError(f"stop must be one of {STOP_RULES}, got {stop!r}")
    if backend not in _BACKENDS:
        raise ValueError(f"backend must be one of {_BACKENDS}, got {backend!r}")
    if backend != "dask" and (scheduler is not None or n_workers is not None):
        raise ValueError("scheduler and n_workers are only used with backend='dask'")
    if track_threshold is None or not np.isfinite(track_threshold) or track_threshold <= 0:
        raise ValueError(f"track_threshold must be a number > 0, got {plain(track_threshold)}")
    if identity_tol is not None and (not np.isfinite(identity_tol) or identity_tol <= 0):
        raise ValueError(f"identity_tol must be a number > 0, got {identity_tol!r}")
    return vals


def _census_config(system, param, vals, start_arr, stop, settings, backend) -> dict:
    """Everything that determines a census's results (stored in its file, and hashed)."""
    base = system.to_dict()
    base[param] = None
    config = {
        "kind": "census",
        "system": base,
        "param": param,
        "n_values": int(vals.size),
        "values_sha256": _values_digest(vals),
        "n_starts": len(start_arr),
        "starts_sha256": _values_digest(start_arr),
        "stop": stop,
        "settings": settings.to_dict(),
    }
    if backend == "cuda":  # GPU points differ from the CPU's at ~1e-9: never mixed in a file
        config["backend"] = "cuda"
    return config


def _census_runner(backend, scheduler, n_workers, system, settings):
    """The backend's runner (its extra imported only when chosen)."""
    from ..backends.local import run_local

    runner = run_local
    if backend == "dask":
        from ..backends.dask import dask_runner

        runner = dask_runner(scheduler, n_workers)
    elif backend == "cuda":
        from ..backends.cuda import cuda_runner

        runner = cuda_runner(system, settings, "census")
    return runner


def _census_chunk_size(chunk_size, backend, runner, nthreads) -> int:
    """(value, start) pairs per unit of work: the caller's, or the backend's default."""
    if chunk_size is None:
        # the Dask runner splits each unit over its workers and waits for the whole
        # unit before the next: units of 64 pairs keep a small cluster busy
        chunk_size = {"local": 32 * nthreads, "dask": 64}.get(
            backend, getattr(runner, "default_chunk_size", 64)
        )
    elif isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1:
        raise ValueError(f"chunk_size must be an integer >= 1, got {plain(chunk_size)}")
    return chunk_size


def _census_bar(stack, progress, done, desc):
    """A progress bar over the pairs still to run (None when not shown)."""
    n_todo = int(done.size - done.sum())
    show = sys.stderr.isatty() if progress is None else bool(progress)
    bar = None
    if show and n_todo:
        from tqdm.auto import tqdm

        bar = stack.enter_context(
            tqdm(total=done.size, initial=done.size - n_todo, unit="run",
                 desc=desc, dynamic_ncols=True, smoothing=0.1)
        )  # fmt: skip
    return bar


def _store_unit(unit, res, file, mem, n_s) -> int:
    """Write one unit's results, in pair order, to the file or the in-memory arrays."""
    flat = np.asarray(unit.targets)
    order = np.argsort(flat, kind="stable")
    data = {k: v[:, 0][order] for k, v in res.items()}
    flat = flat[order]
    if file is not None:
        file.write_pairs(flat, data)
    else:
        vi, si = np.divmod(flat, n_s)
        for k, v in data.items():
            mem[k][vi, si] = v
        mem["done"][vi, si] = 1
    return len(flat)


def load_census(
    path: str | Path,
    *,
    identity_tol: float | None = None,
    track_threshold: float | None = None,
    _write: bool = False,
) -> CensusResult:
    """Open a census file as a :class:`CensusResult` (classified from its runs).

    Runs not computed yet (an unfinished file) are labelled -1 with status
    "missing". ``identity_tol`` and ``track_threshold`` (see
    :func:`classify_census`) default to those the file was classified with,
    else to the defaults. With ``_write`` (what :func:`census` does when it
    finishes) the labels, attractors and tracks are also stored in the file.
    """
    data = read_census(path)
    if identity_tol is None and not _write:
        identity_tol = data["attrs"].get("identity_tol")
    if track_threshold is None:
        track_threshold = data["attrs"].get("track_threshold", DEFAULT_TRACK_THRESHOLD)
    data["status"] = np.where(data["done"] == 1, data["status"], -1).astype(data["status"].dtype)
    cfg = data["config"]
    sysd = {k: v for k, v in cfg["system"].items() if v is not None}
    param = cfg["param"]
    vals = data["values"]
    sysd[param] = float(vals[0])
    system = System.from_dict(sysd)
    settings = cfg["settings"]
    labels, attractors, tracks = classify_census(
        vals, data, period_tol=settings["period_tol"], identity_tol=identity_tol,
        track_threshold=track_threshold,
    )  # fmt: skip
    tol = IDENTITY_FACTOR * settings["period_tol"] if identity_tol is None else identity_tol
    if _write and bool(np.all(data["done"])):
        write_census_classification(
            path, labels, attractors, tracks, KINDS,
            {"identity_tol": tol, "track_threshold": track_threshold},
        )  # fmt: skip
    return CensusResult(
        param=param, values=vals, starts=data["starts"], labels=labels,
        status_code=data["status"], period=data["period"], attractors=attractors,
        tracks=tracks, state_names=data["state_names"], system=system, settings=settings,
        path=Path(path), raw=data,
    )  # fmt: skip
