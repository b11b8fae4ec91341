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
import traceback
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import (  # noqa: E402
    converged,
    peer_diagram,
    peer_precision,
    profile_kernel,
    speed_targets,
    startup,
    sweeps,
    tableaus,
    work_precision,
)
from benchmarks.common import SWEEP_IMPL, machine_info  # noqa: E402
from benchmarks.summary import write_summary  # noqa: E402

SECTIONS = (
    "work_precision",
    "sweep_throughput",
    "parallel_scaling",
    "n_scaling",
    "startup",
    "memory",
    "peers_trajectory",
    "peers_diagram",
    "kernel_profile",
    "converged_stopping",
    "tableaus",
    "first_run",
    "auto_tolerance_rules",
    "multirate_bound",
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
    ap.add_argument(
        "--merge", action="store_true", help="update these sections in an existing results.json"
    )
    args = ap.parse_args(argv)
    mode = "quick" if args.quick else "full"
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()

    def log(msg):
        print(f"[{time.perf_counter() - t_start:7.1f} s] {msg}", flush=True)

    results = dict(mode=mode, machine=machine_info(), sweep_impl=SWEEP_IMPL, sections={})
    if args.merge and (out / "results.json").exists():
        old = json.loads((out / "results.json").read_text())
        results["sections"] = old["sections"]
        results["merged_runs"] = old.get("merged_runs", []) + [sorted(args.only or SECTIONS)]
        results["machine"]["previous_run_machine"] = old["machine"]
        results["superseded"] = old.get("superseded", {})
        for name in args.only or SECTIONS:
            if name in old["sections"]:
                results["superseded"].setdefault(name, []).append(old["sections"][name])
    want = set(args.only or SECTIONS)
    sec = results["sections"]
    plan = [  # start-up first: its child processes compile into their own cache
        ("startup", lambda: startup.run(mode, log)),
        ("work_precision", lambda: work_precision.run(mode, log)),
        ("sweep_throughput", lambda: sweeps.throughput(mode, log)),
        ("parallel_scaling", lambda: sweeps.parallel_scaling(mode, log)),
        ("n_scaling", lambda: sweeps.n_scaling(mode, log)),
        ("memory", lambda: sweeps.memory(mode, log)),
        ("peers_trajectory", lambda: peer_precision.run(mode, log)),
        ("peers_diagram", lambda: peer_diagram.run(mode, log)),
        ("kernel_profile", lambda: profile_kernel.run(mode, log)),
        ("converged_stopping", lambda: converged.run(mode, log)),
        ("tableaus", lambda: tableaus.run(mode, log)),
        # issue 30's targets with their floors (summary_targets.py); full run only
        ("first_run", lambda: speed_targets.first_run_section(mode, log)),
        ("auto_tolerance_rules", lambda: speed_targets.auto_section(mode, log)),
        ("multirate_bound", lambda: speed_targets.multirate_section(mode, log)),
    ]
    failed = []
    for name, fn in plan:
        if name not in want:
            continue
        log(f"== {name}")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)  # sweeps warn about equilibria
                sec[name] = fn()
        except Exception:  # noqa: BLE001 - record and go on with the other sections
            sec[name] = dict(status="error", traceback=traceback.format_exc()[-4000:])
            failed.append(name)
            log(f"   {name} FAILED:\n{sec[name]['traceback']}")
            continue
        if name == "work_precision":
            work_precision.plot(sec[name], out / "work_precision.png")
        if name == "n_scaling":
            sweeps.plot(sec, out / "n_scaling.png")
        if name == "peers_diagram":
            peer_diagram.plot(sec[name], out / "diagram_work_precision.png")
        (out / "results.json").write_text(json.dumps(_clean(results), indent=1))
    if "merged_runs" in results:  # keep the full run's total; record this one apart
        results["total_wall_s"] = old.get("total_wall_s", 0.0)
        results["last_merge_wall_s"] = time.perf_counter() - t_start
    else:
        results["total_wall_s"] = time.perf_counter() - t_start
    import os

    results["machine"]["loadavg_at_end"] = list(os.getloadavg())
    results = _clean(results)
    (out / "results.json").write_text(json.dumps(results, indent=1))
    (out / "summary.md").write_text(write_summary(results))
    log(f"done in {results['total_wall_s']:.0f} s; wrote {out}/results.json, summary.md, PNGs")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
