"""Cost of a census over a plane (issue 28): cells per second on the CPU, and on a GPU.

The plane is that of data/maps/census_plane_eta_k12.toml: asymmetric set,
constant belt, eta in [1, 6] x k12 in [-0.95, -0.55], 16 starts per cell
(the zero state and 15 seeded starts in the default box), converged stopping
with the cap t_end = 3000. A 2 x 2 plane first compiles the kernels (not timed).

    python3 benchmarks/census_plane.py                   # 20 x 20 cells x 16 starts (CPU)
    python3 benchmarks/census_plane.py --n 100           # the issue's 100 x 100 x 16
    python3 benchmarks/census_plane.py --backend cuda --n 100

Every (cell, start) pair is an independent run, so the cost is linear in the
number of cells for a grid over the same rectangle (a coarser grid samples the
same mix of sliding and stick-slip runs); ``projected_100x100_s`` extrapolates.
The classification (grouping and tracking, in Python) is timed separately.
Results go to ``benchmarks/results/census_plane.json`` (appended, one JSON
line per run) and a line to stdout.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import stickslip_fast as ssf  # noqa: E402
from benchmarks.common import add_device_options, append_result, cpu_model  # noqa: E402
from stickslip_fast.analysis.census_plane import classify_plane  # noqa: E402

PARAMS = ("eta", "k12")


def axes(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.linspace(1.0, 6.0, n), np.linspace(-0.95, -0.55, n)


def measure(n: int, n_starts: int, backend: str, threads: int | None, t_end: float) -> dict:
    """Time one n x n plane (after a 2 x 2 warm-up plane) and return the numbers."""
    system = ssf.System.preset("asymmetric")
    kw = dict(t_end=t_end, t_transient=2000.0, max_points=128, n_starts=n_starts,
              backend=backend, threads=threads, progress=False)  # fmt: skip
    ssf.census(system, PARAMS, axes(2), **kw)  # compile (and, on a GPU, load the module)
    t0 = time.perf_counter()
    res = ssf.census(system, PARAMS, axes(n), **kw)
    wall = time.perf_counter() - t0
    runs = {k: v.reshape((n * n,) + v.shape[2:]) for k, v in res.raw.items()}
    t1 = time.perf_counter()
    classify_plane((n, n), runs, period_tol=res.settings["period_tol"])
    classify_s = time.perf_counter() - t1
    cells = n * n
    return {
        "n": n,
        "cells": cells,
        "n_starts": n_starts,
        "backend": backend,
        "threads": threads or os.cpu_count(),
        "t_end": t_end,
        "wall_s": wall,
        "classify_s": classify_s,
        "cells_per_s": cells / wall,
        "runs_per_s": cells * n_starts / wall,
        "steps": int(res.raw["n_steps"].sum()),
        "projected_100x100_s": 10000 / (cells / wall),
        "tracks": len(res.tracks),
        "machine": f"{cpu_model()}, {os.cpu_count()} cores",
        "load_average": os.getloadavg()[0],
        "time": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--n", type=int, default=20, help="cells per side (default 20)")
    p.add_argument("--starts", type=int, default=16, help="starts per cell (default 16)")
    add_device_options(p)
    args = p.parse_args(argv)
    r = measure(args.n, args.starts, args.backend, args.threads, args.t_end)
    print(
        f"census plane {r['n']}x{r['n']}x{r['n_starts']} ({r['backend']}, {r['threads']} threads, "
        f"load {r['load_average']:.1f}): {r['wall_s']:.1f} s, {r['cells_per_s']:.1f} cells/s "
        f"({r['runs_per_s']:.0f} runs/s), classification {r['classify_s']:.2f} s, "
        f"100x100 projected {r['projected_100x100_s']:.0f} s; {r['machine']}"
    )
    append_result("census_plane", r, args.no_save)
    return 0


if __name__ == "__main__":
    sys.exit(main())
