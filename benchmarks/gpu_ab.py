"""Two checkouts' CUDA kernels side by side on the GPU maps: time, and whether the results agree.

A before/after question for a change of the GPU kernels or of their launches (first
asked for the queue of runs per thread, 2026-11-26). For each ``--root``, a fresh
process imports that checkout, compiles its kernels on a small warm-up call (not
timed), then times each workload through the public API:

- ``fig6_fixed``: the Fig. 6 sweep, 10^5 eta values, t_end 3000, t_transient 2000;
- ``fig6_converged``: the same with converged stopping;
- ``census_fig6``: a census of Fig. 6, 1000 eta values x 64 starts, converged;
- ``census_plane``: the (eta, k12) census plane of data/maps/census_plane_eta_k12.toml,
  100 x 100 cells x 16 starts, converged (as ``benchmarks/census_plane.py``);
- ``basins``: the 500 x 500 basin map at eta = 3.2 (as ``benchmarks/basins.py``).

Each run's status, period and steps, and its first Poincare point, are kept; the
parent compares every root with the first (status and period equal, steps equal,
largest point difference). Roots alternate, round by round (``--rounds``).

    python3 -m benchmarks.gpu_ab --root BEFORE --root AFTER [--rounds 1] [--out FILE]
    python3 -m benchmarks.gpu_ab --root . --root .:THREADS_PER_SM=384,RUNS_PER_THREAD=8
    python3 -m benchmarks.gpu_ab --root . --workloads census_fig6,basins --scale 0.1

Needs a GPU (exits with status 2 and a message without one). Results: a JSON file
(default ``benchmarks/results/gpu_ab.json``) and a Markdown table on stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

from .common import ROOT, cpu_model

WORKLOADS = ("fig6_fixed", "fig6_converged", "census_fig6", "census_plane", "basins")

_CHILD = textwrap.dedent(
    """
    import json, sys, time
    import numpy as np
    import stickslip_fast as ssf

    names, scale, out = sys.argv[1].split(","), float(sys.argv[2]), sys.argv[3]
    if sys.argv[4]:  # launch constants of this variant (they do not change results)
        from stickslip_fast.backends import cuda as cb
        for item in sys.argv[4].split(","):
            key, value = item.split("=")
            if not hasattr(cb, key):
                raise SystemExit(f"stickslip_fast.backends.cuda has no {key}")
            setattr(cb, key, int(value))
    asym = ssf.System.preset("asymmetric")
    cuda = dict(backend="cuda", progress=False)

    def n_of(n):
        return max(2, int(round(n * scale)))

    def fields(status, period, steps, points):
        return dict(status=np.asarray(status), period=np.asarray(period),
                    steps=np.asarray(steps), point=np.asarray(points)[..., 0, :])

    def fig6(n, stop):
        kw = dict(t_end=3000.0, t_transient=0.0 if stop == "converged" else 2000.0, stop=stop)
        vals = np.linspace(1.0, 10.0, n)
        ssf.sweep(asym, "eta", vals[:4], **kw, **cuda)  # compile / load
        t0 = time.perf_counter()
        r = ssf.sweep(asym, "eta", vals, **kw, **cuda)
        wall = time.perf_counter() - t0
        return wall, n, fields(r.status_code, r.period, r.n_steps + r.n_rejected, r.points)

    def census(params, axes, n_starts, **kw):
        small = tuple(a[:2] for a in axes) if isinstance(params, tuple) else axes[:2]
        ssf.census(asym, params, small, n_starts=n_starts, **kw, **cuda)
        t0 = time.perf_counter()
        r = ssf.census(asym, params, axes, n_starts=n_starts, **kw, **cuda)
        wall = time.perf_counter() - t0
        raw = r.raw
        runs = int(np.prod(raw["status"].shape))
        return wall, runs, fields(raw["status"], raw["period"],
                                  raw["n_steps"] + raw["n_rejected"], raw["points"])

    def basins(n):
        system = ssf.System.preset("asymmetric", eta=3.2)
        g4 = np.linspace(-0.3, 0.3, 4)
        ssf.basins(system, (g4, g4), t_end=3000.0, **cuda)
        g = np.linspace(-0.3, 0.3, n)
        t0 = time.perf_counter()
        r = ssf.basins(system, (g, g), t_end=3000.0, **cuda)
        wall = time.perf_counter() - t0
        raw = r.census.raw
        return wall, n * n, fields(raw["status"], raw["period"],
                                   raw["n_steps"] + raw["n_rejected"], raw["points"])

    jobs = {
        "fig6_fixed": lambda: fig6(n_of(100_000), "fixed"),
        "fig6_converged": lambda: fig6(n_of(100_000), "converged"),
        "census_fig6": lambda: census("eta", np.linspace(1.0, 10.0, n_of(1000)), 64,
                                      t_end=3000.0, max_points=128),
        "census_plane": lambda: census(("eta", "k12"), (np.linspace(1.0, 6.0, n_of(100)),
                                       np.linspace(-0.95, -0.55, n_of(100))), 16,
                                       t_end=3000.0, t_transient=2000.0, max_points=128),
        "basins": lambda: basins(n_of(500)),
    }
    report = {}
    for name in names:
        wall, runs, arrays = jobs[name]()
        np.savez(f"{out}_{name}.npz", **arrays)
        report[name] = dict(wall_s=wall, runs=runs, runs_per_s=runs / wall)
        print(json.dumps({name: report[name]}), file=sys.stderr, flush=True)
    print(json.dumps(report))
    """
)


def _run_child(variant: str, names: list[str], scale: float, out: str, timeout: float) -> dict:
    root, _, sets = variant.partition(":")
    env = dict(os.environ, PYTHONPATH=root)
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, ",".join(names), str(scale), out, sets],
        capture_output=True, text=True, env=env, cwd=str(root), timeout=timeout,
    )  # fmt: skip
    if proc.returncode != 0:
        raise RuntimeError(f"{variant}: child failed\n{proc.stderr[-4000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _agreement(a: str, b: str) -> dict:
    """Run by run: status and period equal, steps equal, largest first-point difference."""
    x, y = np.load(a), np.load(b)
    same = {k: bool(np.array_equal(x[k], y[k])) for k in ("status", "period", "steps")}
    both = np.isfinite(x["point"]) & np.isfinite(y["point"])
    diff = float(np.max(np.abs(x["point"][both] - y["point"][both]), initial=0.0))
    nan_same = bool(np.array_equal(np.isnan(x["point"]), np.isnan(y["point"])))
    runs = int(x["status"].size)
    return dict(runs=runs, status_period_equal=same["status"] and same["period"],
                status_equal_runs=int(np.sum(x["status"] == y["status"])),
                steps_equal=same["steps"], max_point_diff=diff, nan_pattern_equal=nan_same)  # fmt: skip


def markdown(res: dict) -> str:
    roots = res["roots"]
    lines = [
        f"GPU: {res['gpu']}  |  CPU: {res['cpu']}  |  {res['time']}",
        "",
        "| workload | runs | " + " | ".join(f"{_label(r)} s" for r in roots)
        + " | ratio (first / each) | agreement with the first |",
        "|---|---|" + "---|" * len(roots) + "---|---|",
    ]  # fmt: skip
    for name, row in res["workloads"].items():
        walls = [min(row["wall_s"][r]) for r in roots]
        ratios = " / ".join(f"{walls[0] / w:.2f}" for w in walls[1:]) or "-"
        agree = "; ".join(
            f"status+period {'equal' if a['status_period_equal'] else 'DIFFER'}"
            f" ({a['status_equal_runs']}/{a['runs']} status), steps "
            f"{'equal' if a['steps_equal'] else 'differ'}, points ≤ {a['max_point_diff']:.1e}"
            for a in row["agreement"].values()
        ) or "-"  # fmt: skip
        cells = " | ".join(f"{w:.2f}" for w in walls)
        lines.append(f"| {name} | {row['runs']} | {cells} | {ratios} | {agree} |")
    return "\n".join(lines)


def _label(variant: str) -> str:
    root, _, sets = variant.partition(":")
    return (Path(root).name or root) + (f" ({sets})" if sets else "")


def _gpu_name() -> str:
    try:
        out = subprocess.run(["nvidia-smi", "--query-gpu=name,driver_version",
                              "--format=csv,noheader"], capture_output=True, text=True, timeout=30)  # fmt: skip
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def _resolved(variant: str) -> str:
    root, sep, sets = variant.partition(":")
    return str(Path(root).resolve()) + sep + sets


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--root", action="append",
                    help="a checkout, optionally with launch constants of its "
                    "stickslip_fast.backends.cuda: DIR[:NAME=VALUE,...] (repeat: the first "
                    "is the base)")  # fmt: skip
    ap.add_argument("--workloads", default=",".join(WORKLOADS))
    ap.add_argument("--rounds", type=int, default=1, help="rounds of all roots, alternating")
    ap.add_argument("--scale", type=float, default=1.0, help="workload sizes times this")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds per child process")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "gpu_ab.json"))
    args = ap.parse_args(argv)
    if _gpu_name() == "unknown" and os.environ.get("NUMBA_ENABLE_CUDASIM") != "1":
        print("benchmarks/gpu_ab.py: no NVIDIA GPU here (nvidia-smi failed)", file=sys.stderr)
        return 2
    roots = [_resolved(r) for r in (args.root or [str(ROOT)])]
    names = [w for w in args.workloads.split(",") if w]
    bad = [w for w in names if w not in WORKLOADS]
    if bad:
        ap.error(f"unknown workload(s) {bad}; known: {', '.join(WORKLOADS)}")
    res = dict(gpu=_gpu_name(), cpu=f"{cpu_model()}, {os.cpu_count()} threads",
               time=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()), roots=roots,
               scale=args.scale, workloads={})  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        for rnd in range(args.rounds):
            for k, root in enumerate(roots):
                rep = _run_child(root, names, args.scale, f"{tmp}/r{k}", args.timeout)
                for name, r in rep.items():
                    row = res["workloads"].setdefault(name, dict(runs=r["runs"], wall_s={}))
                    row["wall_s"].setdefault(root, []).append(r["wall_s"])
                print(f"round {rnd + 1}, {root}: {json.dumps(rep)}", file=sys.stderr, flush=True)
        for name, row in res["workloads"].items():
            row["agreement"] = {
                root: _agreement(f"{tmp}/r0_{name}.npz", f"{tmp}/r{k}_{name}.npz")
                for k, root in enumerate(roots[1:], start=1)
            }
    Path(args.out).write_text(json.dumps(res, indent=1))
    print(markdown(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
