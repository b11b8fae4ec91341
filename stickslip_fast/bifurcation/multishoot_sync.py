"""Symmetry-breaking points on branches of in-phase orbits followed by multiple shooting.

Single shooting marks where a transverse multiplier of an in-phase orbit of disks on
one DC motor passes +1 (:func:`.synchrony.in_phase_walk`). Multiple shooting does the
same here, on its own unknowns x = (y_0 on the section, y_1, ..., y_{m-1}, T, lambda)
(:class:`.multishoot.MultiShooting`):

* **The walk stays in phase.** Every segment start is projected onto the in-phase
  states before the segments are integrated, G_i(x) = phi(S y_i, tau_i) - y_{i+1}, so
  the solutions are the in-phase orbits and D G is regular across the disks (there it
  is the block-cyclic shift by -I): Newton cannot slide onto the orbits with the disks
  apart that lie ~1e-6 away next to the pitchfork.
* **The test needs no product.** Each segment's state-transition matrix maps a
  difference between disks 1 and 2, P a (a on disk 1, -a on disk 2; :func:`.synchrony.
  pair_matrix`), to P B_i a plus a multiple of the field, which is in phase, so the
  transverse monodromy Phi_d = B_{m-1} ... B_0 has the 4 x 4 factors
  B_i = (1/2) P^T Phi_i P (the first on the section directions, the last after the
  projection onto the section). Its eigenvalues, the transverse multipliers, come from
  the periodic QR scheme of :func:`.multishoot.periodic_multipliers`, so a multiplier of
  1e8 along the disks does not swamp the one near +1 across them. The test function
  is the product of (mu - 1) over them: det(Phi_d - I), as on single shooting.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..model.system import System
from .multishoot import MultiShooting, periodic_multipliers
from .returnmap import SECTION_INDEX, _field
from .synchrony import (
    SYMMETRY_BREAKING,
    WALK_SYNC_TOL,
    in_phase_projector,
    pair_matrix,
    section_directions,
    state_projector,
    synchronous_point,
    transverse_monodromy,
)

__all__ = ["in_phase_start", "project_segments", "transverse_factors", "symmetry_breaking_test"]


def in_phase_start(system: System, ms: MultiShooting, x: np.ndarray) -> bool:
    """Whether every segment start of x = (u, lambda) has the disks in phase (to
    :data:`.synchrony.WALK_SYNC_TOL`), for disks on one DC motor."""
    if not (system.is_dc_motor and system.n_oscillators >= 2):
        return False
    Y, _ = ms.unpack(x[:-1])
    return all(synchronous_point(system, y, WALK_SYNC_TOL) for y in Y)


def _unknowns_projector(system: System, ms: MultiShooting) -> np.ndarray:
    """Pi on x = (u, lambda): the section projector on y_0, the state projector on every
    other start, T and lambda kept."""
    n, m = ms.n, ms.m
    size = m * n + 1
    Pi = np.zeros((size, size))
    Pi[: n - 1, : n - 1] = in_phase_projector(system)
    S = state_projector(system)
    for i in range(1, m):
        c = ms._cols(i)
        Pi[c, c] = S
    Pi[-2, -2] = Pi[-1, -1] = 1.0
    return Pi


def _shift(ms: MultiShooting) -> np.ndarray:
    """E: the linear part of G in the starts, G_i = phi(y_i) - y_{i+1} = ... - E_i x
    (the identity in y_{(i + 1) mod m}'s columns of row block i, y_0 on the section)."""
    n, m = ms.n, ms.m
    E = np.zeros((m * n, m * n + 1))
    eye = np.eye(n)
    for i in range(m):
        j = (i + 1) % m
        E[i * n : (i + 1) * n, ms._cols(j)] = eye[:, ms.mask] if j == 0 else eye
    return E


def project_segments(evaluate: Callable, system: System, ms: MultiShooting) -> Callable:
    """``evaluate`` of the multiple-shooting system restricted to the in-phase states.

    With x_s = Pi x (every start projected), G(x) = phi(S y_i) - y_{i+1}
    = G_raw(x_s) + E (x_s - x) and D G = (D G_raw(x_s) + E) Pi - E. The fourth output
    becomes (factors, x_s): the segments' factors of the section Jacobian at the
    in-phase orbit, and that orbit's unknowns.
    """
    Pi = _unknowns_projector(system, ms)
    E = _shift(ms)

    def projected(x: np.ndarray):
        xs = Pi @ x
        ok, G, DG, A = evaluate(xs)
        if not ok:
            return ok, G, DG, A
        return True, G + E @ (xs - x), (DG + E) @ Pi - E, (A, xs)

    return projected


def transverse_factors(system: System, y0: np.ndarray, factors: list[np.ndarray]) -> list:
    """The 4 x 4 factors B_0, ..., B_{m-1} of the transverse monodromy of the in-phase
    orbit through ``y0`` (on the section) from the segments' factors of its section
    Jacobian (:meth:`.multishoot.MultiShooting.section_factors`)."""
    if len(factors) == 1:  # one segment: the factor is D P itself
        return [transverse_monodromy(system, y0, factors[0])]
    pair = pair_matrix(system.n_state)
    mask = np.arange(system.n_state) != SECTION_INDEX
    U = section_directions(pair, _field(system, y0))
    first = 0.5 * pair.T @ (factors[0] @ U[mask])
    middle = [0.5 * pair.T @ (A @ pair) for A in factors[1:-1]]
    last = 0.5 * pair[mask].T @ (factors[-1] @ pair)
    return [first, *middle, last]


def symmetry_breaking_test(system: System, y0: np.ndarray, factors: list[np.ndarray]) -> float:
    """det(Phi_d - I), the product of (mu - 1) over the transverse multipliers: its sign
    changes where one passes +1 (a pair through -1 or around the circle changes the sign
    of no factor pair)."""
    mu = periodic_multipliers(transverse_factors(system, y0, factors))
    return float(np.prod(mu - 1.0).real)


def in_phase_marks(system_at: Callable, ms: MultiShooting, tests: Callable,
                   spectrum: Callable) -> dict[str, Any]:  # fmt: skip
    """``tests`` and ``spectrum`` of :func:`.arclength.pseudo_arclength` for a projected
    walk, whose fourth output is (factors, x): the map's own ``tests`` plus
    ``"symmetry-breaking"``."""

    def tests_in_phase(Ax, t: np.ndarray) -> dict[str, float]:
        A, x = Ax
        y0 = ms.unpack(x[:-1])[0][0]
        return {**tests(A, t), SYMMETRY_BREAKING: symmetry_breaking_test(system_at(x[-1]), y0, A)}

    def spectrum_in_phase(Ax) -> np.ndarray:
        return spectrum(Ax[0])

    return {"tests": tests_in_phase, "spectrum": spectrum_in_phase}
