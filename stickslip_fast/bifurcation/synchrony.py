"""Stability of in-phase motion: the Floquet multipliers across the disks and along them.

N >= 2 identical disks started alike stay alike: the in-phase (synchronous) states,
every disk in disk 1's state, form an invariant subspace S of the state space. An
orbit in S has two kinds of multipliers:

* **longitudinal**, those of perturbations that keep the disks alike (inside S);
* **transverse**, those of perturbations that set the disks apart, every pattern
  d_1 + ... + d_N = 0 of disk perturbations with the belt speed held (the
  subspace A, orthogonal to S).

Why they split, and why the transverse ones do not depend on N
---------------------------------------------------------------
The motor feels the disks through the mean (beta / N) sum_i T_s(...) of their torques
(:mod:`stickslip_fast.model.equations`). A transverse perturbation changes that mean
by sum_i d_i = 0 to first order, so the belt speed stays on the synchronous orbit
and every disk's perturbation obeys one and the same 4 x 4 equation d' = A_d(t) d:
the linearisation of one disk driven by the orbit's belt speed v_b(t). The
monodromy maps A to itself, as N - 1 copies of the 4 x 4 monodromy Phi_d. So the
transverse multipliers are the eigenvalues of Phi_d, each N - 1 times, and since
the in-phase motion of N disks is the motion of one disk on the motor (the mean of N
equal torques is one torque), they are the same for every N. On a constant belt
the disks are uncoupled and Phi_d is simply each disk's own monodromy.

From the return map's Jacobian
------------------------------
:func:`~stickslip_fast.find_orbit` gives D P = (I - f e^T / (e^T f)) Phi in section
coordinates (docs/orbits.md; e is the section normal dx1, f the field at the
point z, which lies in S). For a disk perturbation a, the vector
v = P a - (a_dx / f_dx1) f (P a: a on disk 1, -a on disk 2) lies on the section, and
D P v = P Phi_d a - gamma f with f orthogonal to P's columns, so
Phi_d = (1/2) P^T D P [v_1 .. v_4]. The longitudinal block is D P restricted to the
section's part of S (the disks alike with dx = 0, and v_b), which it maps to
itself. The transverse and longitudinal multipliers together are the multipliers
of :attr:`Orbit.multipliers`; :attr:`SyncStability.residual` measures how well
the computed Jacobian keeps the two subspaces apart.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..base.messages import plain
from ..model.system import System
from .detection import _sorted_eigs, _tests
from .orbit_record import Orbit
from .returnmap import SECTION_INDEX, _field, _multipliers

__all__ = [
    "SyncStability",
    "sync_stability",
    "synchronous_point",
    "transverse_block",
    "transverse_monodromy",
    "monodromy_across",
    "in_phase_walk",
    "in_phase_projector",
    "project_in_phase",
    "pair_matrix",
    "section_directions",
]

#: Largest difference between the disks, relative to max(1, abs(state)), for a point
#: to count as in phase (a Newton fixed point from an in-phase start differs by ~tol).
SYNC_TOL = 1e-6

#: The stricter test :func:`in_phase_walk` applies to a branch's start before it keeps the
#: walk in phase: orbits found from in-phase runs agree to ~1e-8 even next to an SB point
#: (measured 1.5e-8), the orbits with the disks apart that :func:`switch_branch` returns
#: differ by 1.7e-6 or more, and those must not be projected back onto the in-phase ones.
WALK_SYNC_TOL = 1e-7


@dataclass
class SyncStability:
    """The stability of an in-phase orbit across the disks and along them.

    Attributes
    ----------
    transverse : ndarray of complex, shape (4,)
        The transverse multipliers (eigenvalues of the 4 x 4 monodromy of a
        difference between the disks), largest modulus first. Each is a
        multiplier of the orbit ``multiplicity`` times.
    longitudinal : ndarray of complex, shape (4,) or (3,)
        The nontrivial multipliers inside the in-phase subspace (4 on a DC motor,
        3 on a constant belt), largest modulus first: those of one disk on the
        same drive.
    multiplicity : int
        N - 1.
    transverse_stable, longitudinal_stable : bool
        Every transverse (longitudinal) multiplier inside the unit circle. An
        in-phase orbit that is longitudinally stable but transversally unstable is
        an attractor of identical disks only: the slightest difference between the
        disks leaves it. On a constant belt the disks are uncoupled: one transverse
        multiplier is exactly 1 (a phase shift between the disks neither grows nor
        decays; computed as 1 - ~1e-6), and ``transverse_stable`` is False.
    transverse_block : ndarray, shape (4, 4)
        The transverse monodromy in one disk's coordinates (x, dx, phi, dphi).
    residual : float
        How far the Jacobian is from keeping the two subspaces apart: the largest
        part of an image of a unit vector that falls outside its subspace, relative
        to the largest entry of the Jacobian. It measures the accuracy of the
        tangents (1e-9 to 1e-7 at find_orbit's defaults).
    orbit : Orbit
        The orbit analysed.
    """

    transverse: np.ndarray
    longitudinal: np.ndarray
    multiplicity: int
    transverse_stable: bool
    longitudinal_stable: bool
    transverse_block: np.ndarray
    residual: float
    orbit: Orbit

    @property
    def stable(self) -> bool:
        """Stable in every direction (equals ``orbit.stable``)."""
        return self.transverse_stable and self.longitudinal_stable

    def __repr__(self) -> str:
        tr = ", ".join(f"{m:.4g}" for m in self.transverse[:2])
        lo = ", ".join(f"{m:.4g}" for m in self.longitudinal[:2])
        return (
            f"SyncStability(transverse=[{tr}, ...] x{self.multiplicity}, "
            f"longitudinal=[{lo}, ...], transverse_stable={self.transverse_stable}, "
            f"longitudinal_stable={self.longitudinal_stable}, residual={self.residual:.1e})"
        )


def synchronous_point(system: System, z: np.ndarray, tol: float = SYNC_TOL) -> bool:
    """Whether the state ``z`` of ``system`` has every disk in disk 1's state (to ``tol``
    relative to max(1, abs(z)); N >= 2)."""
    n = system.n_oscillators
    if n < 2:
        return False
    disks = np.asarray(z, dtype=float)[: 4 * n].reshape(n, 4)
    scale = max(1.0, float(np.max(np.abs(disks))))
    return bool(np.max(np.abs(disks - disks[0])) <= tol * scale)


def _embed(system: System, jac: np.ndarray, v: np.ndarray) -> np.ndarray:
    """D P v in full coordinates, for v on the section (dx1 = 0)."""
    mask = np.arange(system.n_state) != SECTION_INDEX
    w = np.zeros(system.n_state)
    w[mask] = jac @ v[mask]
    return w


def _outside(w: np.ndarray, basis: np.ndarray, scale: float) -> float:
    """The part of ``w`` outside span(basis), relative to ``scale``."""
    coef = np.linalg.lstsq(basis, w, rcond=None)[0]
    return float(np.max(np.abs(w - basis @ coef))) / scale


def pair_matrix(n: int) -> np.ndarray:
    """P: the columns e_j on disk 1 and -e_j on disk 2 (n_state x 4), a basis of one copy
    of the transverse perturbations."""
    pair = np.zeros((n, 4))
    pair[0:4] = np.eye(4)
    pair[4:8] = -np.eye(4)
    return pair


def section_directions(pair: np.ndarray, f: np.ndarray) -> np.ndarray:
    """U: the columns of ``pair`` moved onto the section along the field f (their dx1 made
    0), u = P a - (P a)_dx1 / f_dx1 f; D P maps U a to P Phi_d a plus a multiple of f."""
    return pair - np.outer(f, pair[SECTION_INDEX] / f[SECTION_INDEX])


def monodromy_across(jac: np.ndarray, pair: np.ndarray, U: np.ndarray) -> np.ndarray:
    """Phi_d = (1/2) P^T D P U from the return map's Jacobian in section coordinates (D P's
    images have dx1 = 0, so P^T runs over the other rows)."""
    mask = np.arange(pair.shape[0]) != SECTION_INDEX
    return 0.5 * pair[mask].T @ (jac @ U[mask])


def transverse_monodromy(system: System, z: np.ndarray, jac: np.ndarray) -> np.ndarray:
    """Phi_d at the in-phase point ``z`` (:func:`transverse_block` without its check)."""
    pair = pair_matrix(system.n_state)
    return monodromy_across(jac, pair, section_directions(pair, _field(system, z)))


def transverse_block(system: System, z: np.ndarray, jac: np.ndarray) -> tuple[np.ndarray, float]:
    """The 4 x 4 transverse monodromy of an in-phase orbit from its return map's Jacobian.

    Parameters
    ----------
    system : System
        N >= 2 disks.
    z : ndarray, shape (n_state,)
        The orbit's point on the section (in phase).
    jac : ndarray, shape (n_state - 1, n_state - 1)
        D P^p at ``z`` in section coordinates (:attr:`Orbit.jacobian`).

    Returns
    -------
    block : ndarray, shape (4, 4)
        Phi_d: its eigenvalues are the transverse multipliers.
    residual : float
        The largest part of an image D P v outside span(P, f), relative to
        max(abs(jac)) max(abs(v)).
    """
    f = _field(system, z)
    pair = pair_matrix(system.n_state)
    U = section_directions(pair, f)
    block = monodromy_across(jac, pair, U)
    residual = 0.0
    for j in range(4):
        v = U[:, j]
        w = _embed(system, jac, v)
        scale = max(float(np.max(np.abs(jac))) * float(np.max(np.abs(v))), 1e-300)
        residual = max(residual, _outside(w, np.column_stack([pair, f]), scale))
    return block, residual


def _longitudinal(system: System, jac: np.ndarray) -> tuple[np.ndarray, float]:
    """D P on the section's part of S (disks alike, dx = 0; and v_b) in that basis."""
    n_osc, n = system.n_oscillators, system.n_state
    cols = []
    for j in (0, 2, 3):  # x, phi, dphi of every disk alike (dx = 0 on the section)
        q = np.zeros(n)
        q[j : 4 * n_osc : 4] = 1.0
        cols.append(q)
    if system.is_dc_motor:
        cols.append(np.eye(n)[-1])
    basis = np.column_stack(cols)
    images = np.column_stack([_embed(system, jac, basis[:, j]) for j in range(basis.shape[1])])
    block = np.linalg.lstsq(basis, images, rcond=None)[0]
    scale = max(float(np.max(np.abs(jac))), 1e-300)
    residual = max(_outside(images[:, j], basis, scale) for j in range(basis.shape[1]))
    return block, residual


