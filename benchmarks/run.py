"""Benchmark suite of stickslip_fast. Usage: python benchmarks/run.py [--quick] [--out DIR]

Writes results.json (raw numbers and machine info), summary.md and PNG plots.
See benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import startup, sweeps, work_precision  # noqa: E402
from benchmarks.common import SWEEP_IMPL, machine_info  # noqa: E402
from benchmarks.summary import write_summary  # noqa: E402

SECTIONS = (
    "work_precision",
    "sweep_throughput",
    "parallel_scaling",
    "n_scaling",
    "startup",
    "memory",
)


def _clean(obj):
    """JSON-safe: numpy scalars to Python, inf/nan to strings."""
    import numpy as np

    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return str(obj)
    return obj


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes, < 2 minutes")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--only", nargs="*", choices=SECTIONS, help="run only these sections")
    args = ap.parse_args(argv)
    mode = "quick" if args.quick else "full"
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()

    def log(msg):
        print(f"[{time.perf_counter() - t_start:7.1f} s] {msg}", flush=True)

    results = dict(mode=mode, machine=machine_info(), sweep_impl=SWEEP_IMPL, sections={})
    want = set(args.only or SECTIONS)
    sec = results["sections"]
    if "startup" in want:  # first: its child processes compile into their own cache
        sec["startup"] = startup.run(mode, log)
    if "work_precision" in want:
        sec["work_precision"] = work_precision.run(mode, log)
        work_precision.plot(sec["work_precision"], out / "work_precision.png")
    if "sweep_throughput" in want:
        sec["sweep_throughput"] = sweeps.throughput(mode, log)
    if "parallel_scaling" in want:
        sec["parallel_scaling"] = sweeps.parallel_scaling(mode, log)
    if "n_scaling" in want:
        log("scaling in N (DC motor, 1 thread) ...")
        sec["n_scaling"] = sweeps.n_scaling(mode, log)
        sweeps.plot(sec, out / "n_scaling.png")
    if "memory" in want:
        sec["memory"] = sweeps.memory(mode, log)
    results["total_wall_s"] = time.perf_counter() - t_start
    import os

    results["machine"]["loadavg_at_end"] = list(os.getloadavg())
    results = _clean(results)
    (out / "results.json").write_text(json.dumps(results, indent=1))
    (out / "summary.md").write_text(write_summary(results))
    log(f"done in {results['total_wall_s']:.0f} s; wrote {out}/results.json, summary.md, PNGs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
