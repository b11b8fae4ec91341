"""Seeds for a saddle's stable manifold from the saddle alone, on the rest plane (docs/basins.md).

``ssf.manifold_seeds`` scans g_n = w . (P^n(p) - x*) over an n x n grid of the (x1, phi1)
plane at rest ([-0.3, 0.3]^2, the basin maps' box) and roots its sign changes on grid
edges; ``stable_manifold(..., seeds=...)`` traces from them. Saddles: ``p2``, the unstable
P2 at eta = 9.73102 (scripts/basins_manifold.py ``p2_saddle``, cached in
out/basins/p2_saddle.json), and ``fold``, the P1 saddle past the upper fold (cached in
out/basins/fold_saddle.json). Prints the edges, the seeds, how close the grid's crossings
come to the orbit, and the traced curve.

Usage: ``python3 scripts/basins_manifold_seeds.py [p2|fold] [N] [N_MAX]`` (defaults p2 16 20).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import stickslip_fast as ssf

sys.path.insert(0, str(Path(__file__).parent))
import basins_manifold as bmf  # noqa: E402

if __name__ == "__main__":
    which = sys.argv[1] if len(sys.argv) > 1 else "p2"
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 16
    n_max = int(sys.argv[3]) if len(sys.argv) > 3 else 20
    bmf.OUT.mkdir(parents=True, exist_ok=True)
    t0 = time.time()
    orb = bmf.p2_saddle() if which == "p2" else bmf.fold_saddle()
    r_local = 1e-5 if which == "p2" else 1e-6
    print(f"[saddle: {time.time() - t0:.0f} s]", flush=True)
    t1 = time.time()
    box = [[-0.3, 0.3], [-0.3, 0.3]]
    plane = dict(plane=("x1", "phi1"), bounds=box)
    sc = ssf.manifold_seeds(orb.system, orb, grid=n, n_max=n_max, r_local=r_local, **plane)
    cl = sc["closest"]
    print(f"scan {n} x {n}, n <= {n_max}: {len(sc['edge_status'])} sign-change edges "
          f"{ {k: sc['edge_status'].count(k) for k in set(sc['edge_status'])} }, "
          f"{len(sc['uv'])} seeds, {sc['n_evals']} evaluations [{time.time() - t1:.0f} s]")  # fmt: skip
    print(f"closest approach of a node's crossings to the orbit: min {cl.min():.2e}, "
          f"nodes within 1e-2: {int(np.sum(cl <= 1e-2))}, 1e-3: {int(np.sum(cl <= 1e-3))}, "
          f"1e-4: {int(np.sum(cl <= 1e-4))}; median {np.median(cl):.2e}")  # fmt: skip
    k = np.unravel_index(np.argmin(cl), cl.shape)
    print(f"  closest node: ({sc['g1'][k[0]]:.4f}, {sc['g2'][k[1]]:.4f})")
    for e, en, st in zip(sc["edges"], sc["edge_n"], sc["edge_status"]):
        print(f"  edge {np.round(e, 4).tolist()}: n = {en}, {st}")
    if len(sc["uv"]):
        print("seeds:", np.array2string(sc["uv"], precision=6), "n", sc["n"], "distance",
              np.array2string(sc["distance"], precision=2))  # fmt: skip
        t2 = time.time()
        m = ssf.stable_manifold(orb.system, orb, seeds=sc["uv"], ds=2e-3, r_local=r_local,
                                n_max=n_max, max_points=60, skip_radius=0.15 / n, **plane)  # fmt: skip
        print(f"manifold: {len(m.u)} points, branches {m.branch_status}, seeds "
              f"{m.settings['seed_status']}, n {np.unique(m.n).tolist()}, {m.n_evals} "
              f"evaluations [{time.time() - t2:.0f} s]")  # fmt: skip
        np.savez(bmf.OUT / f"{which}_rest_manifold_scan{n}.npz", u=m.u, v=m.v, branch=m.branch,
                 seeds=sc["uv"], closest=cl)  # fmt: skip
    print(f"[total {time.time() - t0:.0f} s]")
