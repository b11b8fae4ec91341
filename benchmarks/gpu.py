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
the spread of run lengths (per 64 consecutive runs, the slowest run's Rodas5P
steps against the median run's, and the lock-step efficiency these runs would
have with one run per thread, as the kernels ran before their queue of runs:
since then a thread whose run ends takes the next, so the spread costs less than
this says), a block-size scan, and whether the GPU's
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
from numba import cuda  # noqa: E402

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast.backends import cuda as cb  # noqa: E402
from stickslip_fast.backends.local import (  # noqa: E402
    WorkUnit,
    compute_continuation_chunk,
    compute_restart_chunk,
)
from stickslip_fast.core.settings import Settings  # noqa: E402

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


def gpu_clocks() -> str | None:
    """One line of nvidia-smi: SM and memory clocks, power, temperature, throttle reasons."""
    import subprocess

    q = "clocks.sm,clocks.mem,power.draw,temperature.gpu,clocks_event_reasons.active"
    try:
        out = subprocess.run(["nvidia-smi", f"--query-gpu={q}", "--format=csv,noheader"],
                             capture_output=True, text=True, timeout=20)  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def kernel_facts(system, tpb: int, max_registers=None) -> dict:
    k = cb.get_kernel(system.n_oscillators, system.is_dc_motor, max_registers)
    if SIM:
        return {"registers_per_thread": None, "local_bytes_per_thread": None}
    regs = k.get_regs_per_thread()
    lmem = k.get_local_mem_per_thread()
    if isinstance(regs, dict):
        regs = max(regs.values())
    if isinstance(lmem, dict):
        lmem = max(lmem.values())
    out = {"registers_per_thread": int(regs), "local_bytes_per_thread": int(lmem)}
    out.update(occupancy(int(regs), tpb, cuda.get_current_device()))
    return out


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


def gpu_run(system, names, vals, settings, chunk, tpb, budget, starts=None, max_registers=None,
            max_in_flight=None):  # fmt: skip
    """Values (or (value, start) pairs) through the CUDA runner; timing and per-value fields.

    After ``budget`` seconds nothing more is submitted, and the launches in
    flight are collected (the result is then marked partial).
    """
    y0 = system.initial_state(None)
    mode = "restart" if starts is None else "census"
    max_in_flight = max_in_flight or cb.MAX_IN_FLIGHT
    run = cb.cuda_runner(system, settings, mode, threads_per_block=tpb,
                         max_in_flight=max_in_flight, max_registers=max_registers)  # fmt: skip
    chunk = chunk or run.default_chunk_size
    stop = []
    t0 = time.perf_counter()

    def units():
        for a in range(0, len(vals), chunk):
            if stop or time.perf_counter() - t0 > budget:
                return
            if starts is None:
                yield WorkUnit(
                    "restart", vals[a : a + chunk], list(range(a, a + len(vals[a : a + chunk])))
                )
            else:
                v = vals[a : a + chunk]
                yield WorkUnit("continuation", v[:, None, :], list(range(a, a + len(v))),
                               np.ascontiguousarray(starts[a : a + chunk]))  # fmt: skip

    n = len(vals)
    period = np.full(n, -9, dtype=np.int64)
    status = np.full(n, -9, dtype=np.int64)
    steps = np.full(n, -1, dtype=np.int64)
    done = 0
    for unit, res in run(units(), system, names, y0, settings):
        idx = np.asarray(unit.targets)
        sq = (lambda x: x[:, 0]) if starts is not None else (lambda x: x)
        period[idx] = sq(res["period"])
        status[idx] = sq(res["status"])
        steps[idx] = sq(res["n_steps"] + res["n_rejected"])
        done += len(idx)
    dt = time.perf_counter() - t0
    got = steps >= 0
    return {
        "values": int(done),
        "of": int(n),
        "partial": bool(done < n),
        "seconds": dt,
        "traj_per_s": done / dt,
        "chunk": int(chunk),
        "max_in_flight": max_in_flight,
        "steps_median": float(np.median(steps[got])),
        "steps_max": int(steps[got].max()),
        "period": period[got],
        "status": status[got],
        "steps": steps[got],
        "done_mask": got,
    }


def cpu_warm(system, settings):
    """Compile (or load) the CPU kernels outside the timings.

    Two values, as the timed chunks: until 2026-11-29 a chunk of one value compiled
    another specialisation of the sweep entry (read-only starts), which left ~5 s of
    compilation to the first timed call on a cold cache (seen on an H200).
    """
    compute_restart_chunk(system, ("eta",), np.array([[2.0], [2.5]]), system.initial_state(None),
                          settings.replace(t_end=1.0, t_transient=0.0))  # fmt: skip


