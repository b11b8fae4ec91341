"""The far ends of the multiple-shooting branches checked by the independent SciPy model.

``scripts/ms_far_sides.py`` follows Fig. 6's period-1 folds and its period-4 branch by
multiple shooting to leading multipliers of 1e45-1e48. Past ~1e16 the two CPUs we ran
it on part ways (docs/orbits.md), so are those points periodic orbits at all? Each is
checked here without the engine: its segments (``Branch.segments``) are integrated one
by one by ``tests/reference/scipy_segments.py`` (SciPy's Radau on the reference model
written from the paper, with its variational equations), which gives

* the continuity residual at every junction (max norm), and
* the leading multiplier of the segments' monodromies by orthogonal iteration,
  compared with the engine's (a periodic Schur decomposition of its own factors).

Checked: the first point of each branch whose multiplier passes 1e4, 1e8, ..., 1e44,
and its last point.

    PYTHONPATH=. python3 scripts/ms_far_check.py [upper] [lower] [p4-multiple]
        [--out FILE]

The run of 2026-11-27 is benchmarks/results/ms_far_check.json (docs/orbits.md).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))
sys.path.insert(0, str(ROOT / "tests" / "reference"))

import scipy_segments as sg  # noqa: E402
from ms_far_sides import CASES  # noqa: E402

from benchmarks.common import machine_info  # noqa: E402

#: Decades of the leading multiplier at which a point is checked
DECADES = tuple(range(4, 48, 4))


def points_to_check(branch) -> list[int]:
    """The first multiple-shooting point past each of :data:`DECADES`, and the last."""
    lead = np.max(np.abs(branch.multipliers), axis=1)
    have = np.array([seg is not None for seg in branch.segments])
    picks = []
    for d in DECADES:
        idx = np.flatnonzero(have & (lead >= 10.0**d))
        if idx.size:
            picks.append(int(idx[0]))
    last = int(np.flatnonzero(have)[-1])
    return sorted(set(picks + [last]))


def check_point(branch, i: int) -> dict:
    """The SciPy check of point ``i`` of ``branch``."""
    mesh, starts = branch.segments[i]
    system = branch.system.replace(**{branch.param: float(branch.values[i])})
    p = {**system.to_dict(), "n_oscillators": system.n_oscillators}
    t0 = time.perf_counter()
    ref = sg.check_segments(p, mesh, starts, float(branch.T[i]))
    mu = float(np.max(np.abs(branch.multipliers[i])))
    out = {
        "index": i,
        "eta": float(branch.values[i]),
        "T": float(branch.T[i]),
        "segments": int(mesh.size - 1),
        "mu_engine": mu,
        "mu_scipy": ref["mu1"],
        "mu_relative_difference": ref["mu1"] / mu - 1.0,
        "max_junction_residual": ref["residual"],
        "max_segment_norm": float(ref["norms"].max()),
        "seconds": time.perf_counter() - t0,
    }
    print(json.dumps(out), flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    names = ("upper", "lower", "p4-multiple")
    p.add_argument("cases", nargs="*", help=f"some of {names} (default: all)")
    p.add_argument("--max-points", type=int, default=400)
    p.add_argument("--out", default=None, help="write the checks as JSON here")
    args = p.parse_args(argv)
    if set(args.cases) - set(names):
        p.error(f"unknown case(s) {sorted(set(args.cases) - set(names))}; choose from {names}")
    res = []
    for c in args.cases or names:
        name, branch, seconds = CASES[c](True, args.max_points)
        print(f"{name}: {branch.values.size} points, {branch.status} ({seconds:.0f} s)", flush=True)
        checks = [check_point(branch, i) for i in points_to_check(branch)]
        res.append({"case": name, "status": branch.status, "points": int(branch.values.size),
                    "engine_seconds": seconds, "checks": checks, "machine": machine_info()})  # fmt: skip
    if args.out:
        Path(args.out).write_text(json.dumps(res, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
