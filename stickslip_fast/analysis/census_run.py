"""The runs of a census: (cell, start) pairs cut into units, handed to a backend, stored.

Shared by the census over one parameter and over a plane of two
(:func:`stickslip_fast.analysis.census.census`): both see their values as a
list of *cells*, each a row of parameter values (one per swept field), and run
every start at every cell. Each pair is a chain of length one through the
sweep's continuation chunk function
(:func:`stickslip_fast.backends.local.compute_continuation_chunk`), so a run is
bit-identical whatever the backend, thread count or chunk size.
"""

from __future__ import annotations

import contextlib
import hashlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..base.messages import plain
from ..base.terminal import show_progress
from ..core.settings import Settings
from ..io import CensusFile, CensusLayout
from ..model.system import System


@dataclass
class _Unit:
    """A unit of work in the contract of the sweep runners: length-1 chains."""

    kind: str
    values: np.ndarray  # (C, 1, k)
    targets: list  # flat pair indices, one per chain
    y_starts: np.ndarray  # (C, n_state)
    axis: int = 0


@dataclass
class RunOptions:
    """How a census's runs are scheduled (none of it changes the results)."""

    threads: int | None = None
    backend: str = "local"
    scheduler: str | None = None
    n_workers: int | None = None
    progress: bool | None = None
    chunk_size: int | None = None


def _units(
    cells: np.ndarray, starts: np.ndarray, done: np.ndarray, chunk: int, nthreads: int
) -> Iterator[_Unit]:
    """Units of ``chunk`` pairs not yet ``done``; ``cells`` is (n_cells, k)."""
    n_s = len(starts)
    todo = np.flatnonzero(~done.reshape(-1))
    for a in range(0, todo.size, chunk):
        flat = todo[a : a + chunk]
        # interleave over the threads: each thread's share of the unit's lanes then
        # comes from the whole unit (costs vary smoothly with the value)
        flat = np.concatenate([flat[t::nthreads] for t in range(nthreads)])
        vi, si = np.divmod(flat, n_s)
        yield _Unit(
            "continuation", cells[vi][:, None, :], [int(f) for f in flat],
            np.ascontiguousarray(starts[si]),
        )  # fmt: skip


def _values_digest(a: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(a, dtype="<f8").tobytes()).hexdigest()


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
    show = show_progress(progress)
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


def run_pairs(
    system: System,
    names: tuple[str, ...],
    cells: np.ndarray,
    starts: np.ndarray,
    settings: Settings,
    file_spec: tuple[str | Path | None, dict, CensusLayout, str, str],
    opts: RunOptions,
    desc: str,
) -> dict[str, np.ndarray] | None:
    """Run every start at every cell not done yet; the in-memory runs, or None with a file.

    ``file_spec`` is (out, config, layout, title, notes): with ``out`` the runs
    stream into that census file (resuming it; a different configuration is
    refused); without, they are returned as arrays of shape (n_cells, n_starts, ...).
    """
    from ..base.version import package_version
    from .sweep import _numba_threads

    out, config, layout, title, notes = file_spec
    y0 = system.initial_state(None)
    n_c, n_s = len(cells), len(starts)
    runner = _census_runner(opts.backend, opts.scheduler, opts.n_workers, system, settings)
    mem = None
    with contextlib.ExitStack() as stack:
        nthreads = stack.enter_context(_numba_threads(opts.threads))
        chunk_size = _census_chunk_size(opts.chunk_size, opts.backend, runner, nthreads)
        if out is not None:
            file = stack.enter_context(
                CensusFile.open(
                    out, config, layout, title=title, notes=notes, package_version=package_version()
                )
            )
            done = file.done_mask().reshape(n_c, n_s)
        else:
            file = None
            done = np.zeros((n_c, n_s), dtype=bool)
            mem = CensusFile.empty_arrays(layout)
        bar = _census_bar(stack, opts.progress, done, desc)
        units = _units(cells, starts, done, chunk_size, nthreads)
        results = stack.enter_context(
            contextlib.closing(runner(units, system, names, y0, settings))
        )
        for unit, res in results:
            n_written = _store_unit(unit, res, file, mem, n_s)
            if bar is not None:
                bar.update(n_written)
    return mem
