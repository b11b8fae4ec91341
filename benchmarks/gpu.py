"""GPU benchmark of the CUDA backend (issue 12), against the local backend on the same machine.

Run on a machine with an NVIDIA GPU and the ``[cuda]`` extra::

    python3 benchmarks/gpu.py                  # full: Fig. 6 at 1e4 and 1e5 values, 1000x1000 map
    python3 benchmarks/gpu.py --map-size 300   # a smaller period map

It measures, in one run:

* the Fig. 6 sweep (asymmetric set, constant belt, eta in [1, 10], t_end 3000,
  t_transient 2000, 256 points) at 1e4 and 1e5 values;
* a period map of 1000 x 1000 values in (eta, k12) (eta in [1, 10], k12 in
  [-0.9, 0.9], same times, 64 points per value);
* each against the local backend on this machine's CPU cores (all of them, and
  2 of them, as the 2-core reference of the issue's target). The CPU side runs
  an evenly strided subsample of each workload (``--cpu-values``), which has
  the same distribution of cost per value; trajectories per second compare.

and reports trajectories per second, registers and local memory per thread,
theoretical occupancy (from registers, block size and the device's limits),
the effect of divergence (per block, the slowest thread's Rodas5P steps
against the median thread's: threads of a block run in lock step, so the block
lasts as long as its slowest thread), a block-size scan, and whether the GPU's
status and period equal the CPU's on the subsample (and how far the points are).

A workload stops submitting launches after ``--budget-s`` seconds of GPU time
(default 90), collects those in flight, and reports the values it finished
(marked "partial"): the whole run then fits a 10-minute session. Results go to ``benchmarks/results/gpu.json``
and a Markdown table to stdout.

Without a GPU it exits with status 2 and a message saying so. With
``NUMBA_ENABLE_CUDASIM=1`` it runs tiny workloads in numba's simulator, to test
this script: those numbers are not GPU measurements.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # benchmark this checkout, not an installed copy
    sys.path.insert(0, str(ROOT))


def _no_gpu(msg: str) -> None:
    print(f"benchmarks/gpu.py: {msg}", file=sys.stderr)
    print("No GPU figure measured.", file=sys.stderr)
    raise SystemExit(2)


def _require_gpu():
    try:
        import numba_cuda  # noqa: F401
    except ImportError:
        _no_gpu('numba-cuda is not installed: pip install "stickslip_fast[cuda]"')
    from numba import cuda

    sim = cuda.jit.__module__.startswith("numba.cuda.simulator")
    if not sim and not cuda.is_available():
        _no_gpu(
            "no NVIDIA GPU with a working driver on this machine (numba.cuda.is_available() "
            "is False); this benchmark needs one"
        )
    return sim


SIM = _require_gpu()

import numba  # noqa: E402

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast import cuda_backend as cb  # noqa: E402
from stickslip_fast.chunks import WorkUnit, compute_restart_chunk  # noqa: E402
from stickslip_fast.settings import Settings  # noqa: E402

sys.path.insert(0, str(ROOT / "benchmarks"))
from common import cpu_model  # noqa: E402


def settings_for(t_end, t_transient, max_points):
    return Settings.resolve("rodas5p", t_end, t_transient, max_points=max_points)


# ------------------------------------------------------------------ device facts
def occupancy(regs: int, tpb: int, dev) -> dict:
    """Theoretical occupancy from registers per thread and block size (no shared memory)."""
    regs_sm = int(getattr(dev, "MAX_REGISTERS_PER_MULTIPROCESSOR", 65536))
    threads_sm = int(getattr(dev, "MAX_THREADS_PER_MULTIPROCESSOR", 2048))
    blocks_sm = int(getattr(dev, "MAX_BLOCKS_PER_MULTIPROCESSOR", 32))
    warps_block = -(-tpb // 32)
    regs_warp = -(-regs * 32 // 256) * 256  # allocation granularity: 256 registers per warp
    warps_by_regs = regs_sm // regs_warp if regs_warp else threads_sm // 32
    blocks = min(blocks_sm, warps_by_regs // warps_block, threads_sm // (warps_block * 32))
    active = blocks * warps_block * 32
    return {
        "blocks_per_sm": int(blocks),
        "active_threads_per_sm": int(active),
        "max_threads_per_sm": threads_sm,
        "theoretical_occupancy": active / threads_sm,
        "limited_by": "registers" if warps_by_regs // warps_block < blocks_sm else "blocks",
    }


def kernel_facts(system, tpb: int) -> dict:
    k = cb.get_kernel(system.n_oscillators, system.is_dc_motor)
    if SIM:
        return {"registers_per_thread": None, "local_bytes_per_thread": None}
    regs = k.get_regs_per_thread()
    lmem = k.get_local_mem_per_thread()
    if isinstance(regs, dict):
        regs = max(regs.values())
    if isinstance(lmem, dict):
        lmem = max(lmem.values())
    from numba import cuda

    out = {"registers_per_thread": int(regs), "local_bytes_per_thread": int(lmem)}
    out.update(occupancy(int(regs), tpb, cuda.get_current_device()))
    return out


# ------------------------------------------------------------------ measuring
def divergence(steps: np.ndarray, tpb: int) -> dict:
    """Per block of tpb consecutive values: slowest thread's steps / median thread's."""
    n = steps.size // tpb * tpb
    if n == 0:
        return {}
    blocks = steps[:n].reshape(-1, tpb).astype(float)
    mx = blocks.max(axis=1)
    med = np.median(blocks, axis=1)
    ratio = mx / np.maximum(med, 1.0)
    return {
        "slowest_over_median_median": float(np.median(ratio)),
        "slowest_over_median_p90": float(np.percentile(ratio, 90)),
        "slowest_over_median_max": float(ratio.max()),
        # useful thread-steps / thread-steps the blocks occupy (1 = no divergence)
        "lockstep_efficiency": float(blocks.sum() / (mx.sum() * tpb)),
    }


def gpu_run(system, names, vals, settings, chunk, tpb, budget):
    """Restart chunks on the GPU, two launches in flight; returns timing and per-value fields."""
    y0 = system.initial_state(None)
    chunk = chunk or cb.default_chunk_size(system, settings)
    run = cb.cuda_runner(system, settings, "restart", threads_per_block=tpb)
    stop = []

    def units():  # after the budget, submit nothing more but collect what is in flight
        for a in range(0, len(vals), chunk):
            if stop:
                return
            yield WorkUnit("restart", vals[a : a + chunk], [])

    period, status, steps = [], [], []
    t0 = time.perf_counter()
    done = 0
    gen = run(units(), system, names, y0, settings)
    for unit, res in gen:
        period.append(res["period"])
        status.append(res["status"])
        steps.append(res["n_steps"] + res["n_rejected"])
        done += len(unit.values)
        if time.perf_counter() - t0 > budget and not stop:
            stop.append(True)
    partial = done < len(vals)
    dt = time.perf_counter() - t0
    return {
        "values": int(done),
        "of": int(len(vals)),
        "partial": partial,
        "seconds": dt,
        "traj_per_s": done / dt,
        "period": np.concatenate(period),
        "status": np.concatenate(status),
        "steps": np.concatenate(steps),
    }


def cpu_run(system, names, vals, settings, threads):
    y0 = system.initial_state(None)
    old = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        t0 = time.perf_counter()
        res = compute_restart_chunk(system, names, vals, y0, settings)
        dt = time.perf_counter() - t0
    finally:
        numba.set_num_threads(old)
    return dt, res


def compare(system, names, vals, settings, tpb, cpu_res) -> dict:
    gpu = cb.compute_restart_chunk_cuda(
        system, names, vals, system.initial_state(None), settings, tpb
    )
    ok = (cpu_res["status"] == 0) & (gpu["status"] == 0)
    diff = (
        np.nanmax(np.abs(gpu["points"][ok] - cpu_res["points"][ok]), axis=(1, 2))
        if ok.any()
        else np.zeros(0)
    )
    return {
        "values": int(len(vals)),
        "status_equal": int(np.sum(gpu["status"] == cpu_res["status"])),
        "period_equal": int(np.sum(gpu["period"] == cpu_res["period"])),
        "orbits_compared": int(ok.sum()),
        "orbits_points_within_1e-9": int(np.sum(diff <= 1e-9)),
        "max_point_diff_median": float(np.median(diff)) if diff.size else None,
        "max_point_diff_max": float(diff.max()) if diff.size else None,
    }


def workload(name, system, names, vals, settings, args, log):
    tpb = args.threads_per_block
    log(f"[{name}] {len(vals)} values on the GPU ...")
    g = gpu_run(system, names, vals, settings, args.chunk, tpb, args.budget_s)
    stride = max(1, len(vals) // args.cpu_values)
    sub = vals[::stride][: args.cpu_values]
    ncores = numba.config.NUMBA_NUM_THREADS
    log(f"[{name}] {len(sub)} strided values on {ncores} CPU threads ...")
    cpu_all_s, cpu_res = cpu_run(system, names, sub, settings, ncores)
    sub2 = sub[:: max(1, len(sub) // args.cpu2_values)][: args.cpu2_values]
    log(f"[{name}] {len(sub2)} strided values on 2 CPU threads ...")
    cpu2_s, _ = cpu_run(system, names, sub2, settings, min(2, ncores))
    log(f"[{name}] GPU vs CPU on the subsample ...")
    agree = compare(system, names, sub, settings, tpb, cpu_res)
    cpu_rate = len(sub) / cpu_all_s
    cpu2_rate = len(sub2) / cpu2_s
    out = {
        "name": name,
        "gpu": {k: v for k, v in g.items() if k not in ("period", "status", "steps")},
        "cpu_all_cores": {"threads": ncores, "values": len(sub), "seconds": cpu_all_s, "traj_per_s": cpu_rate},
        "cpu_2_cores": {"threads": min(2, ncores), "values": len(sub2), "seconds": cpu2_s, "traj_per_s": cpu2_rate},
        "speedup_vs_all_cores": g["traj_per_s"] / cpu_rate,
        "speedup_vs_2_cores": g["traj_per_s"] / cpu2_rate,
        "divergence": divergence(g["steps"], tpb),
        "agreement_on_subsample": agree,
        "periods_found": {str(int(p)): int(c) for p, c in zip(*np.unique(g["period"], return_counts=True))},
    }  # fmt: skip
    log(json.dumps(out, indent=1))
    return out


def block_scan(system, vals, settings, sizes, budget, log) -> list[dict]:
    rows = []
    for tpb in sizes:
        g = gpu_run(system, ("eta",), vals, settings, len(vals), tpb, budget)
        row = {"threads_per_block": tpb, "traj_per_s": g["traj_per_s"]}
        row.update(kernel_facts(system, tpb))
        rows.append(row)
        log(f"[block scan] {row}")
    return rows


def markdown(res: dict) -> str:
    lines = [
        f"GPU: {res['device']['name']}  |  CPU: {res['machine']['cpu_model']} "
        f"({res['machine']['cores']} threads)  |  {res['when']}",
        "",
        "| workload | values (GPU) | GPU traj/s | CPU traj/s (all cores) | CPU traj/s (2 cores) "
        "| × all cores | × 2 cores | slowest/median per block (median, p90) | lock-step efficiency |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for w in res["workloads"]:
        g, d = w["gpu"], w["divergence"]
        lines.append(
            f"| {w['name']} | {g['values']}{' (partial)' if g['partial'] else ''} "
            f"| {g['traj_per_s']:.0f} | {w['cpu_all_cores']['traj_per_s']:.1f} "
            f"| {w['cpu_2_cores']['traj_per_s']:.1f} | {w['speedup_vs_all_cores']:.1f} "
            f"| {w['speedup_vs_2_cores']:.1f} | {d.get('slowest_over_median_median', float('nan')):.2f}, "
            f"{d.get('slowest_over_median_p90', float('nan')):.2f} "
            f"| {d.get('lockstep_efficiency', float('nan')):.2f} |"
        )
    k = res["kernel"]
    lines += ["", f"Kernel (N = 1, constant belt, {res['threads_per_block']} threads/block): {k}"]
    if res["block_scan"]:
        lines += ["", "| threads/block | traj/s | theoretical occupancy |", "|---|---|---|"]
        for r in res["block_scan"]:
            lines.append(
                f"| {r['threads_per_block']} | {r['traj_per_s']:.0f} "
                f"| {r.get('theoretical_occupancy', float('nan')):.3f} |"
            )
    for w in res["workloads"]:
        lines.append(
            f"\n{w['name']}: agreement with the CPU on the subsample: {w['agreement_on_subsample']}"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fig6-sizes", default="10000,100000", help="values of the Fig. 6 sweeps")
    ap.add_argument(
        "--map-size", type=int, default=1000, help="values per axis of the (eta, k12) map"
    )
    ap.add_argument(
        "--cpu-values", type=int, default=1600, help="strided subsample run on all CPU cores"
    )
    ap.add_argument(
        "--cpu2-values", type=int, default=200, help="strided subsample run on 2 CPU cores"
    )
    ap.add_argument("--threads-per-block", type=int, default=cb.THREADS_PER_BLOCK)
    ap.add_argument(
        "--block-sizes",
        default="32,64,128,256",
        help="block-size scan on 1e4 Fig. 6 values ('' to skip)",
    )
    ap.add_argument("--chunk", type=int, help="values per launch (default: the backend's)")
    ap.add_argument(
        "--budget-s", type=float, default=90.0,
        help="GPU seconds per workload, about (then it reports the values done; the whole run "
        "stays under ~8 min with the defaults)",
    )  # fmt: skip
    ap.add_argument("--t-end", type=float, default=3000.0)
    ap.add_argument("--t-transient", type=float, default=2000.0)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "gpu.json"))
    args = ap.parse_args(argv)
    if SIM:  # testing this script: tiny workloads, and say loudly that this is no measurement
        print(
            "NUMBA_ENABLE_CUDASIM=1: numba's CUDA simulator, NOT a GPU; tiny workloads.",
            file=sys.stderr,
        )
        args.fig6_sizes, args.map_size, args.block_sizes = "8", 2, ""
        args.cpu_values, args.cpu2_values, args.chunk, args.threads_per_block = 4, 2, 4, 4
        args.t_end, args.t_transient = 20.0, 10.0
        args.out = os.path.join(tempfile.gettempdir(), "stickslip_gpu_simulator.json")

    def log(msg):
        print(msg, file=sys.stderr, flush=True)

    asym = ssf.System.preset("asymmetric")
    fig6 = settings_for(args.t_end, args.t_transient, 256)
    res = {
        "when": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
        "simulator": SIM,
        "device": cb.device_summary(),
        "machine": {"cpu_model": cpu_model(), "cores": numba.config.NUMBA_NUM_THREADS,
                    "numba": numba.__version__},
        "threads_per_block": args.threads_per_block,
        "settings": {"t_end": args.t_end, "t_transient": args.t_transient},
        "kernel": None,  # after the first launch has compiled it
        "workloads": [],
        "block_scan": [],
    }  # fmt: skip
    log("compiling the kernel (first launch) ...")
    t0 = time.perf_counter()
    cb.compute_restart_chunk_cuda(asym, ("eta",), np.array([[5.0]]), asym.initial_state(None), fig6)
    res["compile_seconds"] = time.perf_counter() - t0
    res["kernel"] = kernel_facts(asym, args.threads_per_block)

    sizes = [int(s) for s in args.block_sizes.split(",") if s]
    if sizes:
        res["block_scan"] = block_scan(
            asym, np.linspace(1, 10, 10000)[:, None], fig6, sizes, args.budget_s / 4, log
        )
    for n in (int(s) for s in args.fig6_sizes.split(",") if s):
        vals = np.linspace(1.0, 10.0, n)[:, None]
        res["workloads"].append(
            workload(f"Fig. 6, {n} values", asym, ("eta",), vals, fig6, args, log)
        )
    m = args.map_size
    if m > 0:
        eta, k12 = np.meshgrid(np.linspace(1, 10, m), np.linspace(-0.9, 0.9, m), indexing="ij")
        vals = np.stack([eta.ravel(), k12.ravel()], axis=-1)
        res["workloads"].append(
            workload(f"period map {m}x{m} (eta, k12)", asym, ("eta", "k12"), vals,
                     settings_for(args.t_end, args.t_transient, 64), args, log)
        )  # fmt: skip
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(res, indent=1, default=float))
    print(markdown(res))
    log(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
