"""Branch switching at a period-doubling (the doubled orbit), at a symmetry-breaking
point (the orbits with the disks apart) and at a branch point (the crossing branch):
their starts, and their Newton solves."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .branch import Bifurcation, Branch
from .corrector import Evaluator, _correct
from .detection import BRANCH_POINT
from .multishoot import DEFAULT_SEGMENTS
from .orbit_branch import _orbit_evaluator
from .orbits import (
    SECTION_INDEX,
    SHOOTING_MODES,
    Orbit,
    find_orbit,
    return_map,
)
from .returnmap import _field
from .synchrony import (
    SYMMETRY_BREAKING,
    pair_matrix,
    section_directions,
    synchronous_point,
    transverse_monodromy,
)
from .walk_args import BRANCH_POINT_DS  # noqa: F401 (its old home)

# ------------------------------------------------------------ branch switching
#: Offsets along the -1 eigenvector tried by :func:`switch_branch`, largest first: the
#: doubled orbit's amplitude grows like sqrt(|lambda - lambda_PD|), and in the stiff
#: friction layer the quadratic regime can be very narrow.
SWITCH_DELTAS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7)

#: At a symmetry-breaking point an offset whose predictor already has max abs(G) below
#: FLAT * tol is too small to tell the branch apart (measured: 1e-7 and 2e-7 gave 0.1-0.5
#: tol and a spurious "orbit" at the point itself; 1e-6 gave 12-18 tol and the branch).
FLAT = 10.0

#: The bifurcation kinds :func:`switch_branch` switches at.
SWITCH_KINDS = ("period-doubling", SYMMETRY_BREAKING, BRANCH_POINT)


def period_doubling_start(
    evaluate_double: Evaluator,
    x_pd: np.ndarray,
    v: np.ndarray,
    delta: float,
    *,
    tol: float,
    max_corrector: int = 8,
) -> tuple[bool, np.ndarray]:
    """A point of the period-doubled branch near a period-doubling point.

    At a period-doubling point x_pd = (z*, lambda*) of a fixed point of P^p, with
    D_z P^p v = -v, the branch of fixed points of P^2p that are not fixed points
    of P^p crosses the p-branch, tangent to (v, 0): along it z = z* + delta v +
    O(delta^2) and lambda - lambda* = O(delta^2). The predictor (z* + delta v,
    lambda*) is corrected by Newton on G_2p(x) = 0 within the hyperplane
    v . (z - z*) = delta (lambda free).

    Parameters
    ----------
    evaluate_double : callable
        The evaluator of P^2p (see :func:`pseudo_arclength`).
    x_pd : ndarray, shape (m + 1,)
        The period-doubling point (z*, lambda*).
    v : ndarray, shape (m,)
        An eigenvector of D_z P^p(z*) for the multiplier -1.
    delta : float
        Offset along v (v is normalised first).
    tol : float
        Corrector tolerance on max |G_2p|.
    max_corrector : int
        Most Newton iterations.

    Returns
    -------
    ok, x
        Whether the corrector converged, and the point (z, lambda). It may still
        be a fixed point of P^p (for a delta too large): check that.
    """
    v = np.asarray(v, dtype=float)
    w = np.r_[v / np.linalg.norm(v), 0.0]
    x_pred = np.asarray(x_pd, dtype=float) + delta * w
    ok, x, _, _ = _correct(evaluate_double, x_pred, w, x_pred, tol, max_corrector)
    return bool(ok), x


#: :func:`switch_branch`'s docstring (kept out of the body: the layout rule counts lines).
_SWITCH_BRANCH_DOC = """The orbit born at a period-doubling, symmetry-breaking or branch point of a branch.

    At a period-doubling, the period-doubled orbit; at a symmetry-breaking point of
    a branch of in-phase orbits (docs/orbits.md, "In-phase orbits"), one of the two
    orbits of the same period with the disks apart (the other is it with the disks
    swapped), started along the transverse eigenvector of the multiplier +1; at a
    branch point, an orbit of the crossing branch, started along the null direction
    of DG orthogonal to the branch (docs/orbits.md, "Branch points"; offsets
    smallest first, each on both sides).

    Parameters
    ----------
    branch : Branch
        A branch of period-p orbits (:func:`continue_orbit`).
    bifurcation : Bifurcation or int
        One of ``branch.bifurcations`` (or its index there), of kind
        "period-doubling", "symmetry-breaking" or "branch-point".
    deltas : tuple of float
        Offsets along the eigenvector to try, in order (:func:`period_doubling_start`).
        The first that gives a fixed point of P^2p that is not one of P^p wins. At a
        symmetry-breaking point they are tried smallest first, and the first that
        gives a fixed point of P^p with the disks apart wins; an offset too small to
        resolve (the predictor's residual below 10 ``tol``: the normal form is
        cubic) is skipped. The difference between the disks grows like
        sqrt(abs(lambda - lambda_SB)): at the defaults 1e-6 wins, 0.002-0.004 in eta
        from the point on the paper's sets. At a branch point too they are tried
        smallest first (each on both sides), skipping those too small to resolve
        (G is quadratic there); on the anti-phase branch of two disks 1e-4 wins.
    tol, rtol, atol, fd_step
        As for :func:`continue_orbit`.
    shooting : {"single", "multiple", "auto"}
        How the doubled orbit is polished (:func:`find_orbit`): "multiple" gives an
        orbit whose multipliers come from the segments' factors, to be continued
        with ``continue_orbit(..., shooting="multiple")`` where the doubled
        branch is strongly unstable; "auto": single, multiple where single
        shooting reaches its precision limit. The start along the -1
        eigenvector is corrected by single shooting (a step of size ``delta``
        from the period-doubling point) in every mode.
    segments : int
        m >= 1, the segments of multiple shooting.

    Returns
    -------
    Orbit
        Of period 2p (period p at a symmetry-breaking point), at a parameter value
        near the bifurcation's (``orbit.system`` holds it), polished by
        :func:`find_orbit`, with ``orbit.origin`` = the bifurcation and
        ``orbit.origin_param`` = ``branch.param``.
        ``continue_orbit(orbit, branch.param, bounds)`` then walks away from the
        bifurcation, and from a branch point with the first step
        :data:`~stickslip_fast.bifurcation.walk_args.BRANCH_POINT_DS` (1e-3): a larger
        one can land back on the branch it left. A ``ds`` or ``direction`` given to
        :func:`continue_orbit` overrides these.
        If no offset works, the orbit is returned with ``converged = False``
        and a ``message`` saying so.

    Raises
    ------
    ValueError
        For a branch of equilibria, a bifurcation that is not a period-doubling,
        symmetry-breaking or branch point of this branch (or a symmetry-breaking point
        off the in-phase orbits), non-positive deltas, an unknown ``shooting`` or
        a bad ``segments`` (naming the argument).
    """


def switch_branch(
    branch: Branch,
    bifurcation: Bifurcation | int,
    *,
    deltas: tuple[float, ...] = SWITCH_DELTAS,
    tol: float = 1e-10,
    rtol: float = 1e-11,
    atol: float = 1e-13,
    fd_step: float = 1e-7,
    shooting: str = "single",
    segments: int = DEFAULT_SEGMENTS,
) -> Orbit:
    bifurcation = _check_switch(branch, bifurcation, deltas, shooting, segments)
    polish = dict(tol=tol, rtol=rtol, atol=atol, shooting=shooting, segments=int(segments))
    switch = {SYMMETRY_BREAKING: _switch_apart, BRANCH_POINT: _switch_crossing}.get(
        bifurcation.kind, _switch_doubling
    )
    orbit = switch(branch, bifurcation, deltas, fd_step, polish)
    orbit.origin, orbit.origin_param = bifurcation, branch.param  # continue_orbit's defaults
    return orbit


switch_branch.__doc__ = _SWITCH_BRANCH_DOC


def _switch_doubling(branch: Branch, bifurcation: Bifurcation, deltas, fd_step: float,
                     polish) -> Orbit:  # fmt: skip
    """switch_branch at a period-doubling point: an orbit of twice the period."""
    rtol, atol, tol = polish["rtol"], polish["atol"], polish["tol"]
    p = branch.period
    mask = np.arange(branch.system.n_state) != SECTION_INDEX
    lam_pd = float(bifurcation.value)
    z_pd = np.asarray(bifurcation.point, dtype=float)
    s_pd = dataclasses.replace(branch.system, **{branch.param: lam_pd})
    v = _minus_one_vector(s_pd, z_pd, p, rtol, atol)
    evaluate2, full, system_at, _ = _orbit_evaluator(branch.system, branch.param, 2 * p, rtol,
                                                     atol, fd_step)  # fmt: skip
    x_pd = np.r_[z_pd[mask], lam_pd]
    last, tried = None, []
    for delta in deltas:
        ok, x = period_doubling_start(evaluate2, x_pd, v, delta, tol=tol)
        tried.append(delta)
        if not ok or _is_period_p(system_at(x[-1]), full(x), p, mask, delta * np.max(
                np.abs(v / np.linalg.norm(v))), rtol, atol):  # fmt: skip
            continue
        last = find_orbit(system_at(x[-1]), full(x), 2 * p, **polish)
        if last.converged:
            return last
    offsets = ", ".join(f"{d:g}" for d in tried)
    return _not_found(last, s_pd, z_pd, 2 * p, tol, rtol, atol,
                      f"no period-{2 * p} orbit found along the -1 eigenvector (offsets "
                      f"tried: {offsets})")  # fmt: skip


def _minus_one_vector(s_pd, z_pd, p, rtol, atol) -> np.ndarray:
    """The eigenvector of D P^p(z_pd) for the multiplier nearest -1 (real part)."""
    st, _, _, jac = return_map(s_pd, z_pd, p, rtol=rtol, atol=atol)
    if st != "ok":
        raise ValueError(f"the return map fails at the bifurcation point: {st}")
    mu, vecs = np.linalg.eig(jac)
    return np.real(vecs[:, int(np.argmin(np.abs(mu + 1.0)))])


def _not_found(last, system, z, period, tol, rtol, atol, message) -> Orbit:
    """The unconverged Orbit :func:`switch_branch` returns when no offset worked."""
    if last is None:
        last = find_orbit(system, z, period, tol=tol, rtol=rtol, atol=atol, max_iter=0)
    last.converged = False
    last.stable = False
    last.message = message
    if last.status == "converged":
        last.status = "no-progress"
    return last


def _is_period_p(s, z, p, mask, offset, rtol, atol) -> bool:
    """A fixed point of P^p (or a failed map) at z: the hyperplane of
    :func:`period_doubling_start` holds one too, but the doubled orbit's P^p image is its
    other half, ~2 ``offset`` away."""
    st_p, pts_p, _, _ = return_map(s, z, p, tangents=False, rtol=rtol, atol=atol)
    return st_p != "ok" or np.max(np.abs(pts_p[-1][mask] - z[mask])) < 0.5 * offset


def _check_switch(branch, bifurcation, deltas, shooting, segments) -> Bifurcation:
    """:func:`switch_branch`'s arguments, checked; returns the Bifurcation."""
    if not isinstance(branch, Branch) or branch.period < 1:
        raise ValueError("branch must be a Branch of periodic orbits (continue_orbit)")
    if isinstance(bifurcation, (int, np.integer)) and not isinstance(bifurcation, bool):
        if not 0 <= bifurcation < len(branch.bifurcations):
            raise ValueError(
                f"bifurcation index {bifurcation} out of range: the branch has "
                f"{len(branch.bifurcations)} bifurcations"
            )
        bifurcation = branch.bifurcations[int(bifurcation)]
    if not isinstance(bifurcation, Bifurcation) or bifurcation.kind not in SWITCH_KINDS:
        kind = getattr(bifurcation, "kind", type(bifurcation).__name__)
        raise ValueError(
            f"bifurcation must be a period-doubling, symmetry-breaking or branch point of the "
            f"branch, got {kind!r}"
        )
    if not deltas or not all(isinstance(d, (int, float)) and math.isfinite(d) and d > 0
                             for d in deltas):  # fmt: skip
        raise ValueError(f"deltas must be finite numbers > 0, got {deltas!r}")
    if shooting not in SHOOTING_MODES:
        raise ValueError(f"shooting must be one of {SHOOTING_MODES}, got {shooting!r}")
    if isinstance(segments, bool) or not isinstance(segments, (int, np.integer)) or segments < 1:
        raise ValueError(f"segments must be an integer >= 1, got {segments!r}")
    return bifurcation


