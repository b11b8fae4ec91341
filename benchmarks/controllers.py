"""Step-size controllers side by side, at matched Poincare accuracy (issue 11, part 2).

The engine's one adaptive driver takes its step-size factor after an accepted step from
``steppers.accepted_step_factor``: fac = 0.9 err^(-alpha/q) err_prev^(beta/q), clipped to
[0.2, 6] (q = the error estimate's order + 1), with (alpha, beta) = (0.85, 0.2), Hairer
and Wanner's DOPRI5 gains, the default since this measurement chose them; before, it was
(0.7, 0.4), OrdinaryDiffEq.jl's ``PIController`` defaults. This section measures
members of the same family on the per-trajectory cases of the peers' benchmark
(asymmetric preset, constant belt, eta = 2.0 and 9.99, from rest to t = 1500, points after
t = 1000, the SciPy Radau rtol 1e-12 reference):

- ``I``: alpha = 1, beta = 0, the elementary controller (no memory);
- ``PI 0.6/0.2``: a milder integral gain;
- ``PI 0.85/0.2``: Hairer and Wanner's DOPRI5 gains (beta = 0.04 at q = 5), the default;
- ``PI 0.7/0.4``: the default before (OrdinaryDiffEq.jl's gains).

Numba freezes module constants into the compiled code, so each controller runs in its own
process with its own Numba cache directory, its constants set before anything compiles.
For each case and target error (1e-6, 1e-8) a controller runs at the first rtol of the
peers' ladder (atol = 0.01 rtol) whose points all lie within the target; that run is then
timed, best of ``rounds`` in each of two passes over the controllers (the second pass
loads the compiled code from the cache), one core.

Standalone (not a section of ``benchmarks/run.py``: it compiles the kernels four times,
~5 minutes): ``python -m benchmarks.controllers [--quick] [--out FILE.json]``. The
committed result is ``benchmarks/results/controllers.json``; the table is in
``benchmarks/results/profile.md``, section 5c.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: name -> (alpha, beta, description)
CONTROLLERS = {
    "PI 0.7/0.4": (0.7, 0.4, "the former default: OrdinaryDiffEq.jl's PIController gains"),
    "I": (1.0, 0.0, "elementary controller, no memory of the last error"),
    "PI 0.6/0.2": (0.6, 0.2, "milder integral gain"),
    "PI 0.85/0.2": (0.85, 0.2, "the default: Hairer-Wanner's DOPRI5 gains (beta = 0.04 at q = 5)"),
}
#: the baseline the speed-ups are relative to: the controller this measurement replaced
BASELINE = "PI 0.7/0.4"
SETTINGS = {"full": dict(rounds=5, quick=False), "quick": dict(rounds=1, quick=True)}


def _worker(name: str, mode: str, scan: bool, picks: dict | None) -> dict:
    """In a fresh process: set the controller's gains, then scan and/or time."""
    from stickslip_fast.core import steppers

    alpha, beta, _ = CONTROLLERS[name]
    steppers.PI_ALPHA, steppers.PI_BETA = alpha, beta  # before any kernel compiles

    from .common import ssf
    from .peer_precision import ATOL_FACTOR, CASES, LADDER, TARGETS, point_error
    from .reference import trajectory_reference

    quick = SETTINGS[mode]["quick"]
    cases = CASES["quick" if quick else "full"]
    targets = (1e-6,) if quick else TARGETS
    ladder = [1e-6, 3e-7, 1e-7] if quick else LADDER

    def run(system, tr, rtol):
        return ssf.simulate(
            system, tr["t_end"], tr["t_transient"], rtol=rtol, atol=ATOL_FACTOR * rtol,
            max_points=10_000,
        )  # fmt: skip

    out: dict = {}
    for tr in cases:
        system = ssf.System.preset("asymmetric", eta=tr["eta"])
        run(system, dict(tr, t_end=20.0, t_transient=10.0), 1e-6)  # compile outside the timing
        rec: dict = {}
        if scan:
            ref = trajectory_reference(
                tr["eta"], tr["t_end"], tr["t_transient"], log=lambda *a: None
            )
            rows, need = [], set(targets)
            for rtol in ladder:
                r = run(system, tr, rtol)
                if r.status == "ok":
                    err, _ = point_error(ref["t"], ref["points"], r.t_poincare, r.poincare)
                else:
                    err = math.inf
                rows.append(dict(rtol=rtol, error=err, steps=int(r.n_steps),
                                 rejected=int(r.n_rejected)))  # fmt: skip
                need -= {t for t in need if err <= t}
                if not need:
                    break
            rec["scan"] = rows
            rec["picks"] = {
                f"{t:g}": next((s["rtol"] for s in rows if s["error"] <= t), None) for t in targets
            }
        chosen = rec.get("picks") or (picks or {}).get(tr["key"], {})
        times = {}
        for tgt, rtol in chosen.items():
            if rtol is None:
                continue
            best = math.inf
            for _ in range(SETTINGS[mode]["rounds"]):
                t0 = time.perf_counter()
                run(system, tr, rtol)
                best = min(best, time.perf_counter() - t0)
            times[tgt] = best
        rec["times"] = times
        out[tr["key"]] = rec
    return out


