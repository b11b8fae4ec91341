"""The stable manifold of a saddle periodic orbit in a plane of starts: :func:`stable_manifold`.

The curve is traced by :func:`stickslip_fast.analysis.basins_manifold.trace_manifold`
(the condition w . (P^n(p) - x*) = 0, no backward integration) with the model's
return map (:func:`.returnmap.return_map`'s integrator: the first crossing from the
plane start as it is, then crossing to crossing on the section). See docs/basins.md.
"""

from __future__ import annotations

import functools
import math
import os
from typing import Any

import numpy as np

from ..analysis.basins_manifold import StableManifold, local_saddles, trace_manifold
from ..base.interrupt import new_abort_flag
from ..base.journal import call_journaled, journal
from ..base.threads import run_concurrently
from ..base.version import package_version
from ..core.poincare import STATUS_NAMES
from ..core.trajectory import kernel_variant
from ..core.variational import propagate_tangents
from ..model.system import System
from .returnmap import (
    _DEFAULT_ATOL,
    _DEFAULT_RTOL,
    _MAX_STEPS,
    _TANGENT_ATOL,
    SECTION_INDEX,
    return_map,
)

__all__ = ["stable_manifold", "manifold_seeds", "plane_crossings", "store_manifold"]


def plane_crossings(
    system: System, states: Any, n: int, *, rtol: float = _DEFAULT_RTOL,
    atol: float = _DEFAULT_ATOL, t_max: float = 1e4,
) -> np.ndarray:  # fmt: skip
    """The first ``n`` upward crossings of the section (local minima of x1) from each state.

    Unlike :func:`return_map` the start need not lie on the section: the first
    crossing is the first one after t = 0 from the state as given (a start with
    dx1 = 0 exactly is not counted as a crossing). For a start on the section the
    crossings are those of ``return_map(system, z, n, tangents=False)``, bit for bit.

    Returns
    -------
    ndarray (m, n, n_state - 1)
        The crossings in section coordinates (the state without dx1); NaN from
        a failed integration on.

    Notes
    -----
    The states are independent, so they run side by side on Numba's thread count
    (:func:`~stickslip_fast.base.threads.run_concurrently`); each is the same
    sequential integration on any thread, so the result does not depend on the
    threads.
    """
    st = np.atleast_2d(np.asarray(states, dtype=float))
    p_arr = system.to_array()
    variant = kernel_variant(system.n_oscillators, system.is_dc_motor)
    mask = np.arange(system.n_state) != SECTION_INDEX
    out = np.full((len(st), int(n), int(mask.sum())), np.nan)
    U = np.ascontiguousarray(np.eye(system.n_state)[:, :1])
    # one flag for every state: Ctrl-C during a call in the calling thread (which arms
    # it), or in its Python code between two calls (run_concurrently sets it), stops the
    # states running in workers too, within a step
    abort = new_abort_flag()

    def crossings_from(i: int) -> None:  # row i of out, and nothing else
        y = np.array(st[i], dtype=float)
        for k in range(int(n)):
            if abort[0]:
                return
            if k:
                y[SECTION_INDEX] = 0.0  # on the section: no crossing at t = 0
            code, y1, _, t = call_journaled(
                propagate_tangents, y, U.copy(), p_arr, system.n_oscillators,
                system.is_dc_motor, variant, float(t_max), 1, float(rtol), float(atol),
                _TANGENT_ATOL, _MAX_STEPS, abort=abort,
            )  # fmt: skip
            if STATUS_NAMES[code] != "ok" or not math.isfinite(t) or not np.all(np.isfinite(y1)):
                return
            out[i, k] = y1[mask]
            y = np.ascontiguousarray(y1)

    run_concurrently([functools.partial(crossings_from, i) for i in range(len(st))], abort=abort)
    return out


def _plane_of(target: Any, plane: Any, base: Any, bounds: Any) -> tuple:
    """(system, base, directions, box, result or None) of a BasinsResult or a System."""
    from ..analysis.basins import plane_starts

    if isinstance(target, System):
        if plane is None or bounds is None:
            raise ValueError("with a System, plane and bounds are required")
        _, b, dirs, _ = plane_starts(target, [0.0, 1.0], [0.0, 1.0], plane, base)
        box = np.asarray(bounds, dtype=float)
        if box.shape != (2, 2) or not np.all(box[:, 0] < box[:, 1]):
            raise ValueError(f"bounds must be [[u_min, u_max], [v_min, v_max]], got {bounds!r}")
        return target, b, dirs, box, None
    if not hasattr(target, "labels") or not hasattr(target, "directions"):
        raise TypeError(f"target must be a System or a BasinsResult, got {type(target).__name__}")
    box = np.array([[target.g1[0], target.g1[-1]], [target.g2[0], target.g2[-1]]], dtype=float)
    return target.system, target.base, target.directions, box, target


