"""Dask distributed backend for :func:`stickslip_fast.sweep` (the optional ``[dask]`` extra).

:func:`dask_runner` returns a runner with the contract of the local one,
``run(units, system, names, y0, settings) -> iterator of (unit, result)``: each
unit (or part of one) becomes a Dask task that calls the pure chunk functions
:func:`~stickslip_fast.backends.local.compute_restart_chunk` /
:func:`~stickslip_fast.backends.local.compute_continuation_chunk` unchanged, and the
results come back to the client, which alone writes the result file.

* Restart units are independent: a bounded window of them is kept in flight
  and results are handed back in completion order (``as_completed``).
* Continuation units are rounds: a round needs the final states of the
  previous one, which the unit iterator reads back from what the driver has
  written. So a round is pulled from the iterator only after the previous one
  has been handed back; within a round, chains are split across tasks
  (chains are independent, so the split does not change a single bit).
* Every task has a deterministic key (a hash of everything it computes from),
  and each unit is handed back once: a task that Dask re-runs after a worker
  died resolves the same future, and a key seen twice is dropped.
* A :class:`WarmUpPlugin` imports the package and loads (or compiles) the Numba
  kernels once per worker process, when the worker starts, so that tasks never
  pay for compilation.

This module imports without Dask; :func:`dask_runner` raises an ImportError
naming the extra to install when ``distributed`` is missing.
"""

from __future__ import annotations

import asyncio
import hashlib
import itertools
import json
import os
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from ..base.cache_guard import fingerprint
from ..core.settings import Settings
from ..core.sweep_kernels import run_lane
from ..model.system import System
from .local import compute_continuation_chunk, compute_restart_chunk

try:  # the plugin base class; a stand-in keeps this module importable without Dask
    from distributed import WorkerPlugin as _WorkerPluginBase
except ImportError:  # pragma: no cover - exercised only without the extra
    _WorkerPluginBase = object  # type: ignore[assignment,misc]

__all__ = [
    "INSTALL_HINT",
    "PLUGIN_NAME",
    "DEFAULT_CHUNK_SIZE",
    "WarmUpPlugin",
    "dask_runner",
    "fingerprint",
    "local_cluster",
    "prepare_client",
    "warm_up",
]

#: What to install for this backend (quoted in the ImportError).
INSTALL_HINT = 'pip install "stickslip_fast[dask]"'
#: Name under which the warm-up plugin is registered on the workers.
PLUGIN_NAME = "stickslip-fast-warmup"
#: Values per task when ``sweep(chunk_size=None)``: one task is then ~1-2 s of
#: work for typical figure sweeps, small enough to balance the load at the end
#: of a sweep and large enough that the ~ms per-task cost of Dask is negligible.
DEFAULT_CHUNK_SIZE = 8

#: Environment variable through which :func:`local_cluster` tells its workers
#: their Numba thread count (our own name: Numba never reads it, so setting it
#: cannot race with Numba's thread pool the way ``NUMBA_NUM_THREADS`` did).
THREADS_ENV = "STICKSLIP_FAST_NUMBA_THREADS"

#: Numba threads of each task in this worker process (None: Numba's default);
#: set by :class:`WarmUpPlugin`. Numba's thread count is per calling thread, so
#: the task sets it on the executor thread it runs in.
_task_threads: int | None = None


# ------------------------------------------------------------ worker side
def _set_task_threads() -> int:
    import numba

    if _task_threads is not None:
        numba.set_num_threads(min(_task_threads, numba.config.NUMBA_NUM_THREADS))
    return numba.get_num_threads()


def warm_up(numba_threads: int | None = None) -> dict[str, Any]:
    """Load (or compile) both sweep kernels by running each on a tiny problem.

    The call uses the same argument types as real sweeps, so no task compiles
    a new specialisation later. Called once per worker process by
    :class:`WarmUpPlugin`.

    Parameters
    ----------
    numba_threads : int, optional
        Numba threads for every later task in this process (default: the
        value :func:`local_cluster` put in ``STICKSLIP_FAST_NUMBA_THREADS``,
        else Numba's own, i.e. ``NUMBA_NUM_THREADS`` or all cores).

    Returns
    -------
    dict
        ``seconds`` (wall time of the warm-up), ``fingerprint``, ``pid``,
        ``numba_threads`` and ``overloads`` (compiled signatures per kernel).
    """
    global _task_threads
    t0 = time.perf_counter()

    if numba_threads is None and os.environ.get(THREADS_ENV):
        numba_threads = int(os.environ[THREADS_ENV])
    _task_threads = numba_threads
    threads = _set_task_threads()
    system = System.preset("asymmetric")
    settings = Settings.resolve("rodas5p", 1.0, 0.0, max_points=2)
    y0 = system.initial_state(None)
    compute_restart_chunk(system, ("eta",), np.array([[5.0]]), y0, settings)
    compute_continuation_chunk(system, ("eta",), np.array([[[5.0]]]), y0[None, :], y0, settings)
    return {
        "seconds": time.perf_counter() - t0,
        "fingerprint": fingerprint(),
        "pid": os.getpid(),
        "numba_threads": threads,
        "overloads": {"run_lane": len(run_lane.overloads)},
    }


