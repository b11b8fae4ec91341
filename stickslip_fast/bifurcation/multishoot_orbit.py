"""find_orbit by multiple shooting: damped Newton on the system of :mod:`.multishoot`."""

from __future__ import annotations

import math

import numpy as np

from ..base.blas import one_blas_thread
from ..model.system import System
from .equilibria import EQUILIBRIUM_SPEED
from .multishoot import MAX_SEGMENTS, MESH_LIMIT, MultiShooting, periodic_multipliers, refine_mesh
from .orbit_record import Orbit, multipliers_stable
from .returnmap import SECTION_INDEX, _field, _minimal_period, return_map


def initial_segments(ms: MultiShooting, z: np.ndarray, T: float):
    """(status, Y): the segment starts of the trajectory from z on the section over T."""
    z = np.array(z, dtype=float)
    z[SECTION_INDEX] = 0.0
    return ms.states_at(z[None, :], T, ms.mesh[:-1] * T)


def newton_multiple(ms: MultiShooting, u: np.ndarray, tol: float, max_iter: int):
    """Damped Newton on G(u) = 0 (halving the step until max |G| decreases, at most 20 times).

    Returns (status, message, u, factors, residual, iterations, history); status as in
    :data:`~stickslip_fast.bifurcation.orbit_record.ORBIT_STATUSES`.
    """
    st, G, DG, factors = ms.evaluate(u)
    if st != "ok":
        return (
            "integration-failed",
            f"the segments failed at the start: {st}",
            u,
            None,
            math.inf,
            0,
            [math.inf],
        )
    res = float(np.max(np.abs(G)))
    history = [res]
    it = 0
    while res > tol:
        if it >= max_iter:
            return (
                "max-iter",
                f"no convergence to tol={tol:g} in {max_iter} Newton steps",
                u,
                factors,
                res,
                it,
                history,
            )
        try:
            du = np.linalg.solve(DG, -G)
        except np.linalg.LinAlgError:
            return "no-progress", "the shooting Jacobian is singular", u, factors, res, it, history
        it += 1
        lam = 1.0
        for _ in range(21):
            u_new = u + lam * du
            st_n, G_n, DG_n, f_n = ms.evaluate(u_new)
            if st_n == "ok":
                res_n = float(np.max(np.abs(G_n)))
                if res_n < res:
                    break
            lam *= 0.5
        else:
            msg = f"no step along the Newton direction reduces the residual {res:.3g}"
            return "no-progress", msg, u, factors, res, it, history
        u, G, DG, factors, res = u_new, G_n, DG_n, f_n, res_n
        history.append(res)
    return "converged", "", u, factors, res, it, history


def product(factors: list[np.ndarray]) -> np.ndarray:
    """The section Jacobian formed explicitly (for ``Orbit.jacobian``; its eigenvalues are
    taken from the factors by :func:`periodic_multipliers`, not from this product)."""
    P = factors[0]
    for A in factors[1:]:
        P = A @ P
    return P


def _what_converged(system: System, y0: np.ndarray, points: np.ndarray, period: int, tol: float):
    """(status, message, period) of a converged solution: a rest point, an orbit of a
    lower period, or an orbit crossing the section another number of times."""
    p_found = points.shape[0]
    speed = float(np.max(np.abs(_field(system, y0))))
    q = _minimal_period(points, tol)
    if speed < EQUILIBRIUM_SPEED:
        msg = f"converged onto a rest point (max |f| = {speed:.2g}): use find_equilibrium"
        return "equilibrium", msg, period
    if q < p_found:
        return (
            "lower-period",
            f"converged onto an orbit of period {q}, a divisor of {p_found}",
            period,
        )
    if p_found != period:
        msg = f"the orbit crosses the section {p_found} times per period, not {period}"
        return "converged", msg, p_found
    return "converged", "", period


def _failed_orbit(system: System, period: int, z) -> dict:
    """The fields of an Orbit that was not found (z: the point it started from)."""
    n = system.n_state
    return dict(system=system, period=period, points=np.array(z, float)[None, :],
                times=np.array([math.nan]), T=math.nan,
                multipliers=np.full(n - 1, np.nan, complex), stable=False,
                jacobian=np.full((n - 1, n - 1), np.nan), residual=math.inf,
                iterations=0, converged=False)  # fmt: skip