def _saddles(system: System, orbit: Any, rtol: float, atol: float) -> tuple:
    """(points (p, n_state), LocalSaddle list) of ``orbit``: D P^p at each of its points."""
    if not np.allclose(orbit.system.to_array(), system.to_array(), rtol=0, atol=0):
        raise ValueError("orbit.system differs from the plane's system (another parameter value?)")
    pts = np.atleast_2d(np.asarray(orbit.points, dtype=float))
    p = int(orbit.period)
    jacs = []
    for z in pts:
        status, _, _, jac = return_map(system, z, p, rtol=rtol, atol=atol)
        if status != "ok":
            raise ValueError(f"the return map failed at an orbit point ({status})")
        jacs.append(jac)
    mask = np.arange(system.n_state) != SECTION_INDEX
    return pts, local_saddles(pts[:, mask], jacs)


def _plane_map(system: System, b: np.ndarray, dirs: np.ndarray, rtol: float, atol: float):
    """``crossings(uv, n)`` of the tracer: the first n crossings from the plane's points."""

    def crossings(uv: np.ndarray, n: int) -> np.ndarray:
        states = b + uv[:, :1] * dirs[0] + uv[:, 1:2] * dirs[1]
        return plane_crossings(system, states, n, rtol=rtol, atol=atol)

    return crossings


def _scan_summary(scanned: dict) -> dict:
    """What the seed scan found, for ``StableManifold.settings["scan"]`` (JSON)."""
    st = scanned["edge_status"]
    return {"grid": list(scanned["closest"].shape), "r_scan": scanned["r_scan"],
            "n_max": scanned["n_max"], "edges": len(st), "seeds": int(st.count("seed")),
            "edge_status": {k: st.count(k) for k in sorted(set(st))},
            "closest": float(np.min(scanned["closest"])), "n_evals": int(scanned["n_evals"])}  # fmt: skip


def manifold_seeds(
    target: Any,
    orbit: Any,
    *,
    grid: Any = None,
    plane: Any = None,
    base: Any = None,
    bounds: Any = None,
    n_max: int = 30,
    r_scan: float = 1e-2,
    r_local: float = 1e-4,
    tol: float = 1e-11,
    rtol: float = _DEFAULT_RTOL,
    atol: float = _DEFAULT_ATOL,
) -> dict:
    """Seeds on a saddle orbit's stable manifold in a plane, from a scan of a grid.

    Every grid node p is mapped ``n_max`` times; an edge between neighbouring
    nodes whose values of g_n = w . (P^n(p) - x*) have opposite signs, at the same
    n and orbit point x*, while the stable parts of both images (P^n - x* less its
    unstable component) lie within ``r_scan`` of x*, straddles the manifold: the
    root of g_n along the edge is found and n raised (by the period) until its
    image lies within ``r_local`` of x* (the tracer's condition). See
    :func:`stickslip_fast.analysis.basins_seeds.scan_seeds` and docs/basins.md.
    A piece of the manifold thinner than a grid cell, or whose two sides leave
    the saddle on the same side, gives no sign change and no seed.

    Parameters
    ----------
    target : BasinsResult or System
        A basin map (its system, plane, base and grid), or a System with
        ``plane``, ``base`` and ``bounds`` as for :func:`stable_manifold`.
    orbit : Orbit
        The saddle orbit (exactly one real multiplier outside the unit circle).
    grid : int or (array_like, array_like), optional
        ``n`` for an n x n grid over the plane's box, or the two axes. Default:
        the map's own grid; with a System, 32 x 32 over ``bounds``.
    n_max : int
        Crossings per node, and the largest n of a seed.
    r_scan : float
        Radius (max norm, section units) for the stable parts of both ends' images.
    r_local, tol : float
        The tracer's neighbourhood radius and the root's bracket length (plane units).
    rtol, atol : float
        Integration tolerances of the return map.

    Returns
    -------
    dict
        ``uv`` (k, 2) the seeds (plane coordinates) with ``n``, ``target``,
        ``residual``, ``distance`` at each; ``edges``, ``edge_n``,
        ``edge_target``, ``edge_status`` (one per sign-change edge), ``closest``
        (the grid's shape: each node's smallest distance to the orbit over its
        n_max crossings), ``g1``, ``g2``, ``r_scan``, ``n_max``, ``n_evals``.

    Raises
    ------
    ValueError
        Naming the bad argument (``grid``, ``g1``/``g2``, ``n_max``, ``r_scan``,
        ``r_local``, ``tol``), or if the orbit is not a saddle of index one.
    """
    from ..analysis.basins_seeds import check_axis, scan_seeds

    system, b, dirs, box, result = _plane_of(target, plane, base, bounds)
    if grid is None:
        grid = (result.g1, result.g2) if result is not None else 32
    if np.isscalar(grid):
        if int(grid) != grid or int(grid) < 2:
            raise ValueError(f"grid must be an integer >= 2 or two axes, got {grid!r}")
        g1, g2 = (np.linspace(box[k, 0], box[k, 1], int(grid)) for k in (0, 1))
    elif len(grid) == 2:
        g1, g2 = check_axis("g1", grid[0]), check_axis("g2", grid[1])
    else:
        raise ValueError(f"grid must be an integer >= 2 or two axes, got {grid!r}")
    pts, saddles = _saddles(system, orbit, rtol, atol)
    out = scan_seeds(_plane_map(system, b, dirs, rtol, atol), saddles, g1, g2,
                     period=int(orbit.period), n_max=n_max, r_scan=r_scan, r_local=r_local,
                     tol=tol)  # fmt: skip
    out.update(g1=g1, g2=g2, r_scan=float(r_scan), n_max=int(n_max))
    return out


