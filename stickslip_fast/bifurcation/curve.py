"""Two-parameter continuation of a fold or period-doubling of periodic orbits: ``Curve``.

:func:`continue_bifurcation` starts from a bifurcation located on a one-parameter orbit
branch (:func:`~stickslip_fast.continue_orbit`) and follows it in a second
:class:`System` parameter, by the minimally augmented system of :mod:`.foldcurve` on the
return map (single shooting: the Jacobian and both parameter columns from the variational
equations and the parameter sensitivities, :func:`~stickslip_fast.bifurcation.returnmap.return_map`)."""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..base.messages import plain
from ..model.system import SWEEPABLE
from .branch import Bifurcation, Branch
from .detection import _sorted_eigs
from .foldcurve import CURVE_KINDS, follow_curve
from .returnmap import SECTION_INDEX, return_map


@dataclass
class Codim2Point:
    """A codim-2 point on a :class:`Curve`: ``kind`` ("cusp" or "extremum"), ``values``
    (the branch's parameter, ``param2``), ``index`` (the curve point before it) and
    ``point`` (the orbit's state on the section there)."""

    kind: str
    values: np.ndarray
    index: int
    point: np.ndarray


@dataclass
class Curve:
    """A curve of codim-1 points of periodic orbits in two parameters.

    Attributes
    ----------
    system : System
        The system of the start (at the start's values of both parameters).
    param, param2 : str
        The branch's parameter and the second one.
    kind : str
        The codim-1 kind followed: "fold" or "period-doubling".
    period : int
        Section crossings per period of the orbits.
    values : ndarray, shape (k, 2)
        (param, param2) along the curve.
    points : ndarray, shape (k, n_state)
        The orbit's state on the section at each point.
    T : ndarray, shape (k,)
        Period in time.
    multipliers : ndarray of complex, shape (k, n_state - 1)
        Floquet multipliers (one is +1 on a fold curve, -1 on a period-doubling curve).
    codim2 : list of Codim2Point
        "cusp": the curve's parameter-plane tangent vanishes; "extremum": the curve
        turns back in ``param2`` (beyond it, at fixed ``param2``, the two folds met
        and vanished).
    status : str
        How the curve ended (:func:`~stickslip_fast.bifurcation.arclength.pseudo_arclength`'s
        statuses, or "start-failed").
    """

    system: Any
    param: str
    param2: str
    kind: str
    period: int
    values: np.ndarray
    points: np.ndarray
    T: np.ndarray
    multipliers: np.ndarray
    codim2: list[Codim2Point] = field(default_factory=list)
    status: str = ""

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the curve (schema: docs/file-format.md, "Curve files")."""
        from ..io.curvefile import write_curve

        return write_curve(path, {
            "param": self.param, "param2": self.param2, "curve_kind": self.kind,
            "period": int(self.period), "status": self.status,
            "system": json.dumps(self.system.to_dict()), "values": self.values,
            "points": self.points, "T": self.T, "multipliers_real": self.multipliers.real,
            "multipliers_imag": self.multipliers.imag,
            "codim2_kind": [c.kind for c in self.codim2],
            "codim2_values": [c.values for c in self.codim2],
            "codim2_index": [c.index for c in self.codim2],
            "codim2_point": [c.point for c in self.codim2],
        })  # fmt: skip

    @classmethod
    def from_hdf5(cls, path: str | Path) -> Curve:
        """Read a curve file written by :meth:`to_hdf5` (ValueError for another file)."""
        from ..io.curvefile import read_curve
        from ..model.system import System

        d = read_curve(path)
        codim2 = [Codim2Point(k, np.array(v), int(i), np.array(p)) for k, v, i, p in
                  zip(d["codim2_kind"], d["codim2_values"], d["codim2_index"], d["codim2_point"])]  # fmt: skip
        return cls(
            system=System.from_dict(json.loads(d["system"])), param=str(d["param"]),
            param2=str(d["param2"]), kind=str(d["curve_kind"]), period=int(d["period"]),
            values=d["values"], points=d["points"], T=d["T"],
            multipliers=d["multipliers_real"] + 1j * d["multipliers_imag"], codim2=codim2,
            status=str(d["status"]),
        )  # fmt: skip


def _two_param_evaluator(system0, param, param2, p, rtol, atol, fd_step):
    """base(x) of :func:`follow_curve` at x = (section coordinates, param, param2)."""
    n = system0.n_state
    mask = np.arange(n) != SECTION_INDEX
    periods: dict[bytes, float] = {}

    def base(x):
        try:
            s = dataclasses.replace(system0, **{param: float(x[-2]), param2: float(x[-1])})
            s.to_array()
        except ValueError:
            return False, None, None, None
        z = np.zeros(n)
        z[mask] = x[:-2]
        cols = []
        for name in (param, param2):
            st, pts, times, jac = return_map(s, z, p, rtol=rtol, atol=atol, param=name,
                                             param_step=fd_step)  # fmt: skip
            if st != "ok":
                return False, None, None, None
            cols.append(jac[:, -1:])
        A = jac[:, :-1]
        periods[x.tobytes()] = float(times[-1])
        DG = np.hstack([A - np.eye(n - 1), *cols])
        return True, pts[-1][mask] - x[:-2], DG, A

    return base, periods


def continue_bifurcation(
    branch: Branch,
    bifurcation: Bifurcation,
    param2: str,
    bounds2: tuple[float, float],
    *,
    direction: float = 1.0,
    ds: float = 0.01,
    ds_min: float = 1e-9,
    ds_max: float = 0.05,
    max_points: int = 200,
    tol: float = 1e-10,
    rtol: float = 1e-11,
    atol: float = 1e-13,
    fd_step: float = 1e-7,
    h: float = 1e-7,
) -> Curve:
    """Follow a fold or period-doubling of periodic orbits in a second parameter.

    Parameters
    ----------
    branch : Branch
        An orbit branch from :func:`~stickslip_fast.continue_orbit`.
    bifurcation : Bifurcation
        One of ``branch.bifurcations``, of kind "fold" or "period-doubling".
    param2 : str
        A :class:`System` field other than ``branch.param``.
    bounds2 : (float, float)
        The interval of ``param2``; it must contain the branch's value. The curve
        ends on the first bound it reaches (status "bounds").
    direction : float
        +1: start towards increasing ``param2``; -1: decreasing.
    ds, ds_min, ds_max, max_points, tol : float
        Of the pseudo-arclength continuation in (section coordinates, param,
        param2); ``tol`` on the residual and the test function together.
    rtol, atol, fd_step : float
        Of the return map and its parameter sensitivities (:func:`continue_orbit`).
    h : float
        Step of the directional difference of the Jacobian (the test function's
        gradient; docs/orbits.md, "Two-parameter curves").

    Returns
    -------
    Curve

    Raises
    ------
    ValueError
        For a branch of equilibria, a bifurcation of another kind or not on the
        branch, an unknown or equal ``param2``, or bounds that do not contain the
        start (naming the argument).
    """
    kind, system0, lo, hi = _check(branch, bifurcation, param2, bounds2)
    p = branch.period
    base, periods = _two_param_evaluator(system0, branch.param, param2, p, rtol, atol, fd_step)
    mask = np.arange(system0.n_state) != SECTION_INDEX
    x0 = np.r_[bifurcation.point[mask], bifurcation.value, getattr(system0, param2)]
    xs, mults, codim2, status, _ = follow_curve(
        base, x0, kind, direction, (lo, hi), ds=ds, ds_min=ds_min, ds_max=ds_max,
        max_points=max_points, tol=tol, h=h, spectrum=_sorted_eigs,
    )  # fmt: skip
    n = system0.n_state
    if xs is None:
        xs, mults = x0[None, :], np.full((1, n - 1), np.nan, complex)

    def full(x):
        z = np.zeros(n)
        z[mask] = x[:-2]
        return z

    T = np.array([periods.get(x.tobytes(), math.nan) for x in xs])
    return Curve(
        system=system0, param=branch.param, param2=param2, kind=kind, period=p,
        values=xs[:, -2:].copy(), points=np.array([full(x) for x in xs]), T=T,
        multipliers=mults,
        codim2=[Codim2Point(k, x[-2:].copy(), i, full(x)) for k, i, x in codim2],
        status=status,
    )  # fmt: skip


def _check(branch, bifurcation, param2, bounds2):
    if not isinstance(branch, Branch) or branch.period < 1:
        raise ValueError("branch must be an orbit Branch from continue_orbit (period >= 1)")
    if not isinstance(bifurcation, Bifurcation) or bifurcation.kind not in CURVE_KINDS:
        raise ValueError(f"bifurcation must be a Bifurcation of kind {sorted(CURVE_KINDS)}, "
                         f"got {getattr(bifurcation, 'kind', bifurcation)!r}")  # fmt: skip
    if param2 not in SWEEPABLE or param2 in (branch.param, "n_oscillators"):
        raise ValueError(f"param2 must be one of {sorted(SWEEPABLE)} other than "
                         f"{branch.param!r}, got {param2!r}")  # fmt: skip
    try:
        lo, hi = (float(v) for v in bounds2)
    except (TypeError, ValueError):
        raise ValueError(f"bounds2 must be two numbers (lo, hi), got {plain(bounds2)}") from None
    system0 = dataclasses.replace(branch.system, **{branch.param: float(bifurcation.value)})
    v2 = float(getattr(system0, param2))
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= v2 <= hi):
        raise ValueError(f"bounds2 {plain(bounds2)} must contain {param2} = {v2}")
    return bifurcation.kind, system0, lo, hi
