"""Independent integrations on threads: wall time against one thread.

``python -m benchmarks.threads [--threads 1 2] [--rounds 3]``. Each workload
runs with each thread count (``numba.set_num_threads``, which
``MultiShooting.segment_flows`` and ``base.threads.run_concurrently`` follow), the counts
alternating round by round in one
process after a warm-up; it reports the median wall time per count, the ratio to one
thread, and whether every result is bit-identical to the one-thread result. Workloads:

* ``sb_walk``: the in-phase branch of two symmetric disks on a DC motor over
  eta in [4.762, 4.766] by multiple shooting, through its symmetry-breaking point (the
  start's mesh is refined to ~26 segments);
* ``fold_walk``: Fig. 6's period-1 branch (one disk) over eta in [2.0, 2.5] on 8 segments;
* ``find_orbit``: ``find_orbit(shooting="multiple", segments=16)`` at eta = 2.0;
* ``fold_curve``: the upper fold of Fig. 6's period-1 branch at k12 = -0.8 followed in
  k12 (``continue_bifurcation``, 12 points; each step's return maps side by side);
* ``pd_curve``: the period-doubling of Fig. 6's period-2 orbit at eta = 5.04295 followed
  in k12 (8 points).

Results go to ``benchmarks/results/threads.json`` (``--out``).
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

# the stable period-1 orbit at eta = 3.3, k12 = -0.8 (benchmarks/foldcurve.py)
Z33 = np.array([0.07332092304307371, 0.0, 0.12221581726865255, -0.00674109106906407])
# a point of Fig. 6's period-2 orbit near its period-doubling (tests/test_foldcurve_orbit.py)
P2_ETA = 5.043198103554579
P2_POINT = np.array([0.027234629670059556, 0.0, 0.12785148813700828, -0.0038733936156032087])


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

    s33 = ssf.System.preset("asymmetric", eta=3.30, k12=-0.8)
    o33 = ssf.find_orbit(s33, Z33, 1)
    b33 = ssf.continue_orbit(o33, "eta", (3.30, 3.35), ds=2e-3, ds_max=5e-3, max_points=100,
                             stick_events=False, progress=False)  # fmt: skip
    fold = next(b for b in b33.bifurcations if b.kind == "fold")
    s5 = ssf.System.preset("asymmetric", eta=P2_ETA, k12=-0.8)
    b5 = ssf.continue_orbit(ssf.find_orbit(s5, P2_POINT, period=2), "eta", (5.0428, 5.0433),
                            ds=2e-5, ds_min=1e-9, ds_max=4e-5, max_points=8, direction=-1,
                            progress=False)  # fmt: skip
    pd = next(b for b in b5.bifurcations if b.kind == "period-doubling")

    def curve(c) -> list:
        return [c.values, c.points, c.multipliers]

    return {
        "fold_curve": lambda: curve(ssf.continue_bifurcation(
            b33, fold, "k12", (-0.95, -0.79), direction=-1, max_points=12,
            stick_events=False)),
        "pd_curve": lambda: curve(ssf.continue_bifurcation(
            b5, pd, "k12", (-0.806, -0.79), direction=-1, ds=0.002, ds_max=0.005,
            max_points=8, stick_events=False)),
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
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks/results/threads.json")
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
