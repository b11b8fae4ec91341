"""Is the boundary at eta = 3.2 organised by the unstable period-1 orbit? (docs/basins.md)

Three measurements, printed:

1. ``fold``: continue the stable P1 orbit from eta = 3.2 upwards through its fold
   (``continue_orbit``, as data/continuation/fig06_p1.toml), take the unstable
   point whose leading multiplier is closest to 5, map the basins there (32 x 32,
   the (x1, phi1) plane at rest), refine the boundary to 1e-10 and run the edge
   check with that orbit as the saddle -> out/basins/asym_fold_saddle.h5.
2. ``exponent``: the uncertainty exponent at eta = 3.2 from the engine, with
   random pairs at eps = 3e-2 ... 1e-6 (300 pairs each), labelled by the map's
   label function (needs out/basins/asym_eta3.2_rest.h5).
3. ``split``: for 8 refined brackets of that file, when and how the two runs
   (1e-10 apart) separate: the slip speed of disk 1 at that moment.

Usage: ``python3 scripts/basins_saddle_check.py [fold] [exponent] [split]`` (all by default).
"""

from __future__ import annotations

import sys
import time
from types import SimpleNamespace

import numpy as np

import stickslip_fast as ssf
from stickslip_fast.analysis import basins_measures as bm
from stickslip_fast.analysis.basins_boundary import refine_boundary
from stickslip_fast.bifurcation.basin_saddles import edge_check

MAP = "out/basins/asym_eta3.2_rest.h5"
P1_AT_3_2 = [0.0764175880, 0.0, 0.122420158, -0.00705639063]  # the map's P1 point


def fold() -> None:
    s = ssf.System.preset("asymmetric", eta=3.2)
    orb = ssf.find_orbit(s, ssf.simulate(s, 5000, y0=P1_AT_3_2, stop="converged"))
    br = ssf.continue_orbit(orb, "eta", (3.19, 3.33), ds=0.02, ds_max=0.05, direction=1)
    mod = np.abs(br.multipliers[:, 0])
    uns = np.flatnonzero(~br.stable)
    print(f"unstable P1: eta in [{br.values[uns].min()!r}, {br.values[uns].max()!r}], "
          f"|multiplier| {mod[uns].min():.4g} .. {mod[uns].max():.4g}")  # fmt: skip
    k = uns[np.argmin(np.abs(mod[uns] - 5.0))]
    eta = float(br.values[k])
    print(f"saddle: eta = {eta!r}, |multiplier| {mod[k]:.4g}, point {br.points[k]}")
    saddle = SimpleNamespace(points=br.points[k][None, :], period=1, T=float(br.T[k]),
                             multipliers=br.multipliers[k], status="continuation")  # fmt: skip
    g = np.linspace(-0.3, 0.3, 32)
    r = ssf.basins(ssf.System.preset("asymmetric", eta=eta), (g, g),
                   out="out/basins/asym_fold_saddle.h5", progress=False,
                   title=f"Basins at eta = {eta!r} (unstable P1 past the fold)")  # fmt: skip
    refine_boundary(r, tol=1e-10, max_segments=60)
    e = edge_check(r, saddle=saddle, n_tracks=24, t_end=600.0)
    print(r)
    print("closest approach", e.min_distance, "crossings within 1e-3", e.n_near)
    print("split crossing", e.split_crossing, "predicted", np.log(1e7) / np.log(mod[k]))
    print("controls", e.control_min_distance)


def exponent() -> None:
    r = ssf.load_basins(MAP)
    eps = np.array([3e-2, 1e-2, 3e-3, 1e-3, 1e-4, 1e-5, 1e-6])
    fit = bm.uncertainty_exponent_fn(r.label_plane, [[-0.3, 0.3], [-0.3, 0.3]], eps, n=300,
                                     seed=1)  # fmt: skip
    print(
        f"engine: alpha = {fit.alpha:.3f} +- {fit.alpha_stderr:.3f}, dimension "
        f"{fit.dimension:.3f}; f(eps) = {dict(zip(eps.tolist(), fit.f.tolist()))}"
    )


def split() -> None:
    r = ssf.load_basins(MAP)
    b, e, s = r.boundary, r.edge, r.system
    for i in range(8):
        k = np.flatnonzero((b.u == e.u[i]) & (b.v == e.v[i]))[0]
        runs = [ssf.simulate(s, e.t_split[i] + 5, y0=r.state_at(uv)[0], sample_dt=0.002,
                             max_points=100) for uv in (b.ua[k], b.ub[k])]  # fmt: skip
        ya, yb, t = runs[0].y, runs[1].y, runs[0].t
        d = np.max(np.abs(ya - yb), axis=1)
        j = int(np.argmax(d > 1e-7))
        slip = np.hypot(ya[:, 1] - s.vb, ya[:, 3])
        w = slice(max(0, j - 1000), j + 1)
        jm = int(np.argmin(slip[w])) + w.start
        print(
            f"bracket {i}: distance {d[w.start]:.1e} at t - 2, > 1e-7 at t = {t[j]:.3f}, "
            f"{d[min(jm + 50, len(d) - 1)]:.1e} 0.1 later; slip speed of disk 1 "
            f"{slip[jm]:.2e} at t = {t[jm]:.3f} (eps = {s.eps:g})"
        )


if __name__ == "__main__":
    todo = sys.argv[1:] or ["fold", "exponent", "split"]
    for name in todo:
        t0 = time.time()
        {"fold": fold, "exponent": exponent, "split": split}[name]()
        print(f"[{name}: {time.time() - t0:.0f} s]")
