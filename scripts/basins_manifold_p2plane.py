"""The P2 saddle's stable manifold in the (x1, phi1) plane through the saddle (docs/basins.md).

At eta = 9.73102 the rest-plane map has no P2 cell (every start slides), so the
manifold is traced in the plane through the saddle's first point (its other
coordinates kept), seeded at the saddle itself; both sides of the curve are then
run to their attractors. Run from the repository root: ``python3
scripts/basins_manifold_p2plane.py`` (finds the saddle as ``basins_manifold.py p2``
does, or reads its cache out/basins/p2_saddle.json).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import stickslip_fast as ssf
from stickslip_fast.analysis.census import census

sys.path.insert(0, str(Path(__file__).parent))
import basins_manifold as bmf  # noqa: E402

if __name__ == "__main__":
    t0 = time.time()
    orb = bmf.p2_saddle()
    z = orb.points[0]
    box = [[z[0] - 0.05, z[0] + 0.05], [z[2] - 0.05, z[2] + 0.05]]
    m = ssf.stable_manifold(orb.system, orb, plane=("x1", "phi1"), base=z, bounds=box,
                            seeds=[[z[0], z[2]]], ds=2e-3, r_local=1e-6, n_max=20,
                            max_points=40)  # fmt: skip
    print(f"manifold: {len(m.u)} points, branches {m.branch_status}, n {np.unique(m.n)}, "
          f"seeds {m.settings['seed_status']}, residual <= {m.residual.max():.1e}, "
          f"[{time.time() - t0:.0f} s]")  # fmt: skip
    np.savez(bmf.OUT / "p2_plane_manifold.npz", u=m.u, v=m.v, branch=m.branch, n=m.n, z=z)
    k = np.linspace(0, len(m.u) - 2, 5).astype(int)
    starts = []
    for i in k:
        t = m.uv[i + 1] - m.uv[i]
        nrm = np.array([-t[1], t[0]]) / np.linalg.norm(t)
        for d in (1e-5, -1e-5):
            y = z.copy()
            y[0], y[2] = m.uv[i] + d * nrm
            starts.append(y)
    c = census(orb.system, "eta", [orb.system.eta], starts=np.array(starts), t_end=3000.0,
               stop="converged", progress=False)  # fmt: skip
    kind = {a.id: f"{a.kind} P{a.period}" for a in c.attractors[0]}
    print("sides (+1e-5, -1e-5 along the normal) at 5 curve points:",
          [kind.get(int(lab), "failed") for lab in c.labels[0]], f"[{time.time() - t0:.0f} s]")  # fmt: skip