class WarmUpPlugin(_WorkerPluginBase):
    """Worker plugin: import stickslip_fast and load its kernels when a worker starts.

    Registered by :func:`prepare_client`. It runs on every worker present at
    registration and on every worker that joins later (a restarted one too),
    before that worker executes tasks. The warm-up runs in a thread so the
    worker keeps answering the scheduler while Numba compiles (10-30 s when
    the machine has no cache yet; well under a second from the cache).

    Attributes
    ----------
    info : dict or None
        What :func:`warm_up` returned on this worker.
    """

    idempotent = True  # a second sweep on the same cluster does not warm up again
    name = PLUGIN_NAME

    def __init__(self, numba_threads: int | None = None) -> None:
        self.numba_threads = numba_threads
        self.info: dict[str, Any] | None = None

    async def setup(self, worker: Any) -> None:
        loop = asyncio.get_running_loop()
        self.info = await loop.run_in_executor(None, warm_up, self.numba_threads)


def _compute(
    kind: str,
    system: Any,
    names: tuple[str, ...],
    values: np.ndarray,
    y_starts: np.ndarray | None,
    y0: np.ndarray,
    settings: Settings,
    expected: str,
) -> dict[str, np.ndarray]:
    """The task: one (part of a) unit through the unchanged pure chunk function."""
    if fingerprint() != expected:
        raise RuntimeError(
            f"this worker (pid {os.getpid()}) runs stickslip_fast from "
            f"{Path(__file__).parents[1]} with different code or Numba version "
            f"than the client (fingerprint {fingerprint()[:12]} != {expected[:12]}); install "
            "the same stickslip_fast and numba versions on every machine"
        )
    _set_task_threads()
    if kind == "restart":
        return compute_restart_chunk(system, names, values, y0, settings)
    return compute_continuation_chunk(system, names, values, y_starts, y0, settings)


