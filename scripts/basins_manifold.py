"""The stable manifolds of Fig. 6's saddle orbits in basin maps (docs/basins.md, issue 29).

Steps (all by default; results printed, files under out/basins/):

1. ``fold``: the unstable P1 orbit past the upper fold (continuation from eta = 3.2
   upwards through the fold, the unstable point with |multiplier| closest to 5, as
   scripts/basins_saddle_check.py ``fold``; cached in out/basins/fold_saddle.json), its
   32 x 32 basin map in the (x1, phi1) plane at rest, the boundary refined to 1e-10,
   the edge check, and ``stable_manifold`` seeded from the refined boundary points
   -> out/basins/asym_fold_saddle.h5. Prints the distance of every refined boundary
   point to the traced curve.
2. ``p2``: the unstable P2 orbit just below the P2 fold (eta = 9.7310261603): at
   eta = 9.73102 by Newton next to the stable P2 (see ``p2_saddle``; cached in
   out/basins/p2_saddle.json); its map, refinement, edge check and manifold as in 1
   -> out/basins/asym_p2_saddle.h5.
3. ``wada``: the grid and merging Wada tests of every map in out/basins with three or
   more basins.

Usage: ``python3 scripts/basins_manifold.py [fold] [p2] [wada]``.
"""

from __future__ import annotations

import glob
import json
import sys
import time
from pathlib import Path

import numpy as np

import stickslip_fast as ssf
from stickslip_fast.analysis.basins_boundary import refine_boundary
from stickslip_fast.bifurcation.basin_saddles import edge_check

OUT = Path("out/basins")
P1_AT_3_2 = [0.0764175880, 0.0, 0.122420158, -0.00705639063]  # the eta = 3.2 map's P1 point
G = np.linspace(-0.3, 0.3, 32)


def _branch_saddle(cache: Path, make_branch, period: int) -> ssf.Orbit:
    """The unstable point of a branch with |multiplier| closest to 5, polished by Newton."""
    if not cache.exists():
        br = make_branch()
        uns = np.flatnonzero(~br.stable)
        mod = np.abs(br.multipliers[:, 0])
        k = uns[np.argmin(np.abs(mod[uns] - 5.0))]
        cache.write_text(json.dumps({"eta": float(br.values[k]), "point": br.points[k].tolist(),
                                     "mu": float(mod[k]), "eta_unstable": br.values[uns].tolist(),
                                     "mu_unstable": mod[uns].tolist()}, indent=1))  # fmt: skip
    c = json.loads(cache.read_text())
    orb = ssf.find_orbit(ssf.System.preset("asymmetric", eta=c["eta"]), c["point"], period=period)
    print(f"saddle: eta = {c['eta']!r}, {orb}")
    print(f"  unstable side of the branch: eta {min(c['eta_unstable'])!r} .. "
          f"{max(c['eta_unstable'])!r}, |mu| {min(c['mu_unstable']):.4g} .. "
          f"{max(c['mu_unstable']):.4g}")  # fmt: skip
    return orb


def fold_saddle() -> ssf.Orbit:
    def branch():
        s = ssf.System.preset("asymmetric", eta=3.2)
        orb = ssf.find_orbit(s, ssf.simulate(s, 5000, y0=P1_AT_3_2, stop="converged"))
        return ssf.continue_orbit(orb, "eta", (3.19, 3.33), ds=0.02, ds_max=0.05, direction=1)

    return _branch_saddle(OUT / "fold_saddle.json", branch, 1)


