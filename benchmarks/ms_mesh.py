"""Multiple shooting's mesh: refined cuts against even cuts, pace and precision.

``python -m benchmarks.ms_mesh [--rounds 2]``. The in-phase branch of two symmetric
disks on one DC motor (the walk of docs/orbits.md, "The step's measure"), continued
by multiple shooting with three meshes, and by single shooting for reference:

* ``refined``: the default, 8 even cuts refined by :func:`refine_mesh` until no segment
  amplifies by more than ``MESH_LIMIT`` = 10 (here into 24-26 segments);
* ``even8``: the 8 even cuts alone (``max_segments=8``);
* ``even24``: 24 even cuts (``segments=24, max_segments=24``).

Two walks each: ``long``, eta 3 -> 5 at the defaults, and ``window``, eta 4.762 -> 4.766
through the symmetry-breaking point (reference 4.7638949: a secant at rtol 1e-12,
tests/test_sync_stability.py). Reported per walk: points, wall time (one thread, the
best of ``--rounds``, the meshes alternating), the SB point and its error, the segments,
and the slip speed (in units of eps, the smaller of the two disks') at every cut of
the start's mesh: a cut in a disk's breakaway from sticking (slip ~1-100 eps) is where
the refined mesh puts most of its cuts. For the long walk, the end's T and leading
multiplier against single shooting's. Results: ``benchmarks/results/ms_mesh.json``.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # benchmark this checkout, not an installed copy
    sys.path.insert(0, str(ROOT))

import numba  # noqa: E402
import numpy as np  # noqa: E402

import stickslip_fast as ssf  # noqa: E402
from stickslip_fast.bifurcation.stickphases import slip_velocity  # noqa: E402

SB_REFERENCE = 4.7638949
MESHES = {
    "refined": dict(shooting="multiple"),
    "even8": dict(shooting="multiple", segments=8, max_segments=8),
    "even24": dict(shooting="multiple", segments=24, max_segments=24),
    "single": dict(shooting="single"),
}
WALKS = {"long": (3.0, (3.0, 5.0)), "window": (4.762, (4.762, 4.766))}


def _orbit(eta: float) -> ssf.Orbit:
    system = ssf.System.preset("symmetric", drive="dc-motor", n_oscillators=2, eta=eta)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ssf.SynchronousStartWarning)
        run = ssf.simulate(system, 3000, 2000)
    return ssf.find_orbit(system, run)


def _cut_slips(branch: ssf.Branch) -> list[float] | None:
    """Slip speed / eps (the smaller disk's) at each cut of the branch's first mesh."""
    seg = branch.segments[0] if branch.segments else None
    if seg is None:
        return None
    system = branch.orbit_at(0).system
    starts = np.asarray(seg[1])
    slips = [np.hypot(*slip_velocity(system, starts, i)) for i in range(system.n_oscillators)]
    return np.round(np.min(slips, axis=0) / system.eps, 3).tolist()


def _summary(branch: ssf.Branch, seconds: float) -> dict:
    sb = [b.value for b in branch.bifurcations if b.kind == "symmetry-breaking"]
    seg = branch.segments[0] if branch.segments else None
    return {
        "points": int(branch.values.size),
        "seconds": seconds,
        "status": branch.status,
        "end": float(branch.values[-1]),
        "sb": sb,
        "sb_error": [abs(v - SB_REFERENCE) for v in sb],
        "segments": None if seg is None else int(len(seg[0]) - 1),
        "cut_slip_over_eps": _cut_slips(branch),
        "end_T": float(branch.T[-1]),
        "end_leading_multiplier": float(np.max(np.abs(branch.multipliers[-1]))),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks/results/ms_mesh.json")
    args = ap.parse_args()
    numba.set_num_threads(1)  # the meshes' own cost, not the threads'
    orbits = {name: _orbit(eta) for name, (eta, _) in WALKS.items()}
    best: dict = {}
    for _ in range(args.rounds):
        for walk, (_, bounds) in WALKS.items():
            for mesh, kw in MESHES.items():
                t0 = time.perf_counter()
                branch = ssf.continue_orbit(orbits[walk], "eta", bounds, progress=False, **kw)
                dt = time.perf_counter() - t0
                key = f"{walk}/{mesh}"
                if key not in best or dt < best[key]["seconds"]:
                    best[key] = _summary(branch, dt)
    ref = best["long/single"]
    for mesh in MESHES:
        r = best[f"long/{mesh}"]
        r["end_T_minus_single"] = r["end_T"] - ref["end_T"]
        r["end_multiplier_minus_single"] = (
            r["end_leading_multiplier"] - ref["end_leading_multiplier"]
        )
    report = {
        "machine": platform.processor() or platform.machine(),
        "threads": 1,
        "rounds": args.rounds,
        "sb_reference": SB_REFERENCE,
        "results": best,
    }
    args.out.write_text(json.dumps(report, indent=1) + "\n")
    for key, r in best.items():
        sb = ", ".join(f"{v:.9f} ({e:.1e})" for v, e in zip(r["sb"], r["sb_error"]))
        print(f"{key}: {r['points']} points, {r['seconds']:.2f} s, {r['status']} at "
              f"{r['end']:g}, segments {r['segments']}, SB {sb or '-'}")  # fmt: skip
        if r["cut_slip_over_eps"] is not None:
            print(f"    slip / eps at the cuts: {r['cut_slip_over_eps']}")


if __name__ == "__main__":
    main()
