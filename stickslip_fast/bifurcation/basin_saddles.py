"""The saddle ("edge tracking") check of a basin boundary: :func:`edge_check`.

From refined boundary points (:func:`stickslip_fast.analysis.basins_boundary.refine_boundary`)
trajectories are followed; if the boundary is the stable manifold of a saddle
orbit they go to it and linger there. The orbit is found by Newton on the
return map (this layer's :func:`~stickslip_fast.find_orbit`) from their most
nearly recurrent Poincare point, or given. See docs/basins.md.
"""

from __future__ import annotations

import warnings
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..analysis import basins_measures as bm
from ..analysis.basins_boundary import EdgeCheck

__all__ = ["edge_check"]


def _recurrent_point(runs: list, attractors: list, periods: tuple) -> tuple:
    """(point, period) of the most nearly p-recurrent crossing away from the attractors.

    Crossings within 1e-2 (max norm) of a stable orbit or rest point of the map
    are left out: runs settling there recur ever more closely too."""
    best = (np.inf, None, None)
    atts = [a.points for a in attractors if a.kind in ("orbit", "equilibrium", "stalled")]
    for r in runs:
        p_all = r.poincare
        for p in periods:
            if len(p_all) <= p:
                continue
            rec = np.max(np.abs(p_all[p:] - p_all[:-p]), axis=1)
            far = np.ones(len(rec), dtype=bool)
            for pts in atts:
                d = np.min(np.max(np.abs(p_all[:-p, None, :] - pts[None]), axis=2), axis=1)
                far &= d > 1e-2
            rec = np.where(far, rec, np.inf)
            k = int(np.argmin(rec))
            if rec[k] < best[0]:
                best = (rec[k], p_all[k], p)
    return best[1], best[2]


def _saddle(result: Any, runs: list, saddle: Any, periods: tuple) -> tuple:
    """(points, period, T, multipliers, status) of the given or the Newton-found saddle."""
    from .orbits import find_orbit

    if saddle is None:
        z, p = _recurrent_point(runs, result.attractors, periods)
        saddle = find_orbit(result.system, z, period=p) if z is not None else None
        if saddle is not None and saddle.status == "equilibrium":
            saddle = None  # Newton fell onto the rest point: no saddle orbit found
    if saddle is None:
        return np.full((1, result.system.n_state), np.nan), 0, np.nan, [], "none"
    return saddle.points, saddle.period, saddle.T, saddle.multipliers, saddle.status


def _splits(runs_a: list, runs_b: list, split: float) -> tuple:
    """First crossing (and its time) where the two runs of a bracket differ by > split."""
    k_split = np.full(len(runs_a), -1, dtype=int)
    t_split = np.full(len(runs_a), np.nan)
    for i, (ra, rb) in enumerate(zip(runs_a, runs_b)):
        n = min(len(ra.poincare), len(rb.poincare))
        d = np.max(np.abs(ra.poincare[:n] - rb.poincare[:n]), axis=1)
        far = np.flatnonzero(d > split)
        if far.size:
            k_split[i] = far[0]
            t_split[i] = ra.t_poincare[far[0]]
        elif len(ra.poincare) != len(rb.poincare):  # one settled to rest, the other did not
            k_split[i] = n
            t_split[i] = ra.t_poincare[n] if n < len(ra.poincare) else rb.t_poincare[n]
    return k_split, t_split


def _distances(runs: list, saddle: np.ndarray, width: int) -> tuple:
    dist = np.full((len(runs), width), np.nan)
    tmin = np.full(len(runs), np.nan)
    for i, r in enumerate(runs):
        if len(r.poincare):
            d = np.min(np.max(np.abs(r.poincare[:, None, :] - saddle[None]), axis=2), axis=1)
            dist[i, : len(d)] = d[:width]
            tmin[i] = r.t_poincare[int(np.argmin(d))]
    return dist, tmin


def _crossings_of(system: Any, states: Any, t_end: float, kw: dict) -> list:
    """Every recorded crossing of a run from each state, also of runs that settle to rest
    (their approach is the edge tracking's signal; ``simulate`` returns points only for
    status "ok")."""
    from ..analysis.simulate import recorded_crossings

    out = []
    for y in states:
        t, pts, _ = recorded_crossings(system, t_end, y, **kw)
        out.append(SimpleNamespace(t_poincare=t, poincare=pts))
    return out


def edge_check(
    result: Any,
    *,
    saddle: Any = None,
    n_tracks: int = 24,
    t_end: float = 600.0,
    near: float = 1e-3,
    split: float = 1e-3,
    periods: tuple = (1, 2),
    seed: int = 0,
    store: bool = True,
) -> EdgeCheck:
    """Follow refined boundary points forward and measure their approach to a saddle orbit.

    Parameters
    ----------
    result : BasinsResult
        With ``result.boundary`` (:func:`refine_boundary`).
    saddle : Orbit, optional
        The saddle orbit (e.g. an unstable point of a :func:`continue_orbit`
        branch at the map's value). Default: found by Newton
        (:func:`find_orbit`) from the most nearly p-recurrent Poincare point
        (p in ``periods``) of the boundary trajectories away from the map's
        stable orbits.
    n_tracks : int
        Boundary points followed (a seeded sample of the refined segments),
        and as many control starts at non-boundary cells.
    t_end : float
        Length of each followed run.
    near : float
        Distance (max norm) that counts as "at the saddle".
    split : float
        Distance at which the runs from the two ends of a bracket count as split.
    periods : tuple of int
        Periods searched for the saddle.
    seed : int
    store : bool
        Write ``/basins/edge`` into the result's file.
    """
    b = result.boundary
    if b is None:
        raise ValueError("result has no refined boundary; run refine_boundary first")
    rng = np.random.default_rng(seed)
    ok = np.flatnonzero(b.status == 0)
    pick = np.sort(rng.choice(ok, min(n_tracks, ok.size), replace=False))
    s = result.census.settings
    kw = dict(rtol=s["rtol"], atol=s["atol"], max_points=4096)

    def run(states):
        return _crossings_of(result.system, states, t_end, kw)

    runs = run(result.state_at(b.ua[pick]))
    runs_b = run(result.state_at(b.ub[pick]))
    k_split, t_split = _splits(runs, runs_b, split)
    ctrl_cells = np.flatnonzero(~bm.boundary_cells(result.labels).ravel())
    ctrl = np.sort(rng.choice(ctrl_cells, min(len(pick), ctrl_cells.size), replace=False))
    controls = run(result.starts[ctrl])
    sp, per, T, mult, st = _saddle(result, runs, saddle, tuple(periods))
    width = max([1, *(len(r.poincare) for r in runs)])
    dist, tmin = _distances(runs, sp, width)
    cdist, _ = _distances(controls, sp, max([1, *(len(r.poincare) for r in controls)]))
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN rows: no saddle, no crossing
        dmin, cmin = np.nanmin(dist, axis=1), np.nanmin(cdist, axis=1)
    e = EdgeCheck(
        np.asarray(sp), int(per), float(T), np.asarray(mult, dtype=complex), str(st),
        b.u[pick], b.v[pick], dmin, tmin, np.sum(dist <= near, axis=1),
        cmin, np.sum(cdist <= near, axis=1), float(near), k_split, t_split,
        float(split), dist,
    )  # fmt: skip
    result.edge = e
    if store and result.path is not None:
        from ..io.basins_extras import store_extra

        store_extra(result.path, "edge", e)
    return e
