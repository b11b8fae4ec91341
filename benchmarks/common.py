"""Shared helpers of the benchmark suite: machine info, timing, the sweep entry point."""

from __future__ import annotations

import json
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


def _git_commit() -> str | None:
    """HEAD of the checkout being benchmarked (with '+dirty' if it has local changes)."""
    import subprocess

    try:
        head = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=ROOT, capture_output=True, text=True,
        ).stdout.strip()  # fmt: skip
    except OSError:
        return None
    return (head + ("+dirty" if dirty else "")) or None


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
        git_commit=_git_commit(),
    )
    try:
        import psutil

        info["memory_total_gb"] = round(psutil.virtual_memory().total / 2**30, 1)
    except ImportError:
        pass
    from importlib.metadata import PackageNotFoundError, version

    # the peers' versions (None: not installed, so that peer was not run)
    for dist in ("numbalsoda", "scikit-sundae", "diffrax", "jax"):
        try:
            info[dist] = version(dist)
        except PackageNotFoundError:
            info[dist] = None
    return info


def write_result(path: Path, result: dict, log=print) -> None:
    """Write one benchmark's result record as JSON (the folders made) and say where."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result, indent=1, default=float))
    log(f"wrote {path}")


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


def desynchronised_start(n: int):
    """``n_scaling``'s start: N disks of the asymmetric set on one DC motor, x_i and phi_i
    offset uniformly in +-1e-3 (seed 12345), velocities and v_b zero. Returns (system, y0)."""
    system = ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=n)
    y0 = np.zeros(system.n_state)
    offs = np.random.default_rng(12345).uniform(-1e-3, 1e-3, size=(n, 4))
    offs[:, [1, 3]] *= 0.0  # offsets in the positions x_i, phi_i only
    y0[: 4 * n] = offs.ravel()
    return system, y0


run_sweep = ssf.sweep
SWEEP_IMPL = "stickslip_fast.analysis.sweep"


def add_device_options(parser, t_end: float = 3000.0) -> None:
    """The options of the standalone map benchmarks: backend, threads, t_end, --no-save."""
    parser.add_argument("--backend", choices=("local", "cuda"), default="local")
    parser.add_argument("--threads", type=int, default=None)
    parser.add_argument("--t-end", type=float, default=t_end)
    parser.add_argument("--no-save", action="store_true", help="do not append to results/")


def append_result(name: str, record: dict, no_save: bool = False) -> None:
    """Append one JSON line to ``benchmarks/results/<name>.json`` (unless ``no_save``)."""
    import json

    if not no_save:
        with open(ROOT / "benchmarks" / "results" / f"{name}.json", "a") as fh:
            fh.write(json.dumps(record) + "\n")
