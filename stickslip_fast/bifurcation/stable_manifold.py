"""The stable manifold of a saddle periodic orbit in a plane of starts: :func:`stable_manifold`.

The curve is traced by :func:`stickslip_fast.analysis.basins_manifold.trace_manifold`
(the condition w . (P^n(p) - x*) = 0, no backward integration) with the model's
return map (:func:`.returnmap.return_map`'s integrator: the first crossing from the
plane start as it is, then crossing to crossing on the section). See docs/basins.md.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..analysis.basins_manifold import StableManifold, local_saddles, trace_manifold
from ..base.interrupt import call_interruptible, new_abort_flag
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

__all__ = ["stable_manifold", "plane_crossings"]


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
    """
    st = np.atleast_2d(np.asarray(states, dtype=float))
    p_arr = system.to_array()
    variant = kernel_variant(system.n_oscillators, system.is_dc_motor)
    mask = np.arange(system.n_state) != SECTION_INDEX
    out = np.full((len(st), int(n), int(mask.sum())), np.nan)
    U = np.ascontiguousarray(np.eye(system.n_state)[:, :1])
    for i, y0 in enumerate(st):
        y = np.array(y0, dtype=float)
        for k in range(int(n)):
            if k:
                y[SECTION_INDEX] = 0.0  # on the section: no crossing at t = 0
            code, y1, _, t = call_interruptible(
                propagate_tangents, y, U.copy(), p_arr, system.n_oscillators,
                system.is_dc_motor, variant, float(t_max), 1, float(rtol), float(atol),
                _TANGENT_ATOL, _MAX_STEPS, abort=new_abort_flag(),
            )  # fmt: skip
            if STATUS_NAMES[code] != "ok" or not math.isfinite(t) or not np.all(np.isfinite(y1)):
                break
            out[i, k] = y1[mask]
            y = np.ascontiguousarray(y1)
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
    **trace: Any,
) -> StableManifold:
    """The stable manifold of a saddle orbit intersected with a plane of starts, as curves.

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
    seeds : array_like (k, 2), optional
        Plane points near the curve. Default: the map's refined boundary points
        (:func:`refine_boundary`, status 0).
    plane, base, bounds
        With a System: the plane as for :func:`basins`, and its box
        [[u_min, u_max], [v_min, v_max]].
    rtol, atol : float
        Integration tolerances of the return map.
    store : bool
        Write ``/basins/manifold`` into the map's file (and set ``target.manifold``).
    **trace
        Settings of :func:`trace_manifold`: ``ds``, ``ds_min``, ``ds_max``, ``tol``,
        ``r_local``, ``n_max``, ``max_points``, ``max_angle``, ``seed_radius``,
        ``skip_radius``.

    Returns
    -------
    StableManifold
    """
    system, b, dirs, box, result = _plane_of(target, plane, base, bounds)
    if seeds is None:
        if result is None or result.boundary is None:
            raise ValueError("seeds not given and the map has no refined boundary to seed from")
        ok = result.boundary.status == 0
        seeds = np.stack([result.boundary.u[ok], result.boundary.v[ok]], axis=1)
    pts, saddles = _saddles(system, orbit, rtol, atol)

    def crossings(uv: np.ndarray, n: int) -> np.ndarray:
        states = b + uv[:, :1] * dirs[0] + uv[:, 1:2] * dirs[1]
        return plane_crossings(system, states, n, rtol=rtol, atol=atol)

    r = trace_manifold(crossings, saddles, seeds, box, period=int(orbit.period), **trace)
    settings = {k: (v if np.isscalar(v) else np.asarray(v).tolist()) for k, v in trace.items()}
    settings.update(rtol=rtol, atol=atol, seed_status=r["seed_status"])
    m = StableManifold(
        r["uv"][:, 0], r["uv"][:, 1], r["branch"], r["n"], r["target"], r["residual"],
        r["distance"], r["branch_status"], pts, int(orbit.period),
        np.array([s.mu for s in saddles]), float(trace.get("r_local", 1e-4)),
        float(trace.get("tol", 1e-11)), float(trace.get("ds", 1e-3)), int(r["n_evals"]),
        settings,
    )  # fmt: skip
    if result is not None and store:
        _store(result, m)
    return m


def _store(result: Any, m: StableManifold) -> None:
    """Set ``result.manifold`` and write ``/basins/manifold`` (replacing one there)."""
    result.manifold = m
    if result.path is not None:
        from ..io.basins import replace_subgroup

        with replace_subgroup(result.path, "manifold") as h5:
            m.to_group(h5["basins"].create_group("manifold"))
