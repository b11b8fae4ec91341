"""Continuation of equilibria (steady sliding, a stalled motor), with folds and Hopf points."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..model.equations import dense_jacobian
from .arclength import pseudo_arclength
from .branch import Bifurcation, Branch
from .detection import _eigs_by_real_part, _equilibrium_tests
from .orbits import (
    Equilibrium,
    _field,
)
from .progress import points_bar
from .walk_args import _check_args, _difference


# ------------------------------------------------------------------ equilibria
def continue_equilibrium(
    equilibrium: Equilibrium,
    param: str,
    bounds: tuple[float, float],
    *,
    ds: float = 0.01,
    ds_min: float = 1e-8,
    ds_max: float = 0.05,
    max_points: int = 200,
    direction: float = 1.0,
    tol: float = 1e-12,
    fd_step: float = 1e-7,
    progress: bool | None = None,
) -> Branch:
    """Continue an equilibrium (steady sliding, the stalled motor) in one parameter.

    Pseudo-arclength continuation of f(y; lambda) = 0 with the analytic
    Jacobian in y (:func:`stickslip_fast.model.equations.dense_jacobian`) and a central
    difference in lambda. Along the branch it records the Jacobian's
    eigenvalues and the stability, and locates (to ~1e-9 in the parameter)
    folds (lambda turns back: an eigenvalue through 0) and Hopf points (a
    complex pair crosses the imaginary axis: the rightmost complex pair's
    real part changes sign).

    Parameters
    ----------
    equilibrium : Equilibrium
        A converged equilibrium from :func:`find_equilibrium`.
    param, bounds, ds, ds_min, ds_max, max_points, direction
        As for :func:`continue_orbit` (arclength in the full state and the parameter).
    tol : float
        Corrector tolerance on ``max |f(y)|``.
    fd_step : float
        Relative step of the central difference df/dlambda (one-sided at the
        edge of the parameter's valid range, e.g. eta = 1 or 10).
    progress : bool, optional
        As for :func:`continue_orbit`.

    Returns
    -------
    Branch
        With ``period = 0``, ``T`` NaN, ``multipliers`` the eigenvalues
        (largest real part first), and bifurcations of kinds "fold" and "hopf".

    Raises
    ------
    ValueError
        For an unconverged equilibrium, an unknown ``param``, bounds that do
        not contain the start, or non-positive step sizes (naming the argument).
    """
    if not isinstance(equilibrium, Equilibrium) or not equilibrium.converged:
        raise ValueError("equilibrium must be a converged Equilibrium from find_equilibrium")
    system0 = equilibrium.system
    lam0, lo, hi = _check_args(system0, "equilibrium", param, bounds, ds, ds_min, ds_max, tol,
                               max_points)  # fmt: skip
    evaluate = _equilibrium_residual(system0, param, fd_step)
    x0 = np.r_[equilibrium.state, lam0]
    with points_bar(progress, max_points, f"continue_equilibrium {param}", [param]):
        xs, eigs, bifs, status = pseudo_arclength(
            evaluate, x0, direction, (lo, hi), ds=ds, ds_min=ds_min, ds_max=ds_max,
            max_points=max_points, tol=tol, tests=_equilibrium_tests,
            spectrum=_eigs_by_real_part, branch_points=True,
        )  # fmt: skip
    return Branch(
        system=system0,
        param=param,
        period=0,
        values=xs[:, -1].copy(),
        points=xs[:, :-1].copy(),
        T=np.full(len(xs), np.nan),
        multipliers=eigs,
        stable=np.all(eigs.real < 0.0, axis=1),
        bifurcations=[Bifurcation(k, v, i, x[:-1].copy()) for k, v, i, x in bifs],
        status=status,
    )


def _equilibrium_residual(system0, param: str, fd_step: float):
    """The corrector's function x = (y, lambda) -> (ok, f, [df/dy | df/dlambda], df/dy)."""
    nosc, dc = system0.n_oscillators, system0.is_dc_motor

    def system_at(lam):
        return dataclasses.replace(system0, **{param: float(lam)})

    def evaluate(x):
        y, lam = x[:-1], float(x[-1])
        try:
            s = system_at(lam)
        except ValueError:  # outside the parameter's valid range
            return False, None, None, None
        G = _field(s, y)
        J = dense_jacobian(y, s.to_array(), nosc, dc)
        dlam = _difference(lambda v: _field(system_at(v), y), lam,
                           fd_step * max(1.0, abs(lam)), G)  # fmt: skip
        if dlam is None or not (
            np.all(np.isfinite(G)) and np.all(np.isfinite(J)) and np.all(np.isfinite(dlam))
        ):
            return False, None, None, None
        return True, G, np.hstack([J, dlam[:, None]]), J

    return evaluate