def _switch_apart(branch: Branch, bif: Bifurcation, deltas, fd_step: float, polish) -> Orbit:
    """switch_branch at a symmetry-breaking point: an orbit of the same period with the
    disks apart.

    With Phi_d a = a (the transverse multiplier +1), the return map's eigenvector is
    v = P a - (a_dx / f_dx1) f (P a: a on disk 1, -a on disk 2; :mod:`.synchrony`), and
    the branch with the disks apart leaves the in-phase one tangent to (v, 0). The
    predictor z* + delta v / abs(P a) is corrected within the hyperplane through it
    normal to P a, which no in-phase point reaches (P a is orthogonal to them)."""
    p, system = branch.period, branch.system
    rtol, atol, tol = polish["rtol"], polish["atol"], polish["tol"]
    mask = np.arange(system.n_state) != SECTION_INDEX
    lam = float(bif.value)
    z = np.asarray(bif.point, dtype=float)
    s_sb = dataclasses.replace(system, **{branch.param: lam})
    if not synchronous_point(s_sb, z):
        raise ValueError("bifurcation: a symmetry-breaking point must lie on in-phase orbits")
    st, _, _, jac = return_map(s_sb, z, p, rtol=rtol, atol=atol)
    if st != "ok":
        raise ValueError(f"the return map fails at the bifurcation point: {st}")
    mu, vecs = np.linalg.eig(transverse_monodromy(s_sb, z, jac))
    a = np.real(vecs[:, int(np.argmin(np.abs(mu - 1.0)))])
    P = pair_matrix(system.n_state)
    pair = P @ a  # a on disk 1, -a on disk 2
    v = section_directions(P, _field(s_sb, z)) @ a
    size = float(np.linalg.norm(pair[mask]))
    normal = np.r_[pair[mask] / size, 0.0]
    evaluate, full, system_at, _ = _orbit_evaluator(system, branch.param, p, rtol, atol, fd_step)
    last, tried = None, []
    for delta in sorted(deltas):  # the smallest that resolves the branch: nearest the point
        x_pred = np.r_[z[mask], lam] + delta * np.r_[v[mask], 0.0] / size
        tried.append(delta)
        ok, G, _, _ = evaluate(x_pred)
        # too small an offset: the map is flat to ~tol there (its normal form is cubic), so
        # the shifted in-phase point passes for a fixed point of its own
        if not ok or np.max(np.abs(G)) <= FLAT * tol:
            continue
        ok, x, _, _ = _correct(evaluate, x_pred, normal, x_pred, tol, 8)
        if not ok or x[-1] == lam or synchronous_point(system_at(x[-1]), full(x), 0.01 * delta):
            continue
        last = find_orbit(system_at(x[-1]), full(x), p, **polish)
        if last.converged and not synchronous_point(last.system, last.points[0], 0.01 * delta):
            return last
    offsets = ", ".join(f"{d:g}" for d in tried)
    return _not_found(last, s_sb, z, p, tol, rtol, atol,
                      f"no period-{p} orbit with the disks apart found along the transverse "
                      f"eigenvector (offsets tried: {offsets})")  # fmt: skip


