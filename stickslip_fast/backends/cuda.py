"""CUDA backend for :func:`stickslip_fast.sweep` and :func:`stickslip_fast.census`.

Each GPU thread integrates trajectories one after another, taken from a queue; the kernels are in :mod:`stickslip_fast.backends.cuda_kernels`,
this module schedules their launches. Imported only when ``backend="cuda"`` is
asked for (the optional ``[cuda]`` extra, numba-cuda); nothing else in the
package imports CUDA.

Launches
--------
Units of work (restart chunks, or a census's one-value chains with a start
each) go to the GPU up to ``MAX_IN_FLIGHT`` launches at a time, each on its
own stream, and come back in completion order; the writers place every value
by its index. What the kernels do not cover runs on the CPU kernels with a
warning: continuation chains, N > MAX_OSCILLATORS, methods other than Rodas5P.

Agreement with the CPU backend
------------------------------
Status and period equal the CPU's; Poincare points agree to ~1e-9 but are not
bit-identical: the GPU compiler contracts ``a * b + c`` into fused
multiply-adds, which round differently. A file is therefore all-CPU or
all-GPU: ``backend="cuda"`` is part of a sweep's configuration, so resuming a
local file with the GPU (or the other way round) is refused.
"""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Iterator

import numpy as np
from numba import njit

from ..model.params import P_ETA, P_ETAP, eta_prime

# cuda_device raises the ImportError that names the [cuda] extra before numba.cuda is used
from .cuda_device import float64, int64, types
from .cuda_kernels import (
    MAX_OSCILLATORS,
    check_available,
    cuda,
    get_kernel,
    simulator_enabled,
)

__all__ = [
    "MAX_OSCILLATORS",
    "DEFAULT_CHUNK_SIZE",
    "MAX_IN_FLIGHT",
    "THREADS_PER_BLOCK",
    "check_available",
    "compile_ptx",
    "compute_restart_chunk_cuda",
    "cuda_runner",
    "default_chunk_size",
    "device_summary",
    "max_threads",
    "get_kernel",
    "kernel_signature",
    "simulator_enabled",
]

#: Values per unit of work (one kernel launch) when ``sweep(chunk_size=None)``,
#: at most (see :func:`default_chunk_size`).
DEFAULT_CHUNK_SIZE = 262144
#: Device memory for one launch's outputs, at most.
CHUNK_BYTES = 1 << 29
#: Launches queued on the GPU at once (each on its own stream).
MAX_IN_FLIGHT = 6
#: Threads per block (results do not depend on it); see docs/gpu.md.
THREADS_PER_BLOCK = 64
#: Threads per multiprocessor a launch starts, at most: about what the kernel's
#: ~200 registers per thread leave resident (results do not depend on it).
THREADS_PER_SM = 384
#: Runs per thread in a launch of the default size: a thread whose run ends takes
#: the next one from the launch's queue (results do not depend on it).
RUNS_PER_THREAD = 4
#: Threads a launch starts, at most, in numba's simulator (so tests exercise the queue).
SIMULATOR_THREADS = 8


# ------------------------------------------------------------------ launches
@njit(cache=True)
def _fill_etap(rows: np.ndarray) -> None:
    for k in range(rows.shape[0]):
        rows[k, P_ETAP] = eta_prime(rows[k, P_ETA])


def _rows_with_etap(rows: np.ndarray) -> np.ndarray:
    """Parameter rows with eta' computed on the host (the CPU kernel's own function)."""
    rows = np.ascontiguousarray(rows, dtype=np.float64).copy()
    _fill_etap(rows)
    return rows


