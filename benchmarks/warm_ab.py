"""Warm run times of two checkouts, side by side: the before/after of a change to the kernels.

Each checkout runs in fresh processes with its own Numba cache (compiled before the
timings), one thread, alternating checkout by checkout. Each process times, by its own
CPU time (``--clock wall``: wall time), best of ``--best`` calls:

- ``simulate`` with Rodas5P and with ``method="auto"``, asymmetric set, η = 2.0 and
  9.99, t_end 3000, points after 2000 (the README's call);
- two disks on a DC motor (η = 1.5, the first disk's x offset by 1e-3), t_end 3000;
- 32 desynchronised disks on a DC motor (``n_scaling``'s start), t_end 300;
- a 60-value Fig. 6 sweep (η 1 to 10), t_end 3000;
- ``find_orbit`` from a converged run at η = 2.0 (period 1) and 9.99 (period 2): the
  plain tangent path (Newton, multipliers), and ``continue_orbit`` from η = 2.0 to 2.3
  (at most 10 points): the tangents with the parameter sensitivity.

The report is the best over the processes per checkout, and the ratio of the last
checkout to the first. Usage::

    python -m benchmarks.warm_ab --root OLD --root NEW [--processes 3] [--clock wall] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from .common import ROOT, machine_info, write_result

RESULTS = Path(__file__).resolve().parent / "results"

_CHILD = r"""
import json, time, sys
import numba
import numpy as np
numba.set_num_threads(1)
import stickslip_fast as ssf

clock = time.perf_counter if sys.argv[2] == "wall" else time.process_time

def best(fn, n):
    fn()  # compiles (or loads) outside the timing
    b = float("inf")
    for _ in range(n):
        t = clock()
        fn()
        b = min(b, clock() - t)
    return b

n = int(sys.argv[1])
out = {}
for eta in (2.0, 9.99):
    s = ssf.System.preset("asymmetric", eta=eta)
    for m in ("rodas5p", "auto"):
        out[f"simulate {m} eta={eta}"] = best(lambda: ssf.simulate(s, 3000, 2000, method=m), n)
s2 = ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=2)
y2 = np.zeros(s2.n_state)
y2[0] = 1e-3
out["simulate rodas5p N=2 dc"] = best(lambda: ssf.simulate(s2, 3000, 2000, y0=y2), max(3, n // 2))
s32 = ssf.System.preset("asymmetric", drive="dc-motor", n_oscillators=32)
offs = np.random.default_rng(12345).uniform(-1e-3, 1e-3, (32, 4))
offs[:, [1, 3]] = 0.0
y32 = np.zeros(s32.n_state)
y32[:128] = offs.ravel()
out["simulate rodas5p N=32 dc offsets t300"] = best(
    lambda: ssf.simulate(s32, 300, 0.0, y0=y32, max_points=100), max(3, n // 3))
s6 = ssf.System.preset("asymmetric")
vals = np.linspace(1.0, 10.0, 60)
out["sweep fig6 60 values 1 thread"] = best(
    lambda: ssf.sweep(s6, "eta", vals, t_end=3000, t_transient=2000, progress=False), 3)
for eta in (2.0, 9.99):
    so = ssf.System.preset("asymmetric", eta=eta)
    conv = ssf.simulate(so, 20000, stop="converged")
    out[f"find_orbit eta={eta}"] = best(lambda: ssf.find_orbit(so, conv), max(3, n // 3))
    if eta == 2.0:
        orb = ssf.find_orbit(so, conv)
        out["continue_orbit eta 2.0-2.3"] = best(
            lambda: ssf.continue_orbit(orb, "eta", (2.0, 2.3), max_points=10), 3)
print(json.dumps(out))
"""


def run(roots: list[Path], processes: int, best: int, log=print, clock: str = "cpu") -> dict:
    """Best seconds (CPU, or ``clock="wall"``) per workload for each checkout, over
    ``processes`` fresh processes."""
    per_root: dict[str, list[dict]] = {str(r): [] for r in roots}
    with tempfile.TemporaryDirectory(prefix="ssf-warm-ab-") as tmp:
        for k in range(processes):
            for i, root in enumerate(roots):
                env = dict(os.environ, PYTHONPATH=str(root), NUMBA_NUM_THREADS="1",
                           NUMBA_CACHE_DIR=os.path.join(tmp, f"cache{i}"))  # fmt: skip
                proc = subprocess.run([sys.executable, "-W", "ignore", "-c", _CHILD, str(best), clock],
                                      env=env, cwd=root, capture_output=True, text=True)  # fmt: skip
                if proc.returncode != 0:
                    raise RuntimeError(f"{root} failed:\n{proc.stderr[-3000:]}")
                rec = json.loads(proc.stdout.strip().splitlines()[-1])
                per_root[str(root)].append(rec)
                log(f"  {root.name} #{k + 1}: " + ", ".join(f"{n} {v * 1e3:.1f} ms"
                                                          for n, v in rec.items()))  # fmt: skip
    bests = {r: {n: min(rec[n] for rec in recs) for n in recs[0]} for r, recs in per_root.items()}
    first, last = str(roots[0]), str(roots[-1])
    ratios = {n: bests[last][n] / bests[first][n] for n in bests[first]}
    return dict(roots=[str(r) for r in roots], processes=processes, best_of=best, clock=clock,
                runs=per_root, best=bests, ratio_last_over_first=ratios)  # fmt: skip


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", type=Path, action="append", help="a checkout (give two)")
    ap.add_argument("--processes", type=int, default=3, help="fresh processes per checkout")
    ap.add_argument("--best", type=int, default=15, help="calls per workload (best of)")
    ap.add_argument(
        "--clock",
        choices=("cpu", "wall"),
        default="cpu",
        help="time each call by the process's CPU time (default) or wall time",
    )
    ap.add_argument("--out", type=Path, default=RESULTS / "warm_ab.json")
    args = ap.parse_args(argv)
    roots = [r.resolve() for r in (args.root or [ROOT])]
    result = dict(machine=machine_info(), **run(roots, args.processes, args.best, clock=args.clock))
    for name, ratio in result["ratio_last_over_first"].items():
        print(f"  {name:40s} {ratio:.3f}")
    write_result(args.out, result, print)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
