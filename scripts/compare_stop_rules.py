"""Converged stopping against the fixed window, on every sweep config in data/.

For each sweep config: a grid of values (``--num`` per axis of a 1-D sweep,
``--num-2d`` per axis of a 2-D one) run with ``stop="fixed"`` (the config's
t_end / t_transient window) and with ``stop="converged"`` (same t_end as the
cap). A value agrees when status and period are equal and, for orbits, the
last ``period`` points of both runs coincide up to a cyclic shift within
``--tol`` (max norm). Writes a Markdown table and a CSV of every disagreement.

Usage::

    python3 scripts/compare_stop_rules.py --out OUT.md --csv OUT.csv

with OUT under ``benchmarks/results/stop_rules_<date>/``: docs/converged.md cites the
run of 2026-11-27 (``now.md``, ``now.csv``) and explains its disagreements by hand.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import stickslip_fast as ssf
from stickslip_fast.cli.config import load_config

ROOT = Path(__file__).resolve().parents[1]


def _cycle_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Smallest max-norm distance between two point cycles up to a cyclic shift."""
    return min(float(np.abs(np.roll(b, k, axis=0) - a).max()) for k in range(len(a)))


def agreement(st_a, pe_a, pts_a, cnt_a, st_b, pe_b, pts_b, cnt_b, tol: float):
    """Per value: do two diagrams agree, and how far apart are their last cycles.

    Agreement: same status and period and, for orbits, the last ``period`` points
    within ``tol`` (max norm) up to a cyclic shift. Returns (bool array, distance array;
    distance 0 where no cycle was compared).
    """
    ok = np.zeros(st_a.size, dtype=bool)
    dist = np.zeros(st_a.size)
    for i in range(st_a.size):
        ok[i] = st_a[i] == st_b[i] and pe_a[i] == pe_b[i]
        if ok[i] and st_a[i] == "ok" and pe_a[i] > 0:
            p = int(pe_a[i])
            a = pts_a[i, cnt_a[i] - p : cnt_a[i]]
            b = pts_b[i, cnt_b[i] - p : cnt_b[i]]
            dist[i] = _cycle_distance(a, b)
            ok[i] = dist[i] <= tol
    return ok, dist


def sweep_configs(num: int, num_2d: int, only: str | None):
    """Every sweep config in data/ on a grid over its own range.

    Yields (path, config, param, values, sweep keyword arguments): ``num`` values for a
    1-D sweep, ``num_2d`` per axis of a 2-D one; the config's integration settings,
    start and mode.
    """
    for path in sorted((ROOT / "data").glob("*.toml")):
        if only and only not in path.name:
            continue
        cfg = load_config(path)
        if cfg.sweep is None:
            continue
        param = cfg.sweep["param"]
        if isinstance(param, tuple):
            values = tuple(np.linspace(v[0], v[-1], num_2d) for v in cfg.sweep["values"])
        else:
            values = np.linspace(cfg.sweep["values"][0], cfg.sweep["values"][-1], num)
        kw = dict(cfg.integration)
        kw.update(y0=cfg.y0, mode=cfg.sweep.get("mode", "restart"), progress=False)
        yield path, cfg, param, values, kw


def compare(num: int, num_2d: int, tol: float, only: str | None):
    rows, bad = [], []
    for path, cfg, param, values, kw in sweep_configs(num, num_2d, only):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t0 = time.perf_counter()
            fixed = ssf.sweep(cfg.system, param, values, **kw)
            t_fixed = time.perf_counter() - t0
            t0 = time.perf_counter()
            conv = ssf.sweep(cfg.system, param, values, stop="converged", **kw)
            t_conv = time.perf_counter() - t0
        st_f, st_c = fixed.status.ravel(), conv.status.ravel()
        pe_f, pe_c = fixed.period.ravel(), conv.period.ravel()
        pts_f = fixed.points.reshape(-1, *fixed.points.shape[-2:])
        pts_c = conv.points.reshape(-1, *conv.points.shape[-2:])
        cnt_f, cnt_c = fixed.count.ravel(), conv.count.ravel()
        tc = conv.t_converged.ravel()
        grid = (
            np.stack(np.meshgrid(*values, indexing="ij"), -1).reshape(-1, len(values))
            if isinstance(values, tuple)
            else values[:, None]
        )
        if cfg.sweep.get("mode") == "continuation-both":
            grid = np.concatenate([grid, grid])
        ok, dist = agreement(st_f, pe_f, pts_f, cnt_f, st_c, pe_c, pts_c, cnt_c, tol)
        agree = int(ok.sum())
        for i in np.flatnonzero(~ok):
            bad.append(dict(
                config=path.stem, value=" ".join(f"{x:.6g}" for x in grid[i]),
                fixed=f"{st_f[i]}/P{pe_f[i]}", converged=f"{st_c[i]}/P{pe_c[i]}",
                distance=f"{dist[i]:.3g}", t_converged=f"{tc[i]:.1f}",
            ))  # fmt: skip
        finite = tc[np.isfinite(tc)]
        rows.append(dict(
            config=path.stem, values=st_f.size, agree=agree,
            not_converged=int(np.count_nonzero(~np.isfinite(tc))),
            median_t=float(np.median(finite)) if finite.size else float("nan"),
            max_t=float(finite.max()) if finite.size else float("nan"),
            t_end=cfg.integration["t_end"], time_fixed=t_fixed, time_conv=t_conv,
        ))  # fmt: skip
        print(
            f"{path.stem}: {agree}/{st_f.size} agree, {t_fixed:.1f} s -> {t_conv:.1f} s",
            file=sys.stderr,
        )
    return rows, bad


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--num", type=int, default=100)
    ap.add_argument("--num-2d", type=int, default=10)
    ap.add_argument("--tol", type=float, default=1e-6)
    ap.add_argument("--only")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--csv", type=Path)
    args = ap.parse_args()
    rows, bad = compare(args.num, args.num_2d, args.tol, args.only)
    total = sum(r["values"] for r in rows)
    agree = sum(r["agree"] for r in rows)
    lines = [
        "| config | values | agree | not converged by t_end | median / max t_converged | t_end | time fixed / converged |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['config']} | {r['values']} | {r['agree']} | {r['not_converged']} | "
            f"{r['median_t']:.0f} / {r['max_t']:.0f} | {r['t_end']:.0f} | "
            f"{r['time_fixed']:.1f} s / {r['time_conv']:.1f} s ({r['time_fixed'] / r['time_conv']:.1f}x) |"
        )
    lines.append(f"| **all** | {total} | {agree} ({100 * agree / total:.2f}%) | | | | |")
    args.out.write_text("\n".join(lines) + "\n")
    if args.csv:
        with args.csv.open("w", newline="") as fh:
            w = csv.DictWriter(
                fh, fieldnames=["config", "value", "fixed", "converged", "distance", "t_converged"]
            )
            w.writeheader()
            w.writerows(bad)
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
