"""Multiple shooting with its segments on threads: wall time against one thread.

``python -m benchmarks.multishoot_threads [--threads 1 2] [--rounds 3]``. Each workload
runs with each thread count (``numba.set_num_threads``, which
``MultiShooting.segment_flows`` follows), the counts alternating round by round in one
process after a warm-up; it reports the median wall time per count, the ratio to one
thread, and whether every result is bit-identical to the one-thread result. Workloads:

* ``sb_walk``: the in-phase branch of two symmetric disks on a DC motor over
  eta in [4.762, 4.766] by multiple shooting, through its symmetry-breaking point (the
  start's mesh is refined to ~26 segments);
* ``fold_walk``: Fig. 6's period-1 branch (one disk) over eta in [2.0, 2.5] on 8 segments;
* ``find_orbit``: ``find_orbit(shooting="multiple", segments=16)`` at eta = 2.0.

Results go to ``benchmarks/results/multishoot_threads.json`` (``--out``).
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # benchmark this checkout, not an installed copy
    sys.path.insert(0, str(ROOT))

import numba  # noqa: E402
import numpy as np  # noqa: E402

import stickslip_fast as ssf  # noqa: E402


def _orbit(system: ssf.System) -> ssf.Orbit:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ssf.SynchronousStartWarning)
        run = ssf.simulate(system, 3000, 2000)
    return ssf.find_orbit(system, run)


def workloads() -> dict:
    """name -> a call returning the arrays to compare."""
    two = _orbit(ssf.System.preset("symmetric", drive="dc-motor", n_oscillators=2, eta=4.762))
    one = _orbit(ssf.System.preset("asymmetric", eta=2.0))

    def branch(b) -> list:
        return [b.values, b.points, b.multipliers, b.T, [(x.kind, x.value) for x in b.bifurcations]]

    return {
        "sb_walk": lambda: branch(ssf.continue_orbit(
            two, "eta", (4.762, 4.766), shooting="multiple", progress=False)),
        "fold_walk": lambda: branch(ssf.continue_orbit(
            one, "eta", (2.0, 2.5), shooting="multiple", segments=8, max_points=40,
            progress=False)),
        "find_orbit": lambda: [
            (o := ssf.find_orbit(one.system, one.points[0], shooting="multiple", segments=16)).T,
            o.points, o.multipliers],
    }  # fmt: skip


def _same(a, b) -> bool:
    if isinstance(a, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return bool(np.array_equal(a, b)) if isinstance(a, np.ndarray) else a == b


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks/results/multishoot_threads.json")
    args = ap.parse_args()
    calls = workloads()
    for fn in calls.values():  # compile and warm
        fn()
    times = {name: {t: [] for t in args.threads} for name in calls}
    same = {name: True for name in calls}
    for _ in range(args.rounds):
        for name, fn in calls.items():
            ref = None
            for t in args.threads:
                numba.set_num_threads(t)
                t0 = time.perf_counter()
                out = fn()
                times[name][t].append(time.perf_counter() - t0)
                if ref is None:
                    ref = out
                same[name] &= _same(ref, out)
    first = args.threads[0]
    report = {
        "machine": platform.processor() or platform.machine(),
        "cpus": numba.config.NUMBA_NUM_THREADS,
        "rounds": args.rounds,
        "results": {
            name: {
                "median_s": {t: statistics.median(v) for t, v in per.items()},
                "all_s": per,
                f"ratio_to_{first}_thread": {
                    t: statistics.median(per[first]) / statistics.median(v) for t, v in per.items()
                },
                "bit_identical": same[name],
            }
            for name, per in times.items()
        },
    }
    args.out.write_text(json.dumps(report, indent=1) + "\n")
    for name, r in report["results"].items():
        meds = ", ".join(f"{t}: {s:.2f} s" for t, s in r["median_s"].items())
        ratios = ", ".join(f"{t}: {x:.2f}x" for t, x in r[f"ratio_to_{first}_thread"].items())
        print(f"{name}: {meds} ({ratios}); bit-identical: {r['bit_identical']}")


if __name__ == "__main__":
    main()