def sync_stability(orbit: Orbit, *, tol: float = SYNC_TOL) -> SyncStability:
    """Split an in-phase orbit's Floquet multipliers into transverse and longitudinal ones.

    For N >= 2 identical disks in phase (every disk in disk 1's state), the
    multipliers of :func:`~stickslip_fast.find_orbit` fall into those inside the
    in-phase subspace (the orbit of one disk on the same drive) and those of a
    difference between the disks, each N - 1 times (:mod:`.synchrony` derives the
    split). In-phase motion is observable only if both are inside the unit circle;
    the transverse ones are the same for every N (the motor feels the mean torque).

    Parameters
    ----------
    orbit : Orbit
        A converged orbit of N >= 2 disks whose points are in phase (e.g. found from
        a run that started every disk alike).
    tol : float, optional
        How far apart the disks may be at the orbit's points, relative to
        max(1, abs(state)) (default 1e-6: Newton leaves them ~``find_orbit``'s
        ``tol`` apart, more near a symmetry-breaking point, where the
        transverse direction is barely contracted).

    Returns
    -------
    SyncStability

    Raises
    ------
    ValueError
        If the orbit has one disk, did not converge, or is not in phase (naming the
        disks' largest difference).

    Examples
    --------
    >>> two = ssf.System.preset("symmetric", drive="dc-motor", n_oscillators=2, eta=5.0)
    >>> run = ssf.simulate(two, 3000, 2000)      # from rest: the disks stay alike
    >>> s = ssf.sync_stability(ssf.find_orbit(two, run))
    >>> round(float(s.transverse[0].real), 4), s.transverse_stable, s.longitudinal_stable
    (1.0923, False, True)
    """
    if not isinstance(orbit, Orbit):
        raise TypeError(f"orbit must be an Orbit (from find_orbit), got {type(orbit).__name__}")
    system = orbit.system
    if system.n_oscillators < 2:
        raise ValueError("orbit: sync_stability needs N >= 2 disks (system.n_oscillators is 1)")
    if not orbit.converged:
        raise ValueError(f"orbit: not converged (status {orbit.status!r}): {orbit.message}")
    if not tol > 0:
        raise ValueError(f"tol must be > 0, got {plain(tol)}")
    for k, z in enumerate(orbit.points):
        if not synchronous_point(system, z, tol):
            disks = z[: 4 * system.n_oscillators].reshape(-1, 4)
            gap = float(np.max(np.abs(disks - disks[0])))
            raise ValueError(
                f"orbit: not in phase (at points[{k}] the disks differ by up to {gap:.3g}, "
                f"more than tol={tol:g} relative); sync_stability analyses in-phase orbits"
            )
    z = orbit.points[0]
    block, res_t = transverse_block(system, z, orbit.jacobian)
    lblock, res_l = _longitudinal(system, orbit.jacobian)
    transverse = _multipliers(block)
    longitudinal = _multipliers(lblock)
    return SyncStability(
        transverse=transverse,
        longitudinal=longitudinal,
        multiplicity=system.n_oscillators - 1,
        # uncoupled disks (a constant belt) keep their own phases: a multiplier is exactly 1
        transverse_stable=bool(np.all(np.abs(transverse) < 1.0) and system.is_dc_motor),
        longitudinal_stable=bool(np.all(np.abs(longitudinal) < 1.0)),
        transverse_block=block,
        residual=max(res_t, res_l),
        orbit=orbit,
    )