def cpu_run(system, names, vals, settings, threads, starts=None):
    y0 = system.initial_state(None)
    old = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        t0 = time.perf_counter()
        if starts is None:
            res = compute_restart_chunk(system, names, vals, y0, settings)
        else:
            res = compute_continuation_chunk(system, names, vals[:, None, :], starts, y0, settings)
            res = {k: v[:, 0] for k, v in res.items()}
        dt = time.perf_counter() - t0
    finally:
        numba.set_num_threads(old)
    return dt, res


def compare(system, names, vals, settings, tpb, cpu_res, starts=None) -> dict:
    gpu = cb.compute_restart_chunk_cuda(
        system, names, vals, system.initial_state(None) if starts is None else starts, settings, tpb
    )
    ok = (cpu_res["status"] == 0) & (gpu["status"] == 0)
    diff = (
        np.nanmax(np.abs(gpu["points"][ok] - cpu_res["points"][ok]), axis=(1, 2))
        if ok.any()
        else np.zeros(0)
    )
    # converged stopping: the two may see convergence at different crossings (a
    # borderline repeat test flipped by roundoff), and then record the same orbit
    # from another point of its cycle; compare modulo that cyclic shift too
    shift_diff = []
    for k in np.flatnonzero(ok):
        p, c = int(cpu_res["period"][k]), int(cpu_res["count"][k])
        if p <= 0 or c <= p or int(gpu["count"][k]) != c:
            continue
        a, b = gpu["points"][k, : c - p], cpu_res["points"][k, :c]
        shift_diff.append(min(np.max(np.abs(a - b[s_ : s_ + c - p])) for s_ in range(p + 1)))
    shift_diff = np.asarray(shift_diff)
    out = {
        "values": int(len(vals)),
        "status_equal": int(np.sum(gpu["status"] == cpu_res["status"])),
        "orbits_compared_modulo_shift": int(shift_diff.size),
        "orbits_within_1e-9_modulo_shift": int(np.sum(shift_diff <= 1e-9)),
        "max_point_diff_modulo_shift": float(shift_diff.max()) if shift_diff.size else None,
        "period_equal": int(np.sum(gpu["period"] == cpu_res["period"])),
        "steps_equal": int(np.sum(gpu["n_steps"] == cpu_res["n_steps"])),
        "orbits_compared": int(ok.sum()),
        "orbits_points_within_1e-9": int(np.sum(diff <= 1e-9)),
        "max_point_diff_median": float(np.median(diff)) if diff.size else None,
        "max_point_diff_max": float(diff.max()) if diff.size else None,
    }
    if "t_converged" in gpu:
        a, b = gpu["t_converged"], cpu_res["t_converged"]
        out["t_converged_nan_equal"] = int(np.sum(np.isnan(a) == np.isnan(b)))
        both = np.isfinite(a) & np.isfinite(b)
        out["t_converged_max_rel_diff"] = (
            float(np.max(np.abs(a[both] - b[both]) / b[both])) if both.any() else None
        )
    return out


