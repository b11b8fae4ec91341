"""Overhead of the Dask backend against the local one, on the Fig. 6 sweep.

The same sweep (asymmetric set, eta = linspace(1, 10, 1000), t_end 3000,
t_transient 2000, max_points 256, written to an HDF5 file) runs alternately on

* ``local``: the embedded engine with 2 Numba threads (``threads=2``), and
* ``dask``: a LocalCluster of 2 single-threaded worker processes (one Numba
  thread each), started once; its start-up and the workers' warm-up are
  timed separately and not counted in the sweep time.

Each repetition runs local then dask, back to back; the machine may be shared,
so the median over repetitions is reported, with the load average around
each run. Task durations come from Dask's task stream: the first task on each
worker is compared with the rest (per value), to show tasks do not pay for
compilation. Writes ``benchmarks/results/dask_overhead.json`` and ``.md``.

Usage::

    python3 benchmarks/dask_overhead.py [--repeats 3] [--n 1000]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast.analysis.sweep import sweep  # noqa: E402
from stickslip_fast.backends import dask as backends  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"


def _machine() -> dict:
    model = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import dask
    import numba

    return {
        "cpu": model or platform.processor(),
        "cores": len(os.sched_getaffinity(0)),
        "python": platform.python_version(),
        "numba": numba.__version__,
        "dask": dask.__version__,
        "threading_layer": numba.threading_layer(),
        "platform": platform.platform(),
    }


def _task_stats(stream: list[dict], chunk: int) -> dict:
    """Compute durations per task; the first task on each worker versus the rest."""
    tasks = []
    for rec in stream:
        for ss in rec.get("startstops", ()):
            if ss["action"] == "compute" and str(rec["key"]).startswith("stickslip-"):
                tasks.append((rec["worker"], ss["start"], ss["stop"] - ss["start"]))
    tasks.sort(key=lambda t: t[1])
    first = {}
    for worker, _start, dur in tasks:
        first.setdefault(worker, dur)
    durs = [d for _, _, d in tasks]
    return {
        "n_tasks": len(tasks),
        "values_per_task": chunk,
        "median_s": statistics.median(durs) if durs else None,
        "min_s": min(durs) if durs else None,
        "max_s": max(durs) if durs else None,
        "first_task_per_worker_s": list(first.values()),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--n", type=int, default=1000, help="number of eta values")
    ap.add_argument("--out", default=str(RESULTS / "dask_overhead"))
    args = ap.parse_args(argv)

    from distributed import Client, get_task_stream

    warnings.filterwarnings("ignore", message=".*gave no orbit.*")
    system = ssf.System.preset("asymmetric")
    etas = np.linspace(1.0, 10.0, args.n)
    kw = dict(t_end=3000.0, t_transient=2000.0, max_points=256, progress=False)
    sweep(system, "eta", etas[:2], threads=2, t_end=10.0)  # compile / load the cache here

    t0 = time.perf_counter()
    cluster = backends.local_cluster(2)
    client = Client(cluster, set_as_default=False)
    client.wait_for_workers(2)
    t_start = time.perf_counter() - t0
    t0 = time.perf_counter()
    warm = backends.prepare_client(client, numba_threads=1)
    t_warm = time.perf_counter() - t0
    print(f"cluster start {t_start:.2f} s, warm-up {t_warm:.2f} s", flush=True)

    runs: dict[str, list[dict]] = {"local": [], "dask": []}
    tasks = None
    ref = None
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(args.repeats):
            for name in ("local", "dask"):
                path = Path(tmp) / f"{name}{rep}.h5"
                load0 = os.getloadavg()[0]
                t0 = time.perf_counter()
                if name == "local":
                    res = sweep(system, "eta", etas, threads=2, out=path, **kw)
                else:
                    with get_task_stream(client) as ts:
                        res = sweep(system, "eta", etas, backend="dask", out=path,
                                    scheduler=cluster.scheduler_address, **kw)  # fmt: skip
                    tasks = _task_stats(ts.data, backends.DEFAULT_CHUNK_SIZE)
                seconds = time.perf_counter() - t0
                runs[name].append(
                    {"seconds": seconds, "load_before": load0, "load_after": os.getloadavg()[0]}
                )
                if ref is None:
                    ref = res
                else:  # every run gives the same bits
                    for f in ("points", "final_state", "n_steps", "status_code"):
                        np.testing.assert_array_equal(getattr(res, f), getattr(ref, f))
                print(f"rep {rep} {name:5s} {seconds:7.2f} s  (load {load0:.2f})", flush=True)
    client.close()
    t0 = time.perf_counter()
    cluster.close()
    t_close = time.perf_counter() - t0

    med = {k: statistics.median(r["seconds"] for r in v) for k, v in runs.items()}
    pairs = [d["seconds"] / l["seconds"] - 1 for l, d in zip(runs["local"], runs["dask"])]
    result = {
        "benchmark": "dask backend overhead, Fig. 6 sweep",
        "sweep": {"preset": "asymmetric", "param": "eta", "values": f"linspace(1, 10, {args.n})",
                  "t_end": 3000.0, "t_transient": 2000.0, "max_points": 256, "out": "HDF5 file"},
        "local": {"threads": 2, "chunk_size": 64, "runs": runs["local"], "median_s": med["local"]},
        "dask": {
            "cluster": "LocalCluster, 2 worker processes x 1 thread, 1 Numba thread each",
            "chunk_size": backends.DEFAULT_CHUNK_SIZE,
            "runs": runs["dask"],
            "median_s": med["dask"],
            "cluster_start_s": t_start,
            "warm_up_s": t_warm,
            "warm_up_per_worker_s": [w["seconds"] for w in warm.values()],
            "cluster_close_s": t_close,
            "tasks_last_run": tasks,
        },
        "overhead_of_medians": med["dask"] / med["local"] - 1,
        "overhead_per_pair": pairs,
        "overhead_median_of_pairs": statistics.median(pairs),
        "machine": _machine(),
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
    }  # fmt: skip
    _write(result, Path(args.out))
    return 0


def _write(result: dict, out: Path) -> None:
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(result, indent=1) + "\n")
    out.with_suffix(".md").write_text(_markdown(result))
    print(_markdown(result))


def _markdown(r: dict) -> str:
    m, d, lo = r["machine"], r["dask"], r["local"]
    t = d["tasks_last_run"] or {}
    lo_runs = ", ".join(f"{x['seconds']:.1f}" for x in lo["runs"])
    d_runs = ", ".join(f"{x['seconds']:.1f}" for x in d["runs"])
    lines = [
        "# Dask backend overhead (Fig. 6 sweep)",
        "",
        f"Machine: {m['cpu']}, {m['cores']} cores (shared), Python {m['python']}, "
        f"Numba {m['numba']} ({m['threading_layer']} layer), Dask {m['dask']}. {r['date']}.",
        "",
        f"Sweep: asymmetric set, eta = {r['sweep']['values']}, t_end 3000, t_transient 2000, "
        "max_points 256, written to HDF5. Same bits from every run.",
        "",
        "| backend | configuration | runs (s) | median (s) |",
        "|---|---|---|---|",
        f"| local | 2 Numba threads, chunk 64 | {lo_runs} | {lo['median_s']:.1f} |",
        f"| dask | {d['cluster']}, chunk {d['chunk_size']} | {d_runs} | {d['median_s']:.1f} |",
        "",
        f"**Overhead: {100 * r['overhead_of_medians']:+.1f}%** (ratio of medians); "
        f"per back-to-back pair: {', '.join(f'{100 * p:+.1f}%' for p in r['overhead_per_pair'])} "
        f"(median {100 * r['overhead_median_of_pairs']:+.1f}%). Target: <= +10%.",
        "",
        f"Not counted above: cluster start {d['cluster_start_s']:.1f} s, worker warm-up "
        f"(Numba cache load, in parallel) {d['warm_up_s']:.1f} s "
        f"(per worker: {', '.join(f'{x:.2f}' for x in d['warm_up_per_worker_s'])} s), "
        f"cluster close {d['cluster_close_s']:.1f} s.",
        "",
    ]
    if t:
        lines += [
            f"Tasks (last dask run): {t['n_tasks']} tasks of {t['values_per_task']} values, "
            f"compute time median {t['median_s']:.2f} s (min {t['min_s']:.2f}, max "
            f"{t['max_s']:.2f}); the first task on each worker took "
            f"{', '.join(f'{x:.2f}' for x in t['first_task_per_worker_s'])} s "
            f"(the first tasks hold the cheapest values, eta near 1). The warm-up plugin "
            f"had loaded the kernels when each worker started: a task that had to load the "
            f"Numba cache itself would take at least the warm-up time "
            f"({', '.join(f'{x:.2f}' for x in d['warm_up_per_worker_s'])} s), "
            "and a compile 10-30 s.",
            "",
        ]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
