"""Cost of a basin map (issue 29): cells per second on the CPU, and on a GPU when there is one.

The map is the issue's: asymmetric set, constant belt, eta = 3.2, the (x1, phi1)
plane at rest over [-0.3, 0.3]^2, converged stopping with the cap t_end = 3000
(``stickslip_fast.basins``). A 4 x 4 map first compiles the kernels (not timed).

    python3 benchmarks/basins.py                    # 200 x 200 on the CPU (all cores)
    python3 benchmarks/basins.py --n 100            # a smaller map (extrapolate per cell)
    python3 benchmarks/basins.py --backend cuda --n 1000   # the GPU map of the issue

Cells of a map are independent runs, so the cost is linear in the number of
cells at a fixed box and value; a smaller map over the same box has the same
mix of short (steady sliding) and long (stick-slip, near-boundary) runs.
Results go to ``benchmarks/results/basins.json`` (appended, one JSON line per
run) and a line to stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import stickslip_fast as ssf  # noqa: E402
from benchmarks.common import cpu_model  # noqa: E402


def measure(n: int, backend: str, threads: int | None, eta: float, t_end: float) -> dict:
    """Time one n x n map (after a 4 x 4 warm-up map) and return the numbers."""
    system = ssf.System.preset("asymmetric", eta=eta)
    kw = dict(t_end=t_end, backend=backend, threads=threads, progress=False)
    g4 = np.linspace(-0.3, 0.3, 4)
    ssf.basins(system, (g4, g4), **kw)  # compile (and, on a GPU, load the module)
    g = np.linspace(-0.3, 0.3, n)
    t0 = time.perf_counter()
    res = ssf.basins(system, (g, g), **kw)
    wall = time.perf_counter() - t0
    steps = int(res.census.raw["n_steps"].sum())
    return {
        "n": n,
        "cells": n * n,
        "backend": backend,
        "threads": threads or os.cpu_count(),
        "eta": eta,
        "t_end": t_end,
        "wall_s": wall,
        "cells_per_s": n * n / wall,
        "steps": steps,
        "projected_200x200_s": 40000 / (n * n / wall),
        "fractions": {str(k): v for k, v in res.fractions().items()},
        "machine": f"{cpu_model()}, {os.cpu_count()} cores",
        "load_average": os.getloadavg()[0],
        "time": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--n", type=int, default=200, help="cells per side (default 200)")
    p.add_argument("--backend", choices=("local", "cuda"), default="local")
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--eta", type=float, default=3.2)
    p.add_argument("--t-end", type=float, default=3000.0)
    p.add_argument("--no-save", action="store_true", help="do not append to results/")
    args = p.parse_args(argv)
    if args.backend == "cuda":
        try:
            from numba import cuda

            if not cuda.is_available():
                raise RuntimeError
        except (ImportError, RuntimeError):
            print("no CUDA GPU here: run with --backend local", file=sys.stderr)
            return 2
    r = measure(args.n, args.backend, args.threads, args.eta, args.t_end)
    print(
        f"basins {r['n']}x{r['n']} ({r['backend']}, {r['threads']} threads, load "
        f"{r['load_average']:.1f}): {r['wall_s']:.1f} s, {r['cells_per_s']:.1f} cells/s, "
        f"200x200 projected {r['projected_200x200_s']:.0f} s; {r['machine']}"
    )
    if not args.no_save:
        out = ROOT / "benchmarks" / "results" / "basins.json"
        with open(out, "a") as fh:
            fh.write(json.dumps(r) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