def _switch_crossing(branch: Branch, bif: Bifurcation, deltas, fd_step: float, polish) -> Orbit:
    """switch_branch at a branch point: an orbit of the branch that crosses this one.

    At a simple branch point DG has a two-dimensional null space, which holds both
    branches' tangents. The start leaves along phi, the null direction orthogonal to
    the branch's own tangent (the chord through the point), and is corrected within the
    hyperplane normal to phi through the predictor, which the old branch (tangent to
    it) does not reach nearby; a result more than delta / 2 from the predictor is not
    the crossing branch. Offsets are tried smallest first, each on both sides, skipping
    those whose predictor's residual is already below ``FLAT * tol`` (G is quadratic in
    the distance from a branch point: such a start passes for a solution anywhere)."""
    p, system = branch.period, branch.system
    rtol, atol, tol = polish["rtol"], polish["atol"], polish["tol"]
    mask = np.arange(system.n_state) != SECTION_INDEX
    lam, z = float(bif.value), np.asarray(bif.point, dtype=float)
    evaluate, full, system_at, _ = _orbit_evaluator(system, branch.param, p, rtol, atol, fd_step)
    x_bp = np.r_[z[mask], lam]
    ok, _, DG, _ = evaluate(x_bp)
    if not ok:
        raise ValueError("the return map fails at the bifurcation point")
    i = min(bif.index, len(branch.values) - 2)
    chord = np.r_[(branch.points[i + 1] - branch.points[i])[mask],
                  branch.values[i + 1] - branch.values[i]]  # fmt: skip
    null = np.linalg.svd(DG)[2][-2:]  # the two right singular vectors nearest the null space
    tc = null @ chord  # the branch's tangent in that plane's coordinates
    phi = null.T @ np.array([-tc[1], tc[0]])
    phi /= np.linalg.norm(phi)
    last, tried = None, []
    for delta in sorted(deltas):
        tried.append(delta)
        for sign in (1.0, -1.0):
            x_pred = x_bp + sign * delta * phi
            ok, G, _, _ = evaluate(x_pred)
            if not ok or np.max(np.abs(G)) <= FLAT * tol:  # too close: G is quadratic there
                continue
            ok, x, _, _ = _correct(evaluate, x_pred, phi, x_pred, tol, 8)
            if not ok or np.linalg.norm(x - x_pred) > 0.5 * delta:
                continue
            last = find_orbit(system_at(x[-1]), full(x), p, **polish)
            # still off the old branch (Newton at fixed lambda could have fallen back on it),
            # and not the old branch's own orbit at this lambda (found from the point)
            off = abs(phi @ (np.r_[last.points[0][mask], x[-1]] - x_bp))
            if not last.converged or off <= 0.5 * delta:
                continue
            old = find_orbit(last.system, z, p, **polish)
            if not old.converged or np.max(np.abs(old.points[0] - last.points[0])) > 0.5 * delta:
                return last
    offsets = ", ".join(f"{d:g}" for d in tried)
    return _not_found(last, system_at(lam), z, p, tol, rtol, atol,
                      f"no period-{p} orbit of a crossing branch found (offsets tried: {offsets})")  # fmt: skip
