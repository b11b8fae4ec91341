"""Two step-size controllers on every sweep config in data/, each against a tight reference.

Issue 11 asks that any change of the engine's default method or tolerance come with
evidence that the diagrams do not change on the data/ configs. A controller changes
every result at the tolerance level, so this script measures, per config, on a grid of
``--num`` values (each config's own integration settings, mode and start):

- ``old``: the controller gains ``--old ALPHA BETA`` at the config's tolerances;
- ``new``: the gains ``--new ALPHA BETA`` at the same tolerances;
- ``ref``: the ``--old`` gains at ``--ref-rtol`` (atol = 0.01 rtol), the truth both are
  judged by; its periods are detected with the period tolerance of the runs under test.

A value agrees when status and period are equal and, for orbits, the last ``period``
points coincide up to a cyclic shift within ``--tol`` (the rule of
``compare_stop_rules.py``). Chaotic values (no period) agree on status and period alone.
The table gives old-vs-ref, new-vs-ref and old-vs-new agreement, and the total steps
(accepted + rejected) and wall time of the old and new diagrams (the times are only
comparable on a quiet machine; the steps are the machine-independent measure).

Numba freezes module constants into compiled code, so each run is a fresh process with
its own Numba cache directory and the gains set before anything compiles (as in
``benchmarks/controllers.py``).

Usage::

    python3 scripts/compare_controllers.py --old 0.7 0.4 --new 0.85 0.2 --num 100 \\
        --out docs/controller.md --csv docs/controller.csv

For a change of the code rather than of the gains, give the two checkouts instead
(each run imports ``stickslip_fast`` from its own root; the reference uses the old one)::

    python3 scripts/compare_controllers.py --old-root /path/to/main --new-root . \\
        --old 0.85 0.2 --new 0.85 0.2 --num 100 --out cmp.md
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from compare_stop_rules import agreement, sweep_configs  # noqa: E402


def _worker(alpha: float, beta: float, rtol: float | None, num: int, num_2d: int,
            only: str | None, out: Path) -> None:  # fmt: skip
    """In a fresh process: set the gains, run every sweep config, save the diagrams."""
    from stickslip_fast.core import steppers

    steppers.PI_ALPHA, steppers.PI_BETA = alpha, beta  # before any kernel compiles

    import stickslip_fast as ssf
    from stickslip_fast.core.settings import DEFAULT_RTOL, period_tolerance

    arrays: dict[str, np.ndarray] = {}
    for path, cfg, param, values, kw in sweep_configs(num, num_2d, only):
        if rtol is not None:
            # the period is judged as in the runs under test: the default period
            # tolerance scales with rtol and would call slowly contracting orbits aperiodic
            base = kw.get("rtol", DEFAULT_RTOL)
            kw.update(rtol=rtol, atol=0.01 * rtol, period_tol=period_tolerance(base))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            first = tuple(v[:1] for v in values) if isinstance(values, tuple) else values[:1]
            ssf.sweep(cfg.system, param, first, **dict(kw, t_end=10.0, t_transient=5.0))
            t0 = time.perf_counter()  # compiled above: outside the timing
            res = ssf.sweep(cfg.system, param, values, **kw)
            wall = time.perf_counter() - t0
        key = path.stem
        arrays[f"{key}/status"] = np.asarray(res.status).astype("U16").ravel()
        arrays[f"{key}/period"] = res.period.ravel()
        arrays[f"{key}/points"] = res.points.reshape(-1, *res.points.shape[-2:])
        arrays[f"{key}/count"] = res.count.ravel()
        arrays[f"{key}/steps"] = np.asarray(res.n_steps).ravel()
        arrays[f"{key}/wall"] = np.array(wall)
        print(f"  {key}: {wall:.1f} s", file=sys.stderr, flush=True)
    np.savez_compressed(out, **arrays)


def _spawn(name: str, gains, rtol, args, out: Path, cache: Path,
           root: Path) -> dict[str, np.ndarray]:  # fmt: skip
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), PYTHONPATH=str(root))
    cmd = [sys.executable, __file__, "--worker", json.dumps(dict(
        alpha=gains[0], beta=gains[1], rtol=rtol, num=args.num, num_2d=args.num_2d,
        only=args.only, out=str(out)))]  # fmt: skip
    print(f"{name}: gains {gains}, rtol {rtol or 'config'}, {root}", file=sys.stderr, flush=True)
    subprocess.run(cmd, cwd=ROOT, env=env, check=True)
    return dict(np.load(out))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--old", type=float, nargs=2, default=(0.7, 0.4), metavar=("ALPHA", "BETA"))
    ap.add_argument("--new", type=float, nargs=2, default=(0.85, 0.2), metavar=("ALPHA", "BETA"))
    ap.add_argument("--ref-rtol", type=float, default=1e-11)
    ap.add_argument("--num", type=int, default=100)
    ap.add_argument("--num-2d", type=int, default=10)
    ap.add_argument("--tol", type=float, default=1e-6)
    ap.add_argument("--only")
    ap.add_argument("--out", type=Path)
    ap.add_argument("--csv", type=Path)
    ap.add_argument("--old-root", type=Path, default=ROOT, help="checkout of the old code")
    ap.add_argument("--new-root", type=Path, default=ROOT, help="checkout of the new code")
    args = ap.parse_args()
    if args.worker:
        w = json.loads(args.worker)
        _worker(w["alpha"], w["beta"], w["rtol"], w["num"], w["num_2d"], w["only"], Path(w["out"]))
        return 0
    if args.out is None:
        ap.error("--out is required")
    tmp = Path(tempfile.mkdtemp(prefix="ssf-ctrl-cmp-"))
    try:
        runs = {}
        for name, gains, rtol, root in (("old", args.old, None, args.old_root),
                                        ("new", args.new, None, args.new_root),
                                        ("ref", args.old, args.ref_rtol, args.old_root)):  # fmt: skip
            # old and ref share one cache
            cache = tmp / f"cache-{gains[0]}-{gains[1]}-{'new' if name == 'new' else 'old'}"
            runs[name] = _spawn(name, gains, rtol, args, tmp / f"{name}.npz", cache,
                                root.resolve())  # fmt: skip
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    keys = sorted({k.split("/")[0] for k in runs["old"]})
    rows, bad = [], []

    def pair(a, b, key):
        A, B = runs[a], runs[b]
        return agreement(
            A[f"{key}/status"], A[f"{key}/period"], A[f"{key}/points"], A[f"{key}/count"],
            B[f"{key}/status"], B[f"{key}/period"], B[f"{key}/points"], B[f"{key}/count"],
            args.tol,
        )  # fmt: skip

    for key in keys:
        ok_or, d_or = pair("old", "ref", key)
        ok_nr, d_nr = pair("new", "ref", key)
        ok_on, _ = pair("old", "new", key)
        st = {n: runs[n][f"{key}/status"] for n in runs}
        pe = {n: runs[n][f"{key}/period"] for n in runs}
        for i in np.flatnonzero(~(ok_or & ok_nr & ok_on)):
            bad.append(dict(
                config=key, index=int(i),
                old=f"{st['old'][i]}/P{pe['old'][i]}", new=f"{st['new'][i]}/P{pe['new'][i]}",
                ref=f"{st['ref'][i]}/P{pe['ref'][i]}",
                old_ref_distance=f"{d_or[i]:.3g}", new_ref_distance=f"{d_nr[i]:.3g}",
            ))  # fmt: skip
        rows.append(dict(
            config=key, values=ok_or.size, old_ref=int(ok_or.sum()), new_ref=int(ok_nr.sum()),
            old_new=int(ok_on.sum()),
            steps_old=int(runs["old"][f"{key}/steps"].sum()),
            steps_new=int(runs["new"][f"{key}/steps"].sum()),
            wall_old=float(runs["old"][f"{key}/wall"]), wall_new=float(runs["new"][f"{key}/wall"]),
        ))  # fmt: skip
    lines = [
        f"old gains {tuple(args.old)}, new gains {tuple(args.new)}, reference: old gains at "
        f"rtol {args.ref_rtol:g}; agreement: status, period and points within {args.tol:g}",
        "",
        "| config | values | old = ref | new = ref | old = new | steps old / new | time old / new |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['config']} | {r['values']} | {r['old_ref']} | {r['new_ref']} | {r['old_new']} | "
            f"{r['steps_old']} / {r['steps_new']} ({r['steps_old'] / r['steps_new']:.2f}x) | "
            f"{r['wall_old']:.1f} s / {r['wall_new']:.1f} s ({r['wall_old'] / r['wall_new']:.2f}x) |"
        )
    tot = {k: sum(r[k] for r in rows) for k in ("values", "old_ref", "new_ref", "old_new",
                                                "steps_old", "steps_new")}  # fmt: skip
    lines.append(
        f"| **all** | {tot['values']} | {tot['old_ref']} | {tot['new_ref']} | {tot['old_new']} | "
        f"{tot['steps_old'] / tot['steps_new']:.2f}x | |"
    )
    args.out.write_text("\n".join(lines) + "\n")
    if args.csv:
        with args.csv.open("w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(bad[0]) if bad else ["config"])
            w.writeheader()
            w.writerows(bad)
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
