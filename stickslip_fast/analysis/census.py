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
merely crossing a basin boundary. With two parameters the census covers a
grid (a plane) instead: the same runs and grouping per cell, tracks over
neighbouring cells and per-cell maps (:mod:`.census_plane`).

The starts are drawn by :mod:`.census_starts`; the runs are cut into units and
streamed by :mod:`.census_run`. The raw runs (the expensive part) stream to HDF5 and resume after a kill; the
grouping and tracking (cheap, deterministic) are recomputed from the raw runs
and stored in the same file (schema in :mod:`stickslip_fast.io`, census
section, and docs/file-format.md).

Each pair runs through :func:`stickslip_fast.backends.local.compute_continuation_chunk`
(chains of length one, one per pair), the same pure function the sweeps and the
Dask backend use, so a census run of (value, start) is bit-identical to
``simulate(system.replace(param=value), y0=start, ...)`` with the same settings.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..base.messages import plain
from ..core.settings import Settings, system_defaults, warn_if_coarse_atol
from ..io import CENSUS_RUN_FIELDS, CensusLayout, read_census, write_census_classification
from ..model.system import (
    SWEEPABLE,
    System,
    smallest_eps,
    warn_if_synchronous,
)
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
from .census_plane import CensusPlaneResult, classify_plane, plane_track_columns
from .census_run import RunOptions, _values_digest, run_pairs
from .census_starts import _check_starts, default_box, sample_starts  # noqa: F401

#: :func:`census`'s docstring (kept out of the function body: the parameters take more
#: lines than the code, and the layout rule counts a function's lines).
_CENSUS_DOC = """Every attractor at every value of ``param``, with its basin fraction.

Runs every start at every value (in parallel over the (value, start)
pairs), groups the runs of each value into attractors, and matches the
attractors of neighbouring values into tracks. With two parameters the
values are a grid (a plane): every start runs at every cell, and tracks
join the attractors of neighbouring cells (:func:`classify_plane`).

Parameters
----------
system : System
    Base parameters; ``param`` is overwritten per value.
param : str or (str, str)
    The swept field (``"eta"``, ``"k12"``, ...), or two fields for a census
    over the plane they span.
values : array_like, or (array_like, array_like)
    Its values, in the order tracks follow (sorted is what you want); for
    two fields one array each: cell (i, j) is (``values[0][i]``,
    ``values[1][j]``).
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
    Make start 0 the zero state (the paper's initial condition for one disk).
    With N >= 2 disks on a DC motor that start keeps the disks identical and
    can label an in-phase orbit that is unstable across them: a
    :class:`~stickslip_fast.SynchronousStartWarning` says so (``include_zero=False`` avoids it).
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
CensusResult, or CensusPlaneResult for two parameters
    ``attractors[i]`` and ``labels[i, :]`` per value; for a plane
    ``attractors[i][j]`` and ``labels[i, j, :]`` per cell.

Raises
------
ValueError
    For bad input, naming the argument.
"""


def census(
    system: System,
    param: str | tuple[str, str],
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
    equilibrium_tol: float | None = None,
    period_tol: float | None = None,
    dwell: float | None = None,
    identity_tol: float | None = None,
    track_threshold: float = DEFAULT_TRACK_THRESHOLD,
    title: str = "",
    notes: str = "",
    _config_extra: dict | None = None,
    _desc: str | None = None,
) -> CensusResult | CensusPlaneResult:
    names, axes = _check_census_args(
        system, param, values, stop, backend, scheduler, n_workers, track_threshold, identity_tol
    )
    plane = len(names) == 2
    if starts is None and include_zero:
        warn_if_synchronous(system, "start 0 (rest, include_zero=True)", stacklevel=2)
    start_arr, box_arr = _check_starts(
        system, n_starts, box, starts, seed, include_zero, names if plane else param,
        axes if plane else axes[0],
    )  # fmt: skip
    eps = smallest_eps(system, names, axes)
    atol, equilibrium_tol, dwell = system_defaults(
        system, names, axes, atol=atol, equilibrium_tol=equilibrium_tol, dwell=dwell
    )
    settings = Settings.resolve(
        method=method, t_end=t_end, t_transient=t_transient, rtol=rtol, atol=atol, h=h,
        max_points=max_points, max_steps=max_steps, equilibrium_tol=equilibrium_tol,
        period_tol=period_tol, stop=stop, dwell=dwell,
    )  # fmt: skip
    warn_if_coarse_atol(eps, settings.atol, stacklevel=2)
    config = _census_config(system, names, axes, start_arr, stop, settings, backend)
    if _config_extra:  # callers built on the census (basins) add their own fields
        config.update(_config_extra)
    layout = CensusLayout(
        names[0], axes[0], start_arr, settings.max_points, system.state_names,
        stop == "converged", *((names[1], axes[1]) if plane else ()),
    )  # fmt: skip
    # the cells in C order: one row of parameter values each
    cells = np.stack([g.reshape(-1) for g in np.meshgrid(*axes, indexing="ij")], axis=-1)
    opts = RunOptions(threads, backend, scheduler, n_workers, progress, chunk_size)
    mem = run_pairs(
        system, names, cells, start_arr, settings, (out, config, layout, title, notes), opts,
        _desc or f"census {' x '.join(names)}",
    )  # fmt: skip
    if out is not None:
        return load_census(
            out, identity_tol=identity_tol, track_threshold=track_threshold, _write=True
        )
    return _classified(
        system, names, axes, start_arr, mem, settings.to_dict(), identity_tol, track_threshold
    )