def _scan_key(target: Any, orbit: Any, scan_kw: dict, plane_kw: dict) -> str:
    """What a seed scan depends on, as text: the plane (system, base, directions, box, or
    the map's grid), the saddle orbit, the scan's arguments and the tolerances, and the
    package's version (another version may scan otherwise)."""
    from ..io.base import config_digest

    system, b, dirs, box, result = _plane_of(target, plane_kw["plane"], plane_kw["base"],
                                             plane_kw["bounds"])  # fmt: skip
    key = {
        "system": system.to_dict(), "base": b, "directions": dirs, "box": box,
        "grid": None if result is None else [result.g1, result.g2],
        "orbit": {"system": orbit.system.to_dict(), "points": np.asarray(orbit.points),
                  "period": int(orbit.period)},
        "scan": scan_kw, "rtol": plane_kw["rtol"], "atol": plane_kw["atol"],
        "package_version": package_version(),
    }  # fmt: skip
    # the configuration files' canonical JSON: floats in their shortest repr, which tells
    # every float bit apart
    return config_digest(key)[0]


def _scan_once(target: Any, orbit: Any, result: Any, store: bool, kw: dict, plane_kw: dict):
    """:func:`manifold_seeds`, or the scan the map's file holds for the same inputs; a new
    scan is stored there (with ``store``): a second trace need not scan again."""
    path = getattr(result, "path", None)
    if path is None:
        return manifold_seeds(target, orbit, **plane_kw, **kw)
    from ..io.basins_extras import read_manifold_scan, store_manifold_scan

    key = _scan_key(target, orbit, kw, plane_kw)
    scanned = read_manifold_scan(path, key)
    if scanned is None:
        scanned = manifold_seeds(target, orbit, **plane_kw, **kw)
        if store:
            store_manifold_scan(path, key, scanned)
    return scanned


def _resolve_seeds(seeds, scan, result, trace: dict, target, orbit, store, **plane_kw) -> tuple:
    """(seeds, trace settings, scan record or None) of :func:`stable_manifold`."""
    scanned = None
    if isinstance(seeds, str):
        if seeds != "scan":
            raise ValueError(f"seeds must be points (k, 2), None or 'scan', got {seeds!r}")
        kw = {k: trace[k] for k in ("r_local", "n_max", "tol") if k in trace}
        kw.update(scan or {})
        scanned = _scan_once(target, orbit, result, store, kw, plane_kw)
        seeds = scanned["uv"]
        spacing = min(np.min(np.diff(scanned["g1"])), np.min(np.diff(scanned["g2"])))
        trace = {"skip_radius": 0.25 * float(spacing), **trace}  # one curve, many edges
    elif scan is not None:
        raise ValueError("scan is an option of seeds='scan'; seeds were given otherwise")
    if seeds is None:  # stable_manifold found no boundary to seed from
        raise ValueError("seeds not given and the map has no refined boundary to seed from")
    return seeds, trace, scanned


def _boundary_seeds(result) -> np.ndarray | None:
    """The refined boundary's points of a basin map (None without one)."""
    if result is None or result.boundary is None:
        return None
    ok = result.boundary.status == 0
    return np.stack([result.boundary.u[ok], result.boundary.v[ok]], axis=1)