class _Launch:
    """One kernel launch in flight on its own stream, with its outputs on the device.

    ``y0`` is one start (n,) for every value or one per value (L, n). The launch
    starts ``min(L, max_threads(threads_per_sm))`` threads (rounded up to whole
    blocks), which take the L runs from a queue (an atomic counter on the device).
    """

    def __init__(self, system, rows, y0, settings, max_period, threads_per_block,
                 max_registers=None, threads_per_sm=None):  # fmt: skip
        from ..core.trajectory import SWEEP_INT_FIELDS

        kernel = get_kernel(system.n_oscillators, system.is_dc_motor, max_registers)
        nv = rows.shape[0]
        y0 = np.atleast_2d(np.ascontiguousarray(y0, dtype=np.float64))
        n = int(y0.shape[1])
        mp = int(settings.max_points)
        converged = settings.stop == "converged"
        # converged stopping records from t = 0, as the CPU kernel
        t_transient = 0.0 if converged else float(settings.t_transient)
        self.stream = cuda.stream()
        s = self.stream
        d_params = cuda.to_device(_rows_with_etap(rows), stream=s)
        d_y0 = cuda.to_device(y0, stream=s)
        self.d_out = (
            cuda.device_array((nv, mp, n), np.float64, stream=s),
            cuda.device_array((nv, mp), np.float64, stream=s),
            cuda.device_array((nv, len(SWEEP_INT_FIELDS)), np.int64, stream=s),
            cuda.device_array(nv, np.float64, stream=s),
            cuda.device_array((nv, n), np.float64, stream=s),
        )
        self.d_queue = cuda.to_device(np.zeros(1, np.int64), stream=s)
        threads = min(nv, max_threads(threads_per_sm))
        threads_per_block = max(1, min(threads_per_block, threads))
        blocks = max(1, (threads + threads_per_block - 1) // threads_per_block)
        with warnings.catch_warnings():  # small launches are fine: no occupancy warning
            # (numba-cuda raises its own copy of NumbaPerformanceWarning: match the text)
            warnings.filterwarnings("ignore", message=r"(?s).*Grid size \d+ will likely")
            self._launch(kernel, blocks, threads_per_block, s, d_y0, d_params, settings,
                         t_transient, max_period, converged)  # fmt: skip
        self.sim = simulator_enabled()  # the simulator runs launches synchronously
        self.event = cuda.event() if self.sim else cuda.event(timing=False)
        self.event.record(stream=s)

    def _launch(self, kernel, blocks, tpb, s, d_y0, d_params, settings, t_transient,
                max_period, converged):  # fmt: skip
        kernel[blocks, tpb, s](
            d_y0, d_params, float(settings.t_end), t_transient,
            float(settings.rtol), float(settings.atol), float(settings.h),
            int(settings.max_steps), float(settings.equilibrium_tol),
            float(settings.period_tol), int(max_period), converged, float(settings.dwell),
            *self.d_out, self.d_queue,
        )  # fmt: skip

    def done(self) -> bool:
        """True once the kernel has finished (never blocks)."""
        return self.sim or bool(self.event.query())

    def result(self) -> tuple[np.ndarray, ...]:
        out = tuple(d.copy_to_host(stream=self.stream) for d in self.d_out)
        self.stream.synchronize()
        return out


def compute_restart_chunk_cuda(
    system, names, values: np.ndarray, y0: np.ndarray, settings: dict,
    threads_per_block: int = THREADS_PER_BLOCK, max_registers: int | None = None,
    threads_per_sm: int | None = None,
) -> dict[str, np.ndarray]:  # fmt: skip
    """Restart mode on the GPU: the contract of :func:`stickslip_fast.backends.local.compute_restart_chunk`.

    Parameters
    ----------
    system : System
    names : sequence of str
        The swept fields.
    values : ndarray, (L, len(names))
    y0 : ndarray, (n,) or (L, n)
        The initial state, or one per value (a census).
    settings : dict
        :class:`stickslip_fast.core.settings.Settings`; method "rodas5p", stop
        "fixed" or "converged".
    threads_per_block : int
        CUDA block size; results do not depend on it.
    max_registers : int, optional
        Register cap per thread (see :func:`get_kernel`); results do not depend on it.
    threads_per_sm : int, optional
        Threads started per multiprocessor, at most (default THREADS_PER_SM); each
        takes runs from the launch's queue. Results do not depend on it.

    Returns
    -------
    dict of ndarray
        As the CPU function: points, t_points, final_state and the per-value
        integer fields (and t_converged with converged stopping). Status and
        period equal the CPU's; points agree to ~1e-9.
    """
    from ..core.poincare import MAX_PERIOD
    from .local import _pack, _param_rows

    check_available()
    _check_supported(system, settings)
    rows = _param_rows(system, names, np.asarray(values, dtype=float))
    launch = _Launch(system, rows, y0, settings, MAX_PERIOD, threads_per_block, max_registers,
                     threads_per_sm)  # fmt: skip
    return _pack(launch.result(), settings)


def unsupported_reason(system, settings: dict) -> str | None:
    """Why a sweep cannot run on the CUDA kernels (None if it can)."""
    if system.n_oscillators > MAX_OSCILLATORS:
        return (
            f"the CUDA kernels are specialised for N <= {MAX_OSCILLATORS} disks "
            f"(this system has {system.n_oscillators})"
        )
    if settings.method != "rodas5p":
        return f"the CUDA kernels implement method 'rodas5p' only (asked: {settings.method!r})"
    return None


def _check_supported(system, settings) -> None:
    why = unsupported_reason(system, settings)
    if why is not None:
        raise ValueError(why)


def _add_chain_axis(res: dict) -> dict:
    """Restart-shaped results (L, ...) as those of L one-value chains (L, 1, ...)."""
    return {k: v[:, None, ...] for k, v in res.items()}


def _single_value_chains(unit) -> bool:
    return unit.kind == "continuation" and np.asarray(unit.values).shape[1] == 1


def cuda_runner(
    system, settings: dict, mode: str, threads_per_block: int = THREADS_PER_BLOCK,
    max_in_flight: int = MAX_IN_FLIGHT, max_registers: int | None = None,
    threads_per_sm: int | None = None,
):  # fmt: skip
    """The runner for ``sweep(backend="cuda")``: the contract of :func:`chunks.run_local`.

    Restart units (and continuation units whose chains hold one value each,
    as a census makes: one start per value) run on the GPU, up to
    ``max_in_flight`` launches at a time, each on its own stream; results are
    handed back in completion order, so one launch's slowest thread does not
    hold back the next launches (the writers place every value by its index).
    What the kernels do not cover runs on the CPU kernels, with a warning that
    says so: continuation chains (sequential), N > MAX_OSCILLATORS, methods
    other than Rodas5P.

    Parameters
    ----------
    system, settings
        As for the sweep.
    mode : {"restart", "continuation", "census"}
        "census": continuation units of one-value chains, each from its own start.
    threads_per_block, max_in_flight, max_registers, threads_per_sm
        Launch shape (see :func:`compute_restart_chunk_cuda`); results do not depend on them.

    Raises
    ------
    RuntimeError
        Without a GPU (and without NUMBA_ENABLE_CUDASIM=1).
    """
    from ..core.poincare import MAX_PERIOD
    from .local import _pack, _param_rows, run_local

    check_available()
    why = unsupported_reason(system, settings)
    if why is None and mode not in ("restart", "census"):
        why = f"mode {mode!r} follows each chain value after value"
    if why is not None:
        warnings.warn(
            f"backend='cuda': {why}; this {'census' if mode == 'census' else 'sweep'} runs on "
            "the CPU (the local backend) instead",
            UserWarning,
            stacklevel=3,
        )

    def launch(unit, system, names, y0):
        values = np.asarray(unit.values, dtype=float)
        if unit.kind != "restart":  # one-value chains, each from its own start
            values, y0 = values[:, 0, :], unit.y_starts
        rows = _param_rows(system, names, values)
        return _Launch(system, rows, y0, settings, MAX_PERIOD, threads_per_block, max_registers,
                       threads_per_sm)  # fmt: skip

    def finish(unit, lau):
        res = _pack(lau.result(), settings)
        return res if unit.kind == "restart" else _add_chain_axis(res)

    def run(units, system, names, y0, settings_) -> Iterator[tuple]:
        if why is not None:
            yield from run_local(units, system, names, y0, settings_)
            return
        in_flight: list = []
        try:
            for unit in units:
                if unit.kind != "restart" and not _single_value_chains(unit):
                    raise ValueError("the CUDA runner takes restart units and one-value chains")
                in_flight.append((unit, launch(unit, system, names, y0)))
                while len(in_flight) >= max_in_flight:
                    yield _pop_first_done(in_flight, finish)
            while in_flight:
                yield _pop_first_done(in_flight, finish)
        finally:  # closed early (an error, Ctrl-C): leave no kernel running behind us
            for _, lau in in_flight:
                lau.stream.synchronize()

    if why is None:  # otherwise the CPU's default applies
        run.default_chunk_size = default_chunk_size(system, settings)
    return run


def _pop_first_done(in_flight: list, finish) -> tuple:
    """Wait for any launch in flight to finish; remove it and return (unit, result)."""
    while True:
        for k, (unit, lau) in enumerate(in_flight):
            if lau.done():
                del in_flight[k]
                return unit, finish(unit, lau)
        time.sleep(0.001)


def max_threads(threads_per_sm: int | None = None) -> int:
    """Threads one launch starts, at most: ``threads_per_sm`` (default THREADS_PER_SM)
    per multiprocessor of the current GPU; SIMULATOR_THREADS in the simulator."""
    if simulator_enabled():
        return SIMULATOR_THREADS
    per_sm = THREADS_PER_SM if threads_per_sm is None else int(threads_per_sm)
    return max(1, per_sm) * int(cuda.get_current_device().MULTIPROCESSOR_COUNT)


def default_chunk_size(system, settings: dict) -> int:
    """Values per launch: RUNS_PER_THREAD runs for each thread a launch starts.

    A launch starts about the threads the GPU keeps resident (:func:`max_threads`)
    and each takes runs from the launch's queue until it is empty, so a thread
    whose run ends early does not idle while its warp's other runs go on; with
    MAX_IN_FLIGHT launches queued, the next launch's blocks fill the
    multiprocessors that the last runs of a launch leave. At most what fits in
    CHUNK_BYTES of outputs; 64 in the simulator. Results do not depend on it.
    """
    if simulator_enabled():
        return 64
    fill = RUNS_PER_THREAD * max_threads()
    per_value = 8 * ((settings.max_points + 1) * (system.n_state + 1) + 6)
    return int(max(1024, min(DEFAULT_CHUNK_SIZE, fill, CHUNK_BYTES // per_value)))


def device_summary() -> dict:
    """Name, compute capability and multiprocessor count of the current GPU (for benchmarks)."""
    check_available()
    if simulator_enabled():
        return {"name": "numba CUDA simulator", "simulator": True}
    dev = cuda.get_current_device()
    name = dev.name.decode() if isinstance(dev.name, bytes) else str(dev.name)
    return {
        "name": name,
        "compute_capability": ".".join(map(str, dev.compute_capability)),
        "multiprocessors": int(dev.MULTIPROCESSOR_COUNT),
        "simulator": False,
        "env_cudasim": os.environ.get("NUMBA_ENABLE_CUDASIM", ""),
    }


def kernel_signature():
    """The argument types of the sweep kernels (as launched by the backend)."""
    a1, a2, a3, i2 = float64[::1], float64[:, ::1], float64[:, :, ::1], int64[:, ::1]
    f, i = float64, int64
    b = types.boolean
    return (a2, a2, f, f, f, f, f, i, f, f, i, b, f, a3, a2, i2, a1, a2, int64[::1])


def compile_ptx(n_osc: int, dc: bool, cc: tuple[int, int] = (9, 0)) -> str:
    """PTX of a sweep kernel for compute capability ``cc``, compiled without a GPU.

    Needs NVVM (``pip install "stickslip_fast[cuda]"`` brings it) but no driver:
    it checks that the kernels, and the model functions they call, compile for
    the real CUDA target, which the simulator cannot. numba-cuda asks the
    current device for its compute capability when it compiles a called
    function; that question is answered with ``cc`` for the duration.

    Parameters
    ----------
    n_osc, dc : int, bool
        As for :func:`get_kernel`.
    cc : (int, int)
        Target compute capability (default 9.0, Hopper).

    Returns
    -------
    str
        The PTX text (feed it to ``ptxas -v`` for registers per thread).
    """
    if simulator_enabled():
        raise RuntimeError("compile_ptx needs the real CUDA target, not NUMBA_ENABLE_CUDASIM=1")
    import types as _types
    from unittest import mock

    from numba.cuda import dispatcher

    kernel = get_kernel(n_osc, dc)
    fake = _types.SimpleNamespace(compute_capability=tuple(cc))
    with mock.patch.object(dispatcher, "get_current_device", lambda: fake):
        ptx, _ = cuda.compile_ptx(kernel.py_func, kernel_signature(), cc=tuple(cc))
    return ptx