@one_blas_thread()
def find_orbit_multiple(
    system: System,
    z: np.ndarray,
    period: int,
    *,
    segments: int,
    tol: float,
    max_iter: int,
    rtol: float,
    atol: float,
    t_max: float,
    tangent_atol: float,
    T: float | None = None,
    known: tuple[np.ndarray, np.ndarray] | None = None,
    max_segments: int = MAX_SEGMENTS,
):
    """:func:`~stickslip_fast.bifurcation.orbits.find_orbit` with ``shooting="multiple"`` (its arguments).

    ``T``: the period in time, if known (else from the p-th return of z). ``known``:
    ``(mesh, starts)`` of the orbit already cut into segments (``Orbit.segments``,
    ``Branch.segments``), used as they are, with ``T``, instead of ``segments`` even cuts
    of one trajectory from z (which a very unstable orbit leaves within its period).
    ``max_segments``: the most segments the even cuts are refined into.
    """
    if known is not None:
        mesh, starts = (np.array(a, dtype=float) for a in known)
        return _newton_orbit(system, mesh, starts, float(T), period, tol, max_iter,
                             (rtol, atol, tangent_atol))  # fmt: skip
    ms = MultiShooting(system, segments, rtol, atol, tangent_atol)
    if T is None:
        st, _, times, _ = return_map(system, z, period, rtol=rtol, atol=atol, t_max=t_max,
                                     tangents=False)  # fmt: skip
        T = float(times[-1]) if st == "ok" else math.nan
    nan_orbit = _failed_orbit(system, period, z)
    st, Y = initial_segments(ms, z, T) if math.isfinite(T) else ("no-crossings", None)
    if st == "ok":
        # bisect the segments that amplify most (past a sharp fold: the capture into stick)
        mesh = refine_mesh(ms, Y, T, MESH_LIMIT, max_segments)
        st, Y = ms.states_at(Y, T, mesh[:-1] * T, mesh=ms.mesh)
        ms = MultiShooting(system, mesh, rtol, atol, tangent_atol)
    if st != "ok":
        return Orbit(**nan_orbit, status="integration-failed",
                     message=f"no trajectory from the start to cut into segments: {st}")  # fmt: skip
    return _newton_orbit(system, ms.mesh, Y, T, period, tol, max_iter, ms.kw)


def _newton_orbit(system, mesh, Y, T, period, tol, max_iter, kw):
    """The Orbit from segment starts Y on ``mesh`` and period T, by :func:`newton_multiple`
    (its start moved to the crossing with the smallest x1 once converged)."""
    ms = MultiShooting(system, mesh, *kw)
    nan_orbit = _failed_orbit(system, period, Y[0])
    rotated = False
    total_it = 0
    while True:
        status, message, u, factors, res, it, history = newton_multiple(
            ms, ms.pack(Y, T), tol, max_iter
        )
        total_it += it
        Y, T = ms.unpack(u)
        if factors is None:
            return Orbit(**{**nan_orbit, "residual": res}, status=status, message=message)
        st, tc, yc = ms.crossings(Y, T)
        points = np.vstack([Y[0][None, :], yc])
        times = np.r_[tc, T]
        if status != "converged" or rotated or points.shape[0] < 2:
            break
        k = int(np.argmin(points[:, 0]))
        if k == 0:
            break
        rotated = True  # start again from the crossing with the smallest x1
        st, Y = ms.states_at(Y, T, (tc[k - 1] + ms.mesh[:-1] * T) % T, mesh=ms.mesh)
        Y[0][SECTION_INDEX] = 0.0
    mult = periodic_multipliers(factors)
    if status == "converged":
        status, message, period = _what_converged(system, Y[0], points, period, tol)
    converged = status == "converged"
    return Orbit(
        system=system, period=period, points=points, times=times, T=float(T),
        multipliers=mult, stable=bool(converged and multipliers_stable(system, mult)),
        jacobian=product(factors), residual=float(res), iterations=total_it,
        converged=converged, status=status, message=message, history=history,
        segments=(np.array(ms.mesh, dtype=float), np.array(Y, dtype=float)),
    )  # fmt: skip
