"""Are the transients in data/*.toml long enough? Compare t_transient T with 2T.

Usage::

    python scripts/check_transients.py [--num 50] [--out OUT_DIR] [--csv docs/transients.csv]

For every sweep config in data/ (fig*.toml with a [sweep] section) it runs a
coarse grid of ``--num`` values over the same range twice: with the config's
t_transient T, and with 2T and the recording window t_end - T unchanged
(t_end' = t_end + T). Per value it compares the status, the period and the
Poincare points: for a period-p orbit, each of the last p points of one run is
matched to the nearest of the last p points of the other (the phase of the
window differs); the largest distance (max norm over the state) is the point
difference. A value *agrees* when the statuses and periods are equal and the
point difference is below ``--tol`` (default 1e-4; for rest states the final
states are compared). Results are written to a CSV and summarised per config.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast.cli.config import load_config  # noqa: E402

__all__ = ["orbit_distance", "compare", "main"]


def orbit_distance(a: np.ndarray, b: np.ndarray, period: int) -> float:
    """Largest distance between the last ``period`` points of two runs, matched as sets.

    Parameters
    ----------
    a, b : ndarray, shape (k, n_state)
        Poincare points (NaN-padded rows are dropped).
    period : int
        Number of points per orbit (>= 1).

    Returns
    -------
    float
        max over points of a of the min max-norm distance to the points of b
        (symmetrised); NaN if either has fewer than ``period`` points.
    """
    a = a[np.all(np.isfinite(a), axis=1)][-period:]
    b = b[np.all(np.isfinite(b), axis=1)][-period:]
    if len(a) < period or len(b) < period:
        return float("nan")
    d = np.max(np.abs(a[:, None, :] - b[None, :, :]), axis=-1)
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


def compare(r1, r2, tol: float) -> list[dict]:
    """Per-value comparison rows of two 1-D sweep results over the same values."""
    rows = []
    for i, v in enumerate(np.asarray(r1.values)):
        s1, s2 = str(r1.status[i]), str(r2.status[i])
        p1, p2 = int(r1.period[i]), int(r2.period[i])
        if s1 == s2 == "ok" and p1 == p2 and p1 > 0:
            dist = orbit_distance(r1.points[i], r2.points[i], p1)
        elif s1 == s2 and s1 in ("equilibrium", "stalled"):
            dist = float(np.max(np.abs(r1.final_state[i] - r2.final_state[i])))
        else:
            dist = float("nan")
        agree = s1 == s2 and p1 == p2 and (dist <= tol if np.isfinite(dist) else s1 == "ok")
        if s1 == s2 == "ok" and p1 == p2 == 0:
            agree = True  # no period <= 64 in both: nothing sharper to compare
        rows.append(dict(value=float(v), status_T=s1, status_2T=s2, period_T=p1, period_2T=p2,
                         point_diff=dist, agree=bool(agree)))  # fmt: skip
    return rows


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--num", type=int, default=50, help="values per config (default 50)")
    p.add_argument("--tol", type=float, default=1e-4, help="point agreement tolerance")
    p.add_argument("--only", help="comma-separated config name fragments")
    p.add_argument("--out", default="transients_check", help="folder for the sweep files")
    p.add_argument("--csv", default=str(ROOT / "docs" / "transients.csv"))
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    all_rows = []
    for path in sorted((ROOT / "data").glob("fig*.toml")):
        if args.only and not any(f in path.name for f in args.only.split(",")):
            continue
        cfg = load_config(path)
        if cfg.sweep is None or not isinstance(cfg.sweep["param"], str):
            continue
        vals = np.asarray(cfg.sweep["values"])
        grid = np.linspace(vals[0], vals[-1], args.num)
        integ = dict(cfg.integration)
        T = float(integ["t_transient"])
        res = {}
        t0 = time.perf_counter()
        for label, shift in (("T", 0.0), ("2T", T)):
            kw = dict(integ)
            kw["t_end"] = float(integ["t_end"]) + shift
            kw["t_transient"] = T + shift
            with warnings.catch_warnings():
                warnings.filterwarnings("ignore", message=".*gave no orbit.*")
                res[label] = ssf.sweep(
                    cfg.system, cfg.sweep["param"], grid, y0=cfg.y0,
                    mode=cfg.sweep.get("mode", "restart"), progress=False,
                    out=out / f"{path.stem}_{label}_{args.num}.h5", **kw,
                )  # fmt: skip
        rows = compare(res["T"], res["2T"], args.tol)
        n_ok = sum(r["agree"] for r in rows)
        print(f"{path.stem}: T={T:g}, window={float(integ['t_end']) - T:g}: "
              f"{n_ok}/{len(rows)} agree ({time.perf_counter() - t0:.0f} s)")  # fmt: skip
        for r in rows:
            if not r["agree"]:
                print(f"   {cfg.sweep['param']}={r['value']:.4f}: {r['status_T']}/P{r['period_T']}"
                      f" vs {r['status_2T']}/P{r['period_2T']}, point diff {r['point_diff']:.2e}")  # fmt: skip
            all_rows.append({"config": path.stem, "t_transient": T, **r})
    if all_rows:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(all_rows[0]))
            w.writeheader()
            w.writerows(all_rows)
        print(f"wrote {args.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
