"""What a continuation's checkpoint costs, and what a resume saves (base/journal.py).

One fold curve of Fig. 6's period-1 orbit in (eta, k12) (the test case of
``tests/test_foldcurve_orbit.py``), warm kernels, run in turn ``--repeats`` times each:

``none``
    no checkpoint;
``fresh``
    a new checkpoint file (every return-map integration hashed, encoded, appended and
    flushed);
``replay``
    the same call on the finished file (every integration answered from it: the cost of
    resuming a run killed at its very end).

Prints one line per run and writes the runs, the file's size and the machine to
``--out`` (JSON).

    python -m benchmarks.checkpoint --repeats 3 --out benchmarks/results/checkpoint.json
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

import stickslip_fast as ssf

from .common import machine_info

# the stable period-1 orbit at eta = 3.3, k12 = -0.8
Z33 = np.array([0.07332092304307371, 0.0, 0.12221581726865255, -0.00674109106906407])


def _fold():
    s = ssf.System.preset("asymmetric", eta=3.30, k12=-0.8)
    orbit = ssf.find_orbit(s, Z33, 1)
    branch = ssf.continue_orbit(orbit, "eta", (3.30, 3.35), ds=2e-3, ds_max=5e-3,
                                max_points=100, stick_events=False, progress=False)  # fmt: skip
    return branch, next(b for b in branch.bifurcations if b.kind == "fold")


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--points", type=int, default=40, help="max_points of the curve")
    p.add_argument("--out", type=Path, default=None)
    args = p.parse_args(argv)
    branch, fold = _fold()
    kw = dict(direction=-1, ds=0.002, ds_max=0.01, max_points=args.points, progress=False)
    ref = ssf.continue_bifurcation(branch, fold, "k12", (-0.806, -0.79), **kw)  # warm
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "curve.ckpt"
        for rep in range(args.repeats):
            for mode in ("none", "fresh", "replay"):
                if mode == "fresh":
                    path.unlink(missing_ok=True)
                t0 = time.perf_counter()
                c = ssf.continue_bifurcation(branch, fold, "k12", (-0.806, -0.79),
                                             checkpoint=None if mode == "none" else path,
                                             **kw)  # fmt: skip
                wall = time.perf_counter() - t0
                assert np.array_equal(c.values, ref.values), "a checkpoint changed the curve"
                runs.append({"repeat": rep, "mode": mode, "wall_s": wall})
                print(f"{rep} {mode:6s} {wall:7.3f} s  {len(c.values)} points")
        size = path.stat().st_size
    med = {m: float(np.median([r["wall_s"] for r in runs if r["mode"] == m]))
           for m in ("none", "fresh", "replay")}  # fmt: skip
    print(f"median: none {med['none']:.3f} s, fresh {med['fresh']:.3f} s "
          f"(x{med['fresh'] / med['none']:.3f}), replay {med['replay']:.3f} s "
          f"(1/{med['none'] / med['replay']:.1f}); file {size} bytes, "
          f"{size / len(ref.values):.0f} per point")  # fmt: skip
    if args.out is not None:
        info = {"machine": machine_info(), "load": os.getloadavg(), "points": len(ref.values),
                "file_bytes": size, "median_s": med, "runs": runs}  # fmt: skip
        args.out.write_text(json.dumps(info, indent=1) + "\n")


if __name__ == "__main__":
    main()