census.__doc__ = _CENSUS_DOC


def _classified(
    system, names, axes, starts, data, settings, identity_tol, track_threshold, path=None
) -> CensusResult | CensusPlaneResult:
    """The result of a census from its runs (``data``: runs in (n_cells, n_starts) order)."""
    if len(names) == 2:
        labels, attractors, tracks = classify_plane(
            (len(axes[0]), len(axes[1])), data, period_tol=settings["period_tol"],
            identity_tol=identity_tol, track_threshold=track_threshold,
        )  # fmt: skip
        return CensusPlaneResult.from_runs(
            names, axes, starts, labels, attractors, tracks, data, system, settings, path
        )
    labels, attractors, tracks = classify_census(
        axes[0], data, period_tol=settings["period_tol"], identity_tol=identity_tol,
        track_threshold=track_threshold,
    )  # fmt: skip
    return CensusResult(
        param=names[0], values=axes[0], starts=starts, labels=labels,
        status_code=data["status"], period=data["period"], attractors=attractors,
        tracks=tracks, state_names=system.state_names, system=system, settings=settings,
        path=path, raw=data,
    )  # fmt: skip


def _check_census_args(
    system, param, values, stop, backend, scheduler, n_workers, track_threshold, identity_tol
) -> tuple[tuple[str, ...], tuple[np.ndarray, ...]]:
    """Check :func:`census`'s arguments other than the starts and settings; names and values."""
    from .sweep import _normalise_params

    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    if isinstance(param, (tuple, list)) and len(param) == 2:
        if not isinstance(values, (tuple, list)) or len(values) != 2 or 0 in map(np.ndim, values):
            raise ValueError(
                f"values of a census over two params must be a pair of arrays, one per param "
                f"({', '.join(map(repr, param))}), got {plain(values)}"
            )
        names, axes = _normalise_params(system, param, values)  # as a 2-D sweep
    else:
        names, axes = (param,), (_check_values(system, param, values),)
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
    return names, axes


def _check_values(system, param, values) -> np.ndarray:
    """The values of a one-parameter census, checked."""
    if not isinstance(param, str) or param not in SWEEPABLE:
        raise ValueError(
            f"param must be one of {list(SWEEPABLE)} or a tuple of two of them, got {param!r}"
        )
    vals = np.asarray(values, dtype=float)
    if vals.ndim != 1 or vals.size == 0 or not np.all(np.isfinite(vals)):
        raise ValueError("values must be a non-empty 1-D array of finite numbers")
    for v in np.unique(vals):
        try:
            system.replace(**{param: float(v)})
        except ValueError as exc:
            raise ValueError(f"value {plain(v)} of param {param!r} is invalid: {exc}") from None
    return vals


def _census_config(system, names, axes, start_arr, stop, settings, backend) -> dict:
    """Everything that determines a census's results (stored in its file, and hashed)."""
    base = system.to_dict()
    for name in names:
        base[name] = None
    plane = len(names) == 2
    config = {
        "kind": "census",
        "system": base,
        "param": list(names) if plane else names[0],
        "n_values": [int(a.size) for a in axes] if plane else int(axes[0].size),
        "values_sha256": [_values_digest(a) for a in axes] if plane else _values_digest(axes[0]),
        "n_starts": len(start_arr),
        "starts_sha256": _values_digest(start_arr),
        "stop": stop,
        "settings": settings.to_dict(),
    }
    if backend == "cuda":  # GPU points differ from the CPU's at ~1e-9: never mixed in a file
        config["backend"] = "cuda"
    return config


#: The per-run arrays of a census file (what a plane's loader reshapes into cells).
_RUN_KEYS = ("done", "points", "final_state", "label", "t_converged", *CENSUS_RUN_FIELDS)


def load_census(
    path: str | Path,
    *,
    identity_tol: float | None = None,
    track_threshold: float | None = None,
    _write: bool = False,
) -> CensusResult | CensusPlaneResult:
    """Open a census file as a :class:`CensusResult` (classified from its runs).

    A census over a plane opens as a :class:`CensusPlaneResult`.

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
    names = (data["param"], data["param2"]) if "param2" in data else (data["param"],)
    axes = (data["values"], data["values2"]) if "param2" in data else (data["values"],)
    for name, vals in zip(names, axes):
        sysd[name] = float(vals[0])
    system = System.from_dict(sysd)
    settings = cfg["settings"]
    runs = data
    if len(names) == 2:  # the runs in (n_cells, n_starts) order, as the census computes them
        runs = {k: data[k].reshape((-1,) + data[k].shape[2:]) for k in _RUN_KEYS if k in data}
    res = _classified(
        system, names, axes, data["starts"], runs, settings, identity_tol, track_threshold,
        path=Path(path),
    )  # fmt: skip
    tol = IDENTITY_FACTOR * settings["period_tol"] if identity_tol is None else identity_tol
    if _write and bool(np.all(data["done"])):
        plane = len(names) == 2
        write_census_classification(
            path, res.labels, res.attractors, res.tracks, KINDS,
            {"identity_tol": tol, "track_threshold": track_threshold},
            track_columns=plane_track_columns(res.tracks) if plane else None,
        )  # fmt: skip
    return res