#: :func:`stable_manifold`'s docstring (kept out of the function body, as for
#: :func:`~stickslip_fast.continue_orbit`: the layout rule counts a function's lines).
_STABLE_MANIFOLD_DOC = """The stable manifold of a saddle orbit intersected with a plane of starts, as curves.

A plane point p is on the curve when its n-th crossing P^n(p) lands on the
saddle's local stable subspace: w . (P^n(p) - x*) = 0 with w the left
eigenvector of the unstable multiplier, and ||P^n(p) - x*|| <= ``r_local``
(n adapted along the curve). No backward integration. Traced by
predictor-corrector continuation from ``seeds`` both ways until the plane's
box (:func:`stickslip_fast.analysis.basins_manifold.trace_manifold`).

Parameters
----------
target : BasinsResult or System
    A basin map (its system, plane, base and box; the result is stored in its
    file's ``/basins/manifold``), or a System with ``plane``, ``base``, ``bounds``.
orbit : Orbit
    The saddle: :func:`find_orbit`'s record, or any object with ``system``,
    ``points`` (p, n_state) on the section and ``period`` (e.g. from an
    unstable point of a :func:`continue_orbit` branch). It must have exactly
    one real multiplier outside the unit circle.
seeds : array_like (k, 2) or "scan", optional
    Plane points near the curve. Default: the map's refined boundary points
    (:func:`refine_boundary`, status 0). ``"scan"``: from the saddle alone,
    :func:`manifold_seeds` over the map's grid (or ``scan["grid"]``) with the
    tracer's ``r_local``, ``n_max``, ``tol``; recorded in ``settings["scan"]``;
    ``skip_radius`` then defaults to a quarter of the grid's spacing. With a map
    that has a file, the scan is kept there (``/basins/manifold_scan``; with
    ``store``) and used again by a later call with the same saddle, plane, scan
    arguments and tolerances, bit for bit.
plane, base, bounds
    With a System: the plane as for :func:`basins`, and its box
    [[u_min, u_max], [v_min, v_max]].
rtol, atol : float
    Integration tolerances of the return map.
store : bool
    Write ``/basins/manifold`` into the map's file (and set ``target.manifold``).
scan : dict, optional
    With ``seeds="scan"``: arguments of :func:`manifold_seeds` (``grid``, ``r_scan``, ...).
checkpoint : str or os.PathLike, optional
    A file that records the integrations as they are made: the same call with
    the same file resumes after a kill, bit-identically (as for
    :func:`~stickslip_fast.continue_orbit`; docs/orbits.md, "Checkpoints").
**trace
    Settings of :func:`trace_manifold`: ``ds``, ``ds_min``, ``ds_max``, ``tol``,
    ``r_local``, ``n_max``, ``max_points``, ``max_angle``, ``seed_radius``,
    ``skip_radius``.

Returns
-------
StableManifold
"""


def stable_manifold(
    target: Any,
    orbit: Any,
    *,
    seeds: Any = None,
    plane: Any = None,
    base: Any = None,
    bounds: Any = None,
    rtol: float = _DEFAULT_RTOL,
    atol: float = _DEFAULT_ATOL,
    store: bool = True,
    scan: dict | None = None,
    checkpoint: str | os.PathLike | None = None,
    **trace: Any,
) -> StableManifold:
    system, b, dirs, box, result = _plane_of(target, plane, base, bounds)
    if seeds is None:  # the refined boundary's points (None without one: refused below)
        seeds = _boundary_seeds(result)
    given = dict(system=system, base=b, directions=dirs, box=box, scan=scan, rtol=rtol,
                 atol=atol, trace=trace, seeds=seeds,
                 saddle=(orbit.system, np.asarray(orbit.points), orbit.period))  # fmt: skip
    with journal(checkpoint, "stable_manifold", given):
        seeds, trace, scanned = _resolve_seeds(
            seeds, scan, result, trace, target, orbit, store, plane=plane, base=base,
            bounds=bounds, rtol=rtol, atol=atol,
        )  # fmt: skip
        pts, saddles = _saddles(system, orbit, rtol, atol)
        r = trace_manifold(_plane_map(system, b, dirs, rtol, atol), saddles, seeds, box,
                           period=int(orbit.period), **trace)  # fmt: skip
    settings = {k: (v if np.isscalar(v) else np.asarray(v).tolist()) for k, v in trace.items()}
    settings.update(rtol=rtol, atol=atol, seed_status=r["seed_status"])
    if scanned is not None:
        settings.update(seeds="scan", scan=_scan_summary(scanned))
    m = StableManifold(
        r["uv"][:, 0], r["uv"][:, 1], r["branch"], r["n"], r["target"], r["residual"],
        r["distance"], r["branch_status"], pts, int(orbit.period),
        np.array([s.mu for s in saddles]), float(trace.get("r_local", 1e-4)),
        float(trace.get("tol", 1e-11)), float(trace.get("ds", 1e-3)), int(r["n_evals"]),
        settings,
    )  # fmt: skip
    if result is not None and store:
        store_manifold(result, m)
    return m


stable_manifold.__doc__ = _STABLE_MANIFOLD_DOC


def store_manifold(result: Any, m: StableManifold) -> None:
    """Set ``result.manifold`` and write ``/basins/manifold`` into its file (replacing one there)."""
    result.manifold = m
    if result.path is not None:
        from ..io.basins_extras import store_extra

        store_extra(result.path, "manifold", m)
