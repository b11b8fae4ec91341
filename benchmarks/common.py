"""Shared helpers of the benchmark suite: machine info, timing, the sweep entry point."""

from __future__ import annotations

import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # benchmark this checkout, not an installed copy
    sys.path.insert(0, str(ROOT))

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast.simulate import DEFAULT_EQUILIBRIUM_TOL, MAX_PERIOD, resolve_settings  # noqa: E402
from stickslip_fast.system import PARAM_INDEX  # noqa: E402
from stickslip_fast.trajectory import METHODS, sweep_chunk  # noqa: E402

STATUS = np.array(ssf.STATUS_NAMES + ("not-run",))


def cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def machine_info() -> dict:
    import numba
    import scipy

    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:
        cores = os.cpu_count()
    info = dict(
        cpu_model=cpu_model(),
        cores=cores,
        os_cpu_count=os.cpu_count(),
        python=platform.python_version(),
        platform=platform.platform(),
        numpy=np.__version__,
        numba=numba.__version__,
        scipy=scipy.__version__,
        stickslip_fast_file=ssf.__file__,
        numba_num_threads=numba.config.NUMBA_NUM_THREADS,
        loadavg_at_start=list(os.getloadavg()),
    )
    try:
        import psutil

        info["memory_total_gb"] = round(psutil.virtual_memory().total / 2**30, 1)
    except ImportError:
        pass
    try:
        from importlib.metadata import version

        import numbalsoda  # noqa: F401

        info["numbalsoda"] = version("numbalsoda")
    except Exception:  # noqa: BLE001 - optional
        info["numbalsoda"] = None
    return info


def best_time(fn, max_repeats: int = 3, budget: float = 1.0):
    """Call fn() up to max_repeats times (stopping once budget seconds are spent).

    Returns (minimum wall time, result of the last call).
    """
    best = np.inf
    spent = 0.0
    res = None
    for _ in range(max_repeats):
        t0 = time.perf_counter()
        res = fn()
        dt = time.perf_counter() - t0
        best = min(best, dt)
        spent += dt
        if spent > budget:
            break
    return best, res


class StandinSweepResult:
    """The fields of the planned ``ssf.SweepResult`` that the benchmarks read."""

    def __init__(self, values, out):
        points, t_points, count, period, status, n_steps, n_rejected, n_crossings, final = out
        self.values = values
        self.points = points
        self.t_points = t_points
        self.count = count
        self.period = period
        self.status = STATUS[status]
        self.n_steps = n_steps
        self.n_rejected = n_rejected
        self.n_crossings = n_crossings
        self.final_state = final


def sweep_standin(
    system,
    param,
    values,
    *,
    t_end,
    t_transient=0.0,
    threads=None,
    chunk_size=None,
    out=None,
    progress=False,
    method="rodas5p",
    rtol=None,
    atol=None,
    max_points=256,
):
    """Stand-in for ``ssf.sweep`` (same call shape) on the compiled ``sweep_chunk`` kernel."""
    import numba

    if out is not None:
        raise NotImplementedError("the stand-in sweep cannot write files (needs ssf.sweep)")
    s = resolve_settings(
        method, t_end, t_transient, rtol, atol, None, max_points, None,
        DEFAULT_EQUILIBRIUM_TOL, None,
    )  # fmt: skip
    values = np.asarray(values, dtype=float)
    params = np.tile(system.to_array(), (values.size, 1))
    params[:, PARAM_INDEX[param]] = values
    y0s = np.zeros((values.size, system.n_state))
    old = numba.get_num_threads()
    if threads is not None:
        numba.set_num_threads(threads)
    try:
        res = sweep_chunk(
            METHODS.index(method), y0s, params, system.n_oscillators, system.is_dc_motor,
            s["t_end"], s["t_transient"], s["rtol"], s["atol"], s["h"], s["max_steps"],
            s["equilibrium_tol"], s["period_tol"], MAX_PERIOD, s["max_points"],
        )  # fmt: skip
    finally:
        numba.set_num_threads(old)
    return StandinSweepResult(values, res)


# The one line to switch: the real API once it is on this branch, else the stand-in.
run_sweep = getattr(ssf, "sweep", None) or sweep_standin
SWEEP_IMPL = "stickslip_fast.sweep" if run_sweep is not sweep_standin else "standin:sweep_chunk"