def _spawn(name: str, mode: str, cache: Path, scan: bool, picks: dict | None) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), NUMBA_NUM_THREADS="1")
    cmd = [sys.executable, "-m", "benchmarks.controllers", "--worker", name, "--mode", mode]
    if scan:
        cmd.append("--scan")
    if picks is not None:
        cmd += ["--picks", json.dumps(picks)]
    proc = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"controller {name!r} failed:\n{proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def run(mode: str, log=print) -> dict:
    """Scan and time every controller (two passes), with steps, rejections and speed-ups."""
    caches = {name: Path(tempfile.mkdtemp(prefix="ssf-ctrl-")) for name in CONTROLLERS}
    try:
        first = {}
        for name in CONTROLLERS:
            log(f"  controller {name}: compiling, scanning the ladder ...")
            first[name] = _spawn(name, mode, caches[name], True, None)
        second = {}
        for name in CONTROLLERS:
            picks = {k: v["picks"] for k, v in first[name].items()}
            second[name] = _spawn(name, mode, caches[name], False, picks)
    finally:
        for c in caches.values():
            shutil.rmtree(c, ignore_errors=True)
    res: dict = dict(
        controllers={k: dict(alpha=a, beta=b, note=n) for k, (a, b, n) in CONTROLLERS.items()},
        baseline=BASELINE,
        rounds=SETTINGS[mode]["rounds"],
        passes=2,
        cores_used=1,
        cases={},
    )
    for case in first[BASELINE]:
        table: dict = {}
        for name in CONTROLLERS:
            rec = first[name][case]
            for tgt, rtol in rec["picks"].items():
                row = table.setdefault(tgt, {})
                if rtol is None:
                    row[name] = dict(rtol=None, note="target not reached on the ladder")
                    continue
                s = next(s for s in rec["scan"] if s["rtol"] == rtol)
                t = min(rec["times"][tgt], second[name][case]["times"][tgt])
                row[name] = dict(rtol=rtol, error=s["error"], steps=s["steps"],
                                 rejected=s["rejected"], time=t)  # fmt: skip
        for tgt, row in table.items():
            base = row.get(BASELINE, {}).get("time")
            for r in row.values():
                if base and r.get("time"):
                    r["speedup_vs_baseline"] = base / r["time"]
            log(f"  {case} target {tgt}: " + ", ".join(
                f"{n} {r['time'] * 1e3:.1f} ms ({r['steps']}+{r['rejected']} @ {r['rtol']:g})"
                for n, r in row.items() if r.get("time")))  # fmt: skip
        res["cases"][case] = dict(
            tables=table, scans={n: first[n][case]["scan"] for n in CONTROLLERS}
        )
    return res


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--mode", default="full", help=argparse.SUPPRESS)
    ap.add_argument("--scan", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--picks", help=argparse.SUPPRESS)
    ap.add_argument("--out", type=Path, help="write the result as JSON here")
    args = ap.parse_args()
    if args.worker:
        picks = json.loads(args.picks) if args.picks else None
        print(json.dumps(_worker(args.worker, args.mode, args.scan, picks)))
        return
    res = run("quick" if args.quick else "full")
    if args.out:
        args.out.write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