def p2_saddle(eta: float = 9.73102) -> ssf.Orbit:
    """The unstable P2 1e-5 below the P2 fold (9.7310261603): the stable P2 of the eta = 9.0
    map followed by Newton in steps of eta to ``eta``, then Newton from it displaced by
    3e-7 along its leading eigenvector (smaller steps return to the stable orbit, 3e-6 and
    more fall off the smooth piece of the map). Cached in out/basins/p2_saddle.json."""
    cache = OUT / "p2_saddle.json"
    if not cache.exists():
        g = np.linspace(-0.3, 0.3, 40)
        m = ssf.basins(ssf.System.preset("asymmetric", eta=9.0), (g, g),
                       out=OUT / "scan/asym_eta9_rest40.h5", progress=False)  # fmt: skip
        z = next(a for a in m.attractors if a.kind == "orbit" and a.period == 2).points[0]
        for e in (9.7, 9.73, 9.7309, 9.73101, eta):
            node = ssf.find_orbit(ssf.System.preset("asymmetric", eta=e), z, period=2)
            z = node.points[0]
        ev, vr = np.linalg.eig(node.jacobian)
        v = np.insert(np.real(vr[:, np.argmax(np.abs(ev))]), 1, 0.0)
        sad = ssf.find_orbit(node.system, z + 3e-7 * v / np.linalg.norm(v), period=2)
        cache.write_text(json.dumps({"eta": eta, "point": sad.points[0].tolist(),
                                     "node": z.tolist(), "node_mu": abs(node.multipliers[0])}))  # fmt: skip
    c = json.loads(cache.read_text())
    orb = ssf.find_orbit(ssf.System.preset("asymmetric", eta=c["eta"]), c["point"], period=2)
    print(f"saddle: eta = {c['eta']!r}, {orb}; the stable P2's leading multiplier {c['node_mu']:.4g}, "
          f"{np.max(np.abs(orb.points[0] - c['node'])):.2e} away")  # fmt: skip
    return orb


def study(orb: ssf.Orbit, path: Path, segments: int = 60, **trace) -> None:
    """Map, refine, edge check and manifold for the saddle ``orb``; distances printed."""
    t0 = time.time()
    r = ssf.load_basins(path) if path.exists() else ssf.basins(
        orb.system, (G, G), out=path, progress=False,
        title=f"Basins at eta = {orb.system.eta!r} with a P{orb.period} saddle")  # fmt: skip
    print(r, f"[map {time.time() - t0:.0f} s]")
    if r.boundary is None:
        refine_boundary(r, tol=1e-10, max_segments=segments)
    b = r.boundary
    print(f"boundary: {b.n_pairs} pairs, {int(np.sum(b.status == 0))} refined to {b.tol:g}")
    if r.edge is None:
        e = edge_check(r, saddle=orb, n_tracks=24, t_end=600.0)
        print("edge check:", e.summary)
    t1 = time.time()
    m = ssf.stable_manifold(r, orb, **trace)
    print(f"manifold: {len(m.u)} points, branches {m.branch_status}, n {np.unique(m.n)}, "
          f"seeds {m.settings['seed_status']}, residual <= {m.residual.max() if len(m.u) else 0:.1e}, "
          f"distance <= {m.distance.max() if len(m.u) else 0:.1e}, {m.n_evals} evaluations, "
          f"[{time.time() - t1:.0f} s]")  # fmt: skip
    ok = b.status == 0
    if len(m.u):
        d = m.distance_to(np.stack([b.u[ok], b.v[ok]], 1))
        print(
            "distance of the refined boundary points to the curve:", np.array2string(d, precision=2)
        )
        for lab in sorted({*b.label_a[ok].tolist(), *b.label_b[ok].tolist()}):
            print(
                f"  pairs with label {lab}:",
                np.sum((b.label_a[ok] == lab) | (b.label_b[ok] == lab)),
            )


def wada() -> None:
    for f in sorted(glob.glob(str(OUT / "**/*.h5"), recursive=True)):
        r = ssf.load_basins(f)
        w, wm = r.wada(), r.wada_merge()
        print(f"{f}: {r.shape}, {w.n_basins} basins, fractions "
              f"{ {k: round(v, 3) for k, v in r.fractions().items()} }, Wada fraction at "
              f"r = 1..5: {np.round(w.fraction, 3).tolist()}, wada = {w.is_wada}; merging "
              f"test, uncovered: {np.round(wm.uncovered, 3).tolist()}, wada = {wm.is_wada}")  # fmt: skip


if __name__ == "__main__":
    todo = sys.argv[1:] or ["fold", "p2", "wada"]
    for name in todo:
        t = time.time()
        if name == "fold":
            study(fold_saddle(), OUT / "asym_fold_saddle.h5", ds=2e-3, r_local=1e-6, n_max=40)
        elif name == "p2":
            study(p2_saddle(), OUT / "asym_p2_saddle.h5", ds=2e-3, r_local=1e-5, n_max=40)
        else:
            wada()
        print(f"[{name}: {time.time() - t:.0f} s]")