# ------------------------------------------------------------ client side
def _require_distributed() -> Any:
    try:
        import distributed
    except ImportError as exc:
        raise ImportError(
            f"backend='dask' needs Dask distributed, which is not installed ({exc}). "
            f"Install the optional extra: {INSTALL_HINT}"
        ) from exc
    return distributed


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _local_shape(n_workers: int | None) -> tuple[int, int]:
    """(workers, Numba threads per worker) of a local cluster on this machine."""
    cores = _cores()
    n = cores if n_workers is None else n_workers
    return n, max(1, cores // n)


def local_cluster(n_workers: int | None = None, **kwargs: Any) -> Any:
    """Start a ``LocalCluster`` of single-threaded worker processes on this machine.

    Each worker runs one task at a time (``threads_per_worker=1``) and its
    Numba kernels should use ``max(1, cores // n_workers)`` threads, so that
    workers x Numba threads does not exceed the cores: parallelism comes from
    Dask across workers, and within a task from Numba over the worker's share
    of the cores. Pass that count to :func:`prepare_client`, which makes every
    task use it (``numba.set_num_threads`` on the task's thread). The
    scheduler's HTTP server (and dashboard, with bokeh) takes a free port.

    The workers' ``NUMBA_NUM_THREADS`` is left alone on purpose. Numba re-reads
    it at every compilation and raises "Cannot set NUMBA_NUM_THREADS to a
    different value once the threads have been launched" when it differs from
    the value the thread pool was launched with. A spawned worker imports
    Numba (with the parent's environment) before Dask applies a cluster's
    ``env``, so setting it there raced with the warm-up's first compilation
    (about one two-worker cluster in six on a loaded 2-core machine). The
    pool keeps Numba's default size; the idle threads cost nothing. The share
    is passed instead in ``STICKSLIP_FAST_NUMBA_THREADS``, which only the
    warm-up reads, so a sweep given this cluster's address (rather than the
    cluster) still runs each task on its share.

    Parameters
    ----------
    n_workers : int, optional
        Worker processes (default: the number of cores).
    **kwargs
        Passed on to ``distributed.LocalCluster``.

    Returns
    -------
    distributed.LocalCluster
    """
    distributed = _require_distributed()
    n, threads = _local_shape(n_workers)
    options: dict[str, Any] = dict(
        n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0"
    )
    options.update(kwargs)
    options["env"] = {THREADS_ENV: str(threads), **dict(options.get("env") or {})}
    return distributed.LocalCluster(**options)


def prepare_client(client: Any, numba_threads: int | None = None) -> dict[str, dict[str, Any]]:
    """Register :class:`WarmUpPlugin` (once per cluster) and wait for its warm-up.

    Parameters
    ----------
    client : distributed.Client
    numba_threads : int, optional
        Numba threads per task on every worker (default: the share a
        :func:`local_cluster` gave its workers, else each worker's
        ``NUMBA_NUM_THREADS``, or all its cores). Ignored when the plugin is
        already registered on this cluster.

    Returns
    -------
    dict
        Per worker address, what :func:`warm_up` returned there (None for a
        worker that has not finished starting).
    """
    client.register_plugin(WarmUpPlugin(numba_threads), name=PLUGIN_NAME)

    def _info(dask_worker: Any) -> dict[str, Any] | None:
        plugin = dask_worker.plugins.get(PLUGIN_NAME)
        return getattr(plugin, "info", None)

    return client.run(_info)


def _task_key(kind: str, *parts: Any) -> str:
    """A deterministic Dask key: the same inputs always give the same key."""
    digest = hashlib.sha256(kind.encode())
    for part in parts:
        if isinstance(part, np.ndarray):
            digest.update(repr((part.dtype.str, part.shape)).encode())
            digest.update(np.ascontiguousarray(part).tobytes())
        else:
            digest.update(json.dumps(part, sort_keys=True, default=repr).encode())
        digest.update(b"\0")
    return f"stickslip-{kind}-{digest.hexdigest()[:32]}"


class _DaskRunner:
    """The callable :func:`dask_runner` returns (see there)."""

    default_chunk_size = DEFAULT_CHUNK_SIZE

    def __init__(self, scheduler: str | None, n_workers: int | None) -> None:
        self.scheduler = scheduler
        self.n_workers = n_workers
        #: after a run: per worker address, what its warm-up returned
        self.workers: dict[str, Any] = {}

    def __call__(
        self, units: Iterable[Any], system: Any, names: tuple[str, ...], y0: np.ndarray,
        settings: Settings,
    ) -> Iterator[tuple[Any, dict[str, np.ndarray]]]:  # fmt: skip
        distributed = _require_distributed()
        units = iter(units)
        first = next(units, None)
        if first is None:  # nothing left to do (e.g. a finished sweep resumed): no cluster
            return
        units = itertools.chain([first], units)
        cluster = None
        threads = None
        if self.scheduler is None:
            cluster = local_cluster(self.n_workers)
            address = cluster.scheduler_address
            threads = _local_shape(self.n_workers)[1]
        else:
            address = self.scheduler
        try:
            with distributed.Client(address, set_as_default=False) as client:
                self.workers = prepare_client(client, threads)
                yield from _Session(client, system, names, y0, settings).run(units)
        finally:
            if cluster is not None:
                cluster.close()


class _Session:
    """One sweep on one client: submission, collection, deduplication."""

    def __init__(self, client: Any, system: Any, names, y0, settings) -> None:
        self.client = client
        self.args = (system, tuple(names))
        self.y0 = np.asarray(y0, dtype=float)
        self.settings = settings
        self.expected = fingerprint()
        # everything a task computes from, except its values and start states
        self.context = (system.to_dict(), list(names), self.y0, settings.to_dict())
        self.handed_back: set[str] = set()
        self._threads = (0.0, 1)

    def threads(self) -> int:
        """Worker threads in the cluster (cached for a few seconds; at least 1)."""
        stamp, n = self._threads
        if time.monotonic() - stamp > 5.0:
            n = max(1, sum(self.client.nthreads().values()))
            self._threads = (time.monotonic(), n)
        return n

    def submit(self, kind: str, where: str, values: np.ndarray, y_starts: np.ndarray | None) -> Any:
        """Submit one task; ``where`` (the unit's grid targets) keeps equal values apart."""
        key = _task_key(
            kind, where, values, y_starts if y_starts is not None else "-", *self.context
        )
        return self.client.submit(
            _compute, kind, *self.args, values, y_starts, self.y0, self.settings, self.expected,
            key=key, retries=0,
        )  # fmt: skip

    def run(self, units: Iterable[Any]) -> Iterator[tuple[Any, dict[str, np.ndarray]]]:
        units = iter(units)
        first = next(units, None)
        if first is None:
            return
        if first.kind == "restart":
            yield from self._restart(first, units)
        else:
            yield from self._continuation(first, units)

    def _once(self, key: str) -> bool:
        """True the first time a unit key is handed back (never write a unit twice)."""
        if key in self.handed_back:
            return False
        self.handed_back.add(key)
        return True

    def _restart(self, first, units) -> Iterator[tuple[Any, dict[str, np.ndarray]]]:
        from distributed import as_completed

        pending: dict[Any, Any] = {}
        done = as_completed(loop=self.client.loop)
        source = itertools.chain([first], units)

        def top_up() -> None:
            while len(pending) < 4 * self.threads():
                unit = next(source, None)
                if unit is None:
                    return
                future = self.submit("restart", repr(unit.targets), unit.values, None)
                pending[future] = unit
                done.add(future)

        try:
            top_up()
            for future in done:
                unit = pending.pop(future)
                result = future.result()
                top_up()  # keep the workers busy while the client writes
                if self._once(future.key):
                    yield unit, result
                del future
        finally:
            if pending:
                self.client.cancel(list(pending))

    def _continuation(self, first, units) -> Iterator[tuple[Any, dict[str, np.ndarray]]]:
        unit = first
        while unit is not None:
            n_chains = len(unit.values)
            parts = np.array_split(np.arange(n_chains), min(n_chains, self.threads()))
            futures = [
                self.submit("continuation", repr(unit.targets[p[0] : p[-1] + 1]),
                            unit.values[p[0] : p[-1] + 1], unit.y_starts[p[0] : p[-1] + 1])
                for p in parts
            ]  # fmt: skip
            try:
                results = self.client.gather(futures)
            except BaseException:
                self.client.cancel(futures)
                raise
            merged = {
                name: np.concatenate([r[name] for r in results], axis=0) for name in results[0]
            }
            if self._once("+".join(f.key for f in futures)):
                yield unit, merged
            del futures, results
            # only now (after the driver wrote this round) may the next round read its starts
            unit = next(units, None)


def dask_runner(scheduler: str | None = None, n_workers: int | None = None) -> Callable:
    """A sweep runner that computes units on a Dask cluster.

    Parameters
    ----------
    scheduler : str, optional
        Address of a running scheduler (``"tcp://host:8786"``), whose workers
        are used as they are. Without it, a :func:`local_cluster` of
        ``n_workers`` processes is started for the sweep and closed after it.
    n_workers : int, optional
        Worker processes of that local cluster (default: the cores of this
        machine). Not allowed together with ``scheduler``.

    Returns
    -------
    callable
        ``run(units, system, names, y0, settings)`` -> iterator of
        ``(unit, result)``, the contract of :func:`stickslip_fast.backends.local.run_local`; results
        arrive in completion order, each unit exactly once. It has the
        attribute ``default_chunk_size`` (values per task when the sweep does
        not set ``chunk_size``) and, after a run, ``workers`` (what each
        worker's warm-up reported).

    Raises
    ------
    ImportError
        When Dask distributed is not installed (install ``stickslip_fast[dask]``).
    ValueError
        For a bad ``scheduler`` or ``n_workers``.
    """
    _require_distributed()
    if scheduler is not None:
        if not isinstance(scheduler, str) or not scheduler:
            raise ValueError(
                f"scheduler must be an address such as 'tcp://host:8786', got {scheduler!r}"
            )
        if n_workers is not None:
            raise ValueError(
                "n_workers starts a local cluster; with scheduler= the cluster's own workers "
                "are used (start them with `dask worker ADDRESS --nworkers N`)"
            )
    if n_workers is not None and (
        isinstance(n_workers, bool) or not isinstance(n_workers, int) or n_workers < 1
    ):
        raise ValueError(f"n_workers must be an integer >= 1, got {n_workers!r}")
    return _DaskRunner(scheduler, n_workers)
