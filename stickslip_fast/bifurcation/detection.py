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


def point_spread(DG: np.ndarray, t: np.ndarray, tol: float) -> float:
    """How far a point converged to ``tol`` can lie from the exact branch point:
    tol times the norm of [DG; t^T]'s inverse (inf where it is singular).

    Large where DG is nearly singular in a direction other than the tangent: the
    corrector's residual no longer pins the point down along that direction, and the
    tangent, the fold test and the branch-point test there are noise."""
    smallest = float(np.linalg.svd(_bordered(DG, t), compute_uv=False)[-1])
    return math.inf if smallest == 0.0 else tol / smallest
