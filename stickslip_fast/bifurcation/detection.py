"""Bifurcation test functions along a branch (the locators that use them are in arclength.py).

Orbits: folds (a multiplier through +1), period-doublings (through -1), Neimark-Sacker
points (a complex pair through the unit circle); equilibria: folds and Hopf points. A
change in the orbit's stick phases is located by bisection."""

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
