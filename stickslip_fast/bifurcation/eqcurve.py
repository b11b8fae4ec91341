"""Two-parameter curves of folds and Hopf points of the model's equilibria: the
:class:`System` side of :mod:`.hopfcurve` (:func:`~stickslip_fast.continue_bifurcation`
on a branch from :func:`~stickslip_fast.continue_equilibrium`)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..model.equations import dense_jacobian
from .curverecord import Codim2Point, Curve
from .hopfcurve import follow_equilibrium_fold, follow_hopf_curve
from .returnmap import _field
from .walk_args import _difference

#: The codim-1 kinds of equilibria that :func:`continue_equilibrium_curve` follows.
EQUILIBRIUM_CURVE_KINDS = ("fold", "hopf")


def equilibrium_evaluator(system0, param: str, param2: str, fd_step: float = 1e-7):
    """base(x) at x = (y, param, param2): (ok, f, [J | df/dparam | df/dparam2], J), J the
    analytic Jacobian, the parameter columns by central differences (relative step
    ``fd_step``; one-sided at the edge of a parameter's valid range)."""
    nosc, dc = system0.n_oscillators, system0.is_dc_motor

    def at(l1, l2):
        s = dataclasses.replace(system0, **{param: float(l1), param2: float(l2)})
        s.to_array()  # raises ValueError outside the valid range
        return s

    def base(x):
        y, l1, l2 = x[:-2], float(x[-2]), float(x[-1])
        try:
            s = at(l1, l2)
        except ValueError:
            return False, None, None, None
        f = _field(s, y)
        J = dense_jacobian(y, s.to_array(), nosc, dc)
        d1 = _difference(lambda v: _field(at(v, l2), y), l1, fd_step * max(1.0, abs(l1)), f)
        d2 = _difference(lambda v: _field(at(l1, v), y), l2, fd_step * max(1.0, abs(l2)), f)
        cols = (f, J, d1, d2)
        if any(c is None or not np.all(np.isfinite(c)) for c in cols):
            return False, None, None, None
        return True, f, np.column_stack([J, d1, d2]), J

    return base


def continue_equilibrium_curve(branch, bifurcation, param2: str, bounds: tuple[float, float],
                               system0, *, direction: float = 1.0, h: float = 1e-7,
                               fd_step: float = 1e-7, lyap_step: float = 1e-4,
                               **settings) -> Curve:  # fmt: skip
    """Follow a fold or Hopf point of an equilibrium branch in ``param2`` (checked by the
    caller, :func:`~stickslip_fast.continue_bifurcation`). ``settings``: ds, ds_min,
    ds_max, max_points, tol of :func:`.foldcurve.run_curve`."""
    base = equilibrium_evaluator(system0, branch.param, param2, fd_step)
    y0 = np.asarray(bifurcation.point, float)
    l12 = np.array([float(bifurcation.value), float(getattr(system0, param2))])
    n = y0.size
    if bifurcation.kind == "hopf":
        ok, _, _, J = base(np.r_[y0, l12])
        ev = np.linalg.eigvals(J) if ok else np.array([1j])
        cplx = ev[np.abs(ev.imag) > 0]
        omega = float(np.abs(cplx[np.argmin(np.abs(cplx.real))].imag)) if cplx.size else 1.0
        x0 = np.r_[y0, omega * omega, l12]
        xs, eigs, codim2, status, _ = follow_hopf_curve(
            base, x0, direction, bounds, h=h, lyap_step=lyap_step, **settings)  # fmt: skip
    else:
        x0 = np.r_[y0, l12]
        xs, eigs, codim2, status, _ = follow_equilibrium_fold(base, x0, direction, bounds, h=h,
                                                              **settings)  # fmt: skip
    if xs is None:
        xs, eigs = x0[None, :], np.full((1, n), np.nan, complex)
    kappa = xs[:, n] if bifurcation.kind == "hopf" else np.full(len(xs), np.nan)
    T = np.array([2 * math.pi / math.sqrt(k) if k > 0 else math.nan for k in kappa])
    return Curve(
        system=system0, param=branch.param, param2=param2, kind=bifurcation.kind, period=0,
        values=xs[:, -2:].copy(), points=xs[:, :n].copy(), T=T, multipliers=eigs,
        codim2=[Codim2Point(k, x[-2:].copy(), i, x[:n].copy()) for k, i, x in codim2],
        status=status,
    )  # fmt: skip