def workload(name, system, names, vals, settings, args, log, starts=None, budget=None):
    tpb = args.threads_per_block
    log(f"[{name}] {len(vals)} runs on the GPU ...")
    clocks = gpu_clocks()
    g = gpu_run(system, names, vals, settings, args.chunk, tpb, budget or args.budget_s, starts)
    idx = np.flatnonzero(g["done_mask"])  # the CPU runs a strided subsample of what the GPU did
    sub_i = idx[:: max(1, len(idx) // args.cpu_values)][: args.cpu_values]
    sub = vals[sub_i]
    sub_s = None if starts is None else starts[sub_i]
    ncores = numba.config.NUMBA_NUM_THREADS
    log(f"[{name}] {len(sub)} strided runs on {ncores} CPU threads ...")
    cpu_all_s, cpu_res = cpu_run(system, names, sub, settings, ncores, sub_s)
    k2 = max(1, len(sub) // args.cpu2_values)
    sub2, sub2_s = (
        sub[::k2][: args.cpu2_values],
        None if starts is None else sub_s[::k2][: args.cpu2_values],
    )
    log(f"[{name}] {len(sub2)} strided runs on 2 CPU threads ...")
    cpu2_s, _ = cpu_run(system, names, sub2, settings, min(2, ncores), sub2_s)
    log(f"[{name}] GPU vs CPU on the subsample ...")
    agree = compare(system, names, sub, settings, tpb, cpu_res, sub_s)
    cpu_rate = len(sub) / cpu_all_s
    cpu2_rate = len(sub2) / cpu2_s
    # the slowest runs: GPU steps against the CPU's for the same runs
    top = np.argsort(g["steps"])[::-1][:5]
    top_i = idx[top]
    _, cpu_top = cpu_run(system, names, vals[top_i], settings, ncores,
                         None if starts is None else starts[top_i])  # fmt: skip
    slowest = [
        {"values": [float(x) for x in vals[i]], "gpu_steps": int(g["steps"][t]),
         "cpu_steps": int(cpu_top["n_steps"][j] + cpu_top["n_rejected"][j]),
         "period": int(g["period"][t]), "status": int(g["status"][t])}
        for j, (t, i) in enumerate(zip(top, top_i))
    ]  # fmt: skip
    out = {
        "name": name,
        "stop": settings.stop,
        "clocks_before": clocks,  # nvidia-smi: SM, memory clocks, power, temperature, throttling
        "gpu": {k: v for k, v in g.items() if k not in ("period", "status", "steps", "done_mask")},
        "cpu_all_cores": {"threads": ncores, "values": len(sub), "seconds": cpu_all_s, "traj_per_s": cpu_rate},
        "cpu_2_cores": {"threads": min(2, ncores), "values": len(sub2), "seconds": cpu2_s, "traj_per_s": cpu2_rate},
        "speedup_vs_all_cores": g["traj_per_s"] / cpu_rate,
        "speedup_vs_2_cores": g["traj_per_s"] / cpu2_rate,
        "divergence": divergence(g["steps"], tpb),
        "slowest_runs": slowest,
        "agreement_on_subsample": agree,
        "periods_found": {str(int(p)): int(c) for p, c in zip(*np.unique(g["period"], return_counts=True))},
    }  # fmt: skip
    log(json.dumps(out, indent=1))
    return out


def register_scan(system, settings, caps, tpb, budget, log) -> list[dict]:
    """Throughput against the register cap, on 4 launches' worth of period-2 values."""
    rows = []
    n = 4 * cb.default_chunk_size(system, settings)
    vals = np.linspace(5.5, 10.0, n)[:, None]  # period-2 region: uniform cost per value
    for cap in caps:
        t0 = time.perf_counter()
        cb.compute_restart_chunk_cuda(system, ("eta",), vals[:1], system.initial_state(None),
                                      settings, tpb, cap)  # fmt: skip
        comp = time.perf_counter() - t0  # compiles a capped kernel on its first launch
        g = gpu_run(system, ("eta",), vals, settings, None, tpb, budget, max_registers=cap)
        row = {"max_registers": cap, "compile_s": comp, "traj_per_s": g["traj_per_s"],
               "values": g["values"]}  # fmt: skip
        row.update(kernel_facts(system, tpb, cap))
        rows.append(row)
        log(f"[register scan] {row}")
    return rows


def runner_ab(system, settings, n, tpb, budget, log) -> list[dict]:
    """The launch schedule, A/B on one workload: the previous one (two launches of
    ~1e5 values in flight, results in order of submission) against the current
    default (launches of about the resident threads, MAX_IN_FLIGHT in flight, in
    completion order). Alternated, twice each."""
    vals = np.linspace(1.0, 10.0, n)[:, None]
    per_value = 8 * ((settings.max_points + 1) * (system.n_state + 1) + 6)
    old_chunk = min(262144, (1 << 30) // per_value)
    rows = []
    for rep_ in range(2):
        for label, chunk, fl in (("previous: 2 in flight", old_chunk, 2),
                                 ("current default", None, None)):  # fmt: skip
            g = gpu_run(system, ("eta",), vals, settings, chunk, tpb, budget, max_in_flight=fl)
            row = {"schedule": label, "repeat": rep_, "chunk": g["chunk"],
                   "max_in_flight": g["max_in_flight"], "seconds": g["seconds"],
                   "traj_per_s": g["traj_per_s"], "values": g["values"]}  # fmt: skip
            rows.append(row)
            log(f"[runner A/B] {row}")
    return rows


def markdown(res: dict) -> str:
    lines = [
        f"GPU: {res['device']['name']}  |  CPU: {res['machine']['cpu_model']} "
        f"({res['machine']['cores']} threads)  |  {res['when']}",
        "",
        "| workload | stop | runs (GPU) | GPU runs/s | CPU runs/s (all cores) | CPU runs/s (2 cores) "
        "| × all cores | × 2 cores | slowest/median steps per 64 runs (median, p90) "
        "| lock-step efficiency, one run per thread | agreement (status, period, points ≤ 1e-9) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for w in res["workloads"]:
        g, d, a = w["gpu"], w["divergence"], w["agreement_on_subsample"]
        lines.append(
            f"| {w['name']} | {w['stop']} | {g['values']}{' (partial)' if g['partial'] else ''} "
            f"| {g['traj_per_s']:.0f} | {w['cpu_all_cores']['traj_per_s']:.1f} "
            f"| {w['cpu_2_cores']['traj_per_s']:.1f} | {w['speedup_vs_all_cores']:.1f} "
            f"| {w['speedup_vs_2_cores']:.1f} | {d.get('slowest_over_median_median', float('nan')):.2f}, "
            f"{d.get('slowest_over_median_p90', float('nan')):.2f} "
            f"| {d.get('lockstep_efficiency', float('nan')):.2f} "
            f"| {a['status_equal']}, {a['period_equal']}, {a['orbits_points_within_1e-9']}"
            f"/{a['orbits_compared']} of {a['values']} |"
        )
    k = res["kernel"]
    lines += ["", f"Kernel (N = 1, constant belt, {res['threads_per_block']} threads/block): {k}",
              f"First launch (compile): {res.get('compile_seconds', float('nan')):.1f} s"]  # fmt: skip
    if res.get("register_scan"):
        lines += ["", "| register cap | registers | local bytes | theoretical occupancy | runs/s |",
                  "|---|---|---|---|---|"]  # fmt: skip
        for r in res["register_scan"]:
            lines.append(
                f"| {r['max_registers']} | {r.get('registers_per_thread')} "
                f"| {r.get('local_bytes_per_thread')} "
                f"| {r.get('theoretical_occupancy', float('nan')):.3f} | {r['traj_per_s']:.0f} |"
            )
    if res.get("runner_ab"):
        lines += ["", "| launch schedule | values per launch | in flight | s | runs/s |",
                  "|---|---|---|---|---|"]  # fmt: skip
        for r in res["runner_ab"]:
            lines.append(
                f"| {r['schedule']} | {r['chunk']} | {r['max_in_flight']} | {r['seconds']:.2f} "
                f"| {r['traj_per_s']:.0f} |"
            )
    if res.get("skipped"):
        lines += ["", f"Skipped (past the deadline): {', '.join(res['skipped'])}"]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument(
        "--fig6-sizes", default="10000,100000", help="values of the Fig. 6 sweeps (fixed stop)"
    )
    ap.add_argument(
        "--converged-size",
        type=int,
        default=100000,
        help="values of the Fig. 6 sweep with converged stopping (0 to skip)",
    )
    ap.add_argument(
        "--map-size",
        type=int,
        default=1000,
        help="values per axis of the (eta, k12) map (converged stopping; 0 to skip)",
    )
    ap.add_argument(
        "--census-values",
        type=int,
        default=1000,
        help="values of the Fig. 6 census, 64 starts each (0 to skip)",
    )
    ap.add_argument(
        "--cpu-values", type=int, default=800, help="strided subsample run on all CPU cores"
    )
    ap.add_argument(
        "--cpu2-values", type=int, default=100, help="strided subsample run on 2 CPU cores"
    )
    ap.add_argument("--threads-per-block", type=int, default=cb.THREADS_PER_BLOCK)
    ap.add_argument(
        "--register-caps",
        default="0,128,96,64",
        help="register caps to scan (0 = the compiler's choice; '' to skip)",
    )
    ap.add_argument("--chunk", type=int, help="values per launch (default: the backend's)")
    ap.add_argument(
        "--map-budget-s", type=float, default=150.0, help="GPU seconds for the period map, about"
    )
    ap.add_argument(
        "--ab-size",
        type=int,
        default=100000,
        help="Fig. 6 values for the launch-schedule A/B (0 to skip)",
    )
    ap.add_argument(
        "--budget-s",
        type=float,
        default=45.0,
        help="GPU seconds per workload, about (then it reports the runs done)",
    )
    ap.add_argument(
        "--deadline-s",
        type=float,
        default=480.0,
        help="skip what is left after this many seconds (the JSON keeps what ran)",
    )
    ap.add_argument("--t-end", type=float, default=3000.0)
    ap.add_argument("--t-transient", type=float, default=2000.0)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "gpu.json"))
    args = ap.parse_args(argv)  # fmt: skip
    if SIM:  # testing this script: tiny workloads, and say loudly that this is no measurement
        print(
            "NUMBA_ENABLE_CUDASIM=1: numba's CUDA simulator, NOT a GPU; tiny workloads.",
            file=sys.stderr,
        )
        args.fig6_sizes, args.map_size, args.register_caps = "8", 2, ""
        args.converged_size, args.census_values, args.ab_size = 4, 2, 0
        args.cpu_values, args.cpu2_values, args.chunk, args.threads_per_block = 4, 2, 4, 4
        args.t_end, args.t_transient = 20.0, 10.0
        args.out = os.path.join(tempfile.gettempdir(), "stickslip_gpu_simulator.json")
    t_start = time.perf_counter()

    def log(msg):
        print(msg, file=sys.stderr, flush=True)

    asym = ssf.System.preset("asymmetric")
    fig6 = settings_for(args.t_end, args.t_transient, 256)
    conv = fig6.replace(stop="converged")
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
        "register_scan": [],
        "runner_ab": [],
        "skipped": [],
    }  # fmt: skip

    def save():
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(res, indent=1, default=float))

    log("compiling the kernel (first launch) ...")
    t0 = time.perf_counter()
    cb.compute_restart_chunk_cuda(asym, ("eta",), np.array([[5.0]]), asym.initial_state(None), fig6)
    res["compile_seconds"] = time.perf_counter() - t0
    res["kernel"] = kernel_facts(asym, args.threads_per_block)
    log(f"compiled in {res['compile_seconds']:.1f} s: {res['kernel']}")
    t0 = time.perf_counter()
    cpu_warm(asym, fig6)
    res["cpu_compile_seconds"] = time.perf_counter() - t0
    save()

    jobs = []
    for n in (int(x) for x in args.fig6_sizes.split(",") if x):
        jobs.append(
            (f"Fig. 6, {n} values", ("eta",), np.linspace(1.0, 10.0, n)[:, None], fig6, None)
        )
    if args.converged_size:
        n = args.converged_size
        jobs.append(
            (f"Fig. 6, {n} values", ("eta",), np.linspace(1.0, 10.0, n)[:, None], conv, None)
        )
    if args.census_values:
        from stickslip_fast.analysis.census import _check_starts

        nv = args.census_values
        starts, _ = _check_starts(asym, 64, None, None, 0, True, "eta", np.array([2.0]))
        v = np.repeat(np.linspace(1.0, 10.0, nv), len(starts))[:, None]
        st = np.tile(starts, (nv, 1))
        jobs.append((f"census, {nv} values x {len(starts)} starts", ("eta",), v,
                     settings_for(args.t_end, 0.0, 128).replace(stop="converged"), st))  # fmt: skip
    if args.map_size:
        m = args.map_size
        eta, k12 = np.meshgrid(np.linspace(1, 10, m), np.linspace(-0.9, 0.9, m), indexing="ij")
        vals = np.stack([eta.ravel(), k12.ravel()], axis=-1)
        jobs.append((f"period map {m}x{m} (eta, k12)", ("eta", "k12"), vals,
                     settings_for(args.t_end, args.t_transient, 64).replace(stop="converged"), None))  # fmt: skip
    for name, names, vals, settings, starts in jobs:
        if time.perf_counter() - t_start > args.deadline_s:
            res["skipped"].append(name)
            log(f"[{name}] skipped: past the deadline")
            continue
        budget = args.map_budget_s if name.startswith("period map") else args.budget_s
        res["workloads"].append(
            workload(name, asym, names, vals, settings, args, log, starts, budget)
        )
        save()
    if args.ab_size and time.perf_counter() - t_start < args.deadline_s:
        res["runner_ab"] = runner_ab(asym, fig6, args.ab_size, args.threads_per_block,
                                     args.budget_s, log)  # fmt: skip
        save()
    caps = [int(c) or None for c in args.register_caps.split(",") if c]
    if caps and time.perf_counter() - t_start < args.deadline_s:
        short = settings_for(1000.0, 500.0, 64)
        res["register_scan"] = register_scan(asym, short, caps, args.threads_per_block,
                                             args.budget_s / 3, log)  # fmt: skip
    elif caps:
        res["skipped"].append("register scan")
    save()
    print(markdown(res))
    log(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
