"""Bifurcation test functions along a branch (the locators that use them are in arclength.py).

Orbits: folds (a multiplier through +1), period-doublings (through -1), Neimark-Sacker
points (a complex pair through the unit circle); equilibria: folds and Hopf points; both:
branch points, where another branch crosses (:func:`branch_point_test`). A change in the
orbit's stick phases is located by bisection."""

from __future__ import annotations

import math

import numpy as np


def _tests(A: np.ndarray, t: np.ndarray) -> dict[str, float]:
    """Test functions whose sign changes mark the bifurcations of a map's fixed points."""
    mu = np.linalg.eigvals(A)
    cplx = mu[np.abs(mu.imag) > 1e-12 * np.maximum(1.0, np.abs(mu))]
    ns = math.nan  # |mu| - 1 of the complex pair nearest the unit circle
    if cplx.size:
        ns = float((np.abs(cplx) - 1.0)[np.argmin(np.abs(np.abs(cplx) - 1.0))])
    return {
        "fold": float(t[-1]),  # d lambda / ds
        "period-doubling": float(np.linalg.det(A + np.eye(A.shape[0]))),  # prod (mu + 1)
        "neimark-sacker": ns,
    }


def _equilibrium_tests(J: np.ndarray, t: np.ndarray) -> dict[str, float]:
    """Test functions of an ODE's equilibria: the fold (d lambda / ds), and the Hopf
    point (the largest real part among complex eigenvalues of the Jacobian J: it
    changes sign when the rightmost complex pair crosses the imaginary axis)."""
    ev = np.linalg.eigvals(J)
    cplx = ev[np.abs(ev.imag) > 1e-12 * np.maximum(1.0, np.abs(ev))]
    return {
        "fold": float(t[-1]),
        "hopf": float(cplx.real.max()) if cplx.size else math.nan,
    }


def _eigs_by_real_part(J):
    ev = np.linalg.eigvals(J).astype(complex)
    return ev[np.argsort(-ev.real, kind="stable")]


def _sorted_eigs(A):
    ev = np.linalg.eigvals(A).astype(complex)
    return ev[np.argsort(-np.abs(ev), kind="stable")]


#: The kind of a branch point: two branches of solutions cross (label BP).
BRANCH_POINT = "branch-point"


def _bordered(DG: np.ndarray, t: np.ndarray) -> np.ndarray:
    """[DG; t^T]: the Jacobian of the corrector's system, regular at regular points and
    at folds, singular where a second branch crosses."""
    return np.vstack([DG, t[None, :]])


def branch_point_test(DG: np.ndarray, t: np.ndarray) -> float:
    """The branch-point test: det [DG; t^T], rows scaled to unit length.

    With t the tangent oriented continuously along the branch, it changes sign where
    a second branch of solutions crosses (a simple branch point: the null space of DG
    is two-dimensional there), and keeps its sign through a fold (AUTO and MatCont
    use the same determinant). Scaling the rows bounds it by 1 (Hadamard) and leaves
    its sign and zeros alone."""
    M = _bordered(DG, t)
    return float(np.linalg.det(M / np.linalg.norm(M, axis=1)[:, None]))


#: Below this :func:`rank_gap`, DG is taken to have two null directions: the walk's
#: tangent is then noise, and so are the fold and branch-point tests built on it. An
#: orbit branch's DG at the default tolerances is accurate to 1e-9 to 3e-7 of its norm
#: (measured along the anti-phase branch of two disks on one motor: rtol 1e-11 against
#: 1e-12), so a second singular value below 1e-6 of the largest is within a few times
#: the noise; folds and branch points away from such places have gaps of 4e-4 and more.
RANK_GAP_MIN = 1e-6


def rank_gap(DG: np.ndarray) -> float:
    """sigma_m / sigma_1 of DG (m x (m + 1)): its smallest singular value over its largest.

    Zero where DG has a second null direction besides the tangent (at a branch point,
    or all along a family of solutions at one parameter value); small near them."""
    return singular_gaps(DG)[0]


def singular_gaps(DG: np.ndarray) -> tuple[float, float]:
    """(sigma_m / sigma_1, sigma_m / sigma_(m-1)) of DG (m x (m + 1)), from one SVD.

    The first is :func:`rank_gap`. The second measures the smallest singular value
    against the rest of the spectrum, not against the largest alone: past a sharp fold
    one multiplier of 1e6 makes sigma_1 huge and the first gap small (6e-8 on Fig. 12's
    period-2 branch) while sigma_m stays 0.1-0.35, no second null direction; along a
    family of solutions at one parameter value both are small (1e-8 where a disk is
    nearly undamped). For m = 1 both are the first.
    """
    s = np.linalg.svd(DG, compute_uv=False)
    if s[0] <= 0:
        return 0.0, 0.0
    below = s[-2] if s.size > 1 else s[0]
    return float(s[-1] / s[0]), float(s[-1] / below) if below > 0 else 0.0