def state_projector(system: System, coords=(0, 1, 2, 3)) -> np.ndarray:
    """The orthogonal projector onto the in-phase states (n_state x n_state): each disk's
    coordinates ``coords`` (of x, dx, phi, dphi) replaced by their mean over the disks,
    the others set to 0, v_b kept."""
    n_osc, n = system.n_oscillators, system.n_state
    full = np.zeros((n, n))
    for j in coords:
        idx = np.arange(j, 4 * n_osc, 4)
        full[np.ix_(idx, idx)] = 1.0 / n_osc
    if system.is_dc_motor:
        full[-1, -1] = 1.0
    return full


def in_phase_projector(system: System) -> np.ndarray:
    """The orthogonal projector onto the in-phase states of the section, in section
    coordinates (the state without dx1): each disk's x, phi and dphi replaced by their
    mean over the disks, every dx set to 0 (dx1 is 0 on the section), v_b kept."""
    mask = np.arange(system.n_state) != SECTION_INDEX
    return state_projector(system, (0, 2, 3))[np.ix_(mask, mask)]


def project_in_phase(evaluate: Callable, S: np.ndarray, n_params: int,
                     periods: dict[bytes, float] | None = None) -> Callable:  # fmt: skip
    """``evaluate`` of G(x) = P(z) - z restricted to the in-phase subspace: G(x) =
    P(S z) - z, with Jacobian D P(S z) S - I in z.

    x = (z, parameters), ``n_params`` of them. The solutions are the in-phase fixed
    points, and D G is regular in the directions across the disks (there it is -I),
    so Newton cannot leave the subspace for a nearby orbit with the disks apart. The
    fourth output stays the map's own Jacobian D P(S z) (for the multipliers).
    ``periods``: the evaluator's record of return times by x's bytes, where x gets the
    one of S z too.
    """
    nz = S.shape[0]

    def projected(x: np.ndarray):
        xs = x.copy()
        xs[:nz] = S @ x[:nz]
        ok, G, DG, A = evaluate(xs)
        if not ok:
            return ok, G, DG, A
        if periods is not None and xs.tobytes() in periods:
            periods[x.tobytes()] = periods[xs.tobytes()]
        DG = DG.copy()
        DG[:, :nz] = A @ S - np.eye(nz)
        return True, G + (xs - x)[:nz], DG, A

    return projected


