"""``method="auto"`` against ``rodas5p`` across parameter sets, drives, disks and tolerances.

The fair benchmark (:mod:`benchmarks.autoswitch`) and the diagrams of ``data/``
(:mod:`benchmarks.autoswitch_configs`) test ``auto`` on the asymmetric set and at rtol
1e-9. This scan runs every combination of the three parameter sets, both drives, one and
two disks, eta in {1.5, 3, 6, 9} and rtol in {1e-3, 1e-4, 1e-5, 1e-6} (192 runs of t 1000,
points after 500, atol = 0.01 rtol; two disks start 0.01 apart in x1), once with each
method, one core, and reports the total time per rtol, the runs where ``auto`` is
slowest against ``rodas5p`` and the labels that differ. It found ``auto``'s explicit mode
chattering in the stick band (docs/performance.md, "The stick band's stiffness").

``--old-root DIR`` runs the same scan on another checkout's ``auto`` in a subprocess
with its own Numba cache, for a before/after comparison in one run.

Result: ``results/autoswitch_scan_<date>.json`` (``--out``), with the machine.

    python3 -m benchmarks.autoswitch_scan [--old-root DIR] [--max-steps N]
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"
PRESETS = ("asymmetric", "literature", "symmetric")
DRIVES = ("constant", "dc-motor")
DISKS = (1, 2)
ETAS = (1.5, 3.0, 6.0, 9.0)
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6)
METHODS = ("auto", "rodas5p")


def scan(max_steps: int) -> list[dict]:
    """One run of each method per case; the package imported from ``sys.path``."""
    import stickslip_fast as ssf

    package = ssf.__file__
    warnings.simplefilter("ignore")  # the synchronous-start warning of two disks
    # compile (or load) every kernel first: time the runs, not the compiles
    for drive, n, method in itertools.product(DRIVES, DISKS, METHODS):
        ssf.simulate(ssf.System.preset("asymmetric", n_oscillators=n, drive=drive), 1.0,
                     method=method)  # fmt: skip
    rows = []
    for preset, drive, n, eta, rtol in itertools.product(PRESETS, DRIVES, DISKS, ETAS, RTOLS):
        system = ssf.System.preset(preset, eta=eta, n_oscillators=n, drive=drive)
        y0 = None
        if n == 2:  # the disks 0.01 apart in x1
            y0 = np.zeros(system.n_state)
            y0[0] = 0.01
        row = dict(preset=preset, drive=drive, n=n, eta=eta, rtol=rtol, package=package)
        for method in METHODS:
            t0 = time.perf_counter()
            r = ssf.simulate(system, 1000.0, 500.0, y0=y0, rtol=rtol, atol=0.01 * rtol,
                             method=method, max_steps=max_steps)  # fmt: skip
            row[method] = dict(status=r.status, period=int(r.period),
                               time=time.perf_counter() - t0, steps=int(r.n_steps))  # fmt: skip
        rows.append(row)
    return rows


def summarise(rows: list[dict]) -> dict:
    """Totals per rtol, the slowest cases of auto against rodas5p, labels that differ."""
    totals = {}
    for r in rows:
        t = totals.setdefault(f"{r['rtol']:g}", {"auto": 0.0, "rodas5p": 0.0})
        t["auto"] += r["auto"]["time"]
        t["rodas5p"] += r["rodas5p"]["time"]
    worst = sorted(rows, key=lambda r: -r["auto"]["time"] / r["rodas5p"]["time"])[:8]
    differ = [r for r in rows
              if (r["auto"]["status"], r["auto"]["period"]) != (r["rodas5p"]["status"], r["rodas5p"]["period"])]  # fmt: skip
    ratio = {}
    for r in rows:
        k = f"{r['rtol']:g}"
        ratio[k] = max(ratio.get(k, 0.0), r["auto"]["time"] / r["rodas5p"]["time"])
    return dict(totals=totals, worst_ratio=ratio, worst=worst, labels_differ=differ, rows=rows,
                max_steps_auto=sum(r["auto"]["status"] == "max-steps" for r in rows),
                max_steps_rodas5p=sum(r["rodas5p"]["status"] == "max-steps" for r in rows))  # fmt: skip


def _in_checkout(root: Path, max_steps: int) -> list[dict]:
    """The scan on another checkout, in a child process with a fresh Numba cache."""
    with tempfile.TemporaryDirectory() as cache:
        # run as a script: its folder, not this checkout's root, leads sys.path
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=str(root))
        cmd = [sys.executable, __file__, "--child", "--max-steps", str(max_steps)]
        out = subprocess.run(cmd, env=env, cwd=root, check=True, capture_output=True, text=True)
    rows = json.loads(out.stdout.strip().splitlines()[-1])
    assert rows[0]["package"].startswith(str(root)), rows[0]["package"]
    return rows


def _log_summary(label: str, s: dict) -> None:
    tot = ", ".join(f"rtol {k}: auto {v['auto']:.2f} s, rodas5p {v['rodas5p']:.2f} s"
                    for k, v in s["totals"].items())  # fmt: skip
    tot += "; worst auto / rodas5p " + ", ".join(
        f"{k}: {v:.1f}x" for k, v in s["worst_ratio"].items()
    )
    print(
        f"{label}: {tot}; max-steps auto {s['max_steps_auto']}, rodas5p "
        f"{s['max_steps_rodas5p']}; labels differ in {len(s['labels_differ'])} runs",
        flush=True,
    )
    for r in s["worst"][:4]:
        print(
            f"  {r['preset']} {r['drive']} N={r['n']} eta={r['eta']} rtol={r['rtol']:g}: "
            f"auto {r['auto']['status']} {r['auto']['time'] * 1e3:.1f} ms "
            f"({r['auto']['steps']} steps), rodas5p {r['rodas5p']['time'] * 1e3:.1f} ms",
            flush=True,
        )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old-root", type=Path, help="another checkout to scan as well")
    ap.add_argument("--max-steps", type=int, default=20_000_000)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--out", type=Path,
                    default=RESULTS / f"autoswitch_scan_{time.strftime('%Y-%m-%d')}.json")  # fmt: skip
    args = ap.parse_args(argv)
    if args.child:  # the scan of another checkout (_in_checkout)
        print(json.dumps(scan(args.max_steps)))
        return 0
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from benchmarks.common import machine_info, write_result

    started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
    result = dict(machine=machine_info(), started=started, cases=len(PRESETS) * len(DRIVES)
                  * len(DISKS) * len(ETAS) * len(RTOLS))  # fmt: skip
    if args.old_root is not None:
        old = summarise(_in_checkout(args.old_root.resolve(), args.max_steps))
        result["old"] = dict(root=str(args.old_root), **old)
        _log_summary(f"old ({args.old_root})", old)
    new = summarise(scan(args.max_steps))
    result["new"] = new
    _log_summary("this checkout", new)
    write_result(args.out, result, print)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