#: The kind of the bifurcation :func:`in_phase_walk` adds to an in-phase branch.
SYMMETRY_BREAKING = "symmetry-breaking"


def in_phase_walk(orbit: Orbit, system_at, full, evaluate, refine, periods=None):
    """What :func:`~stickslip_fast.continue_orbit` needs to mark symmetry-breaking points.

    Along a branch of in-phase orbits of disks on one DC motor, a transverse
    multiplier through +1 is a symmetry-breaking pitchfork: two orbits with the
    disks apart (one the other with the disks swapped) branch off, and the
    in-phase orbit changes stability, with no fold and no period-doubling for the
    usual test functions to see. Its test function is det(Phi_d - I), the product
    of (mu - 1) over the transverse multipliers. (Through -1 or as a complex pair
    the transverse multipliers are seen by the period-doubling and Neimark-Sacker
    tests of the whole map.)

    Parameters
    ----------
    orbit : Orbit
        The branch's start; nothing changes unless it is in phase (to
        :data:`WALK_SYNC_TOL`) on a DC motor.
    system_at : callable
        lambda -> System on the branch.
    full : callable
        Branch coordinates x (section coordinates and lambda) -> the state.
    evaluate : callable
        The branch's evaluator (:func:`.arclength.pseudo_arclength`).
    refine : list of (evaluator, tol, ds_min)
        Its refinement stages.
    periods : dict, optional
        The evaluators' return times by x's bytes (:func:`project_in_phase`).

    The walk is kept in the in-phase subspace (:func:`project_in_phase`): next to the
    pitchfork the orbits with the disks apart lie ~1e-6 away, and without the
    projection a step across the point could land on them (measured: a step of 0.01 in
    eta over the point at beta = 0.00141 did, and the test never changed sign).

    Returns
    -------
    evaluate, refine
        The same, projected, their fourth output ``(jacobian, x)`` for an in-phase
        branch.
    marks : dict
        ``tests`` (the map's test functions plus ``"symmetry-breaking"``) and
        ``spectrum`` for :func:`.arclength.pseudo_arclength`; empty otherwise.
    """
    system = orbit.system
    if not (system.is_dc_motor
            and all(synchronous_point(system, z, WALK_SYNC_TOL) for z in orbit.points)):  # fmt: skip
        return evaluate, refine, {}

    S = in_phase_projector(system)

    def wrap(ev: Callable[[np.ndarray], Any]) -> Callable[[np.ndarray], Any]:
        projected = project_in_phase(ev, S, 1, periods)

        def in_phase(x: np.ndarray):
            ok, G, DG, A = projected(x)
            return (ok, G, DG, (A, x)) if ok else (ok, G, DG, A)

        return in_phase

    def tests(A, t: np.ndarray) -> dict[str, float]:
        jac, x = A
        block = transverse_monodromy(system_at(float(x[-1])), full(x), jac)
        return {**_tests(jac, t), SYMMETRY_BREAKING: float(np.linalg.det(block - np.eye(4)))}

    def spectrum(A) -> np.ndarray:
        return _sorted_eigs(A[0])

    stages = [(wrap(ev), tol, ds_min) for ev, tol, ds_min in refine]
    return wrap(evaluate), stages, {"tests": tests, "spectrum": spectrum}
