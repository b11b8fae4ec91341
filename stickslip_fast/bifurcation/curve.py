"""Two-parameter continuation of a fold, period-doubling or Neimark-Sacker point of periodic
orbits (:mod:`.foldcurve`, :mod:`.nscurve`), or of a fold or Hopf point of equilibria
(:mod:`.eqcurve`): ``Curve``.

:func:`continue_bifurcation` starts from a bifurcation located on a one-parameter orbit
branch (:func:`~stickslip_fast.continue_orbit`) and follows it in a second
:class:`System` parameter, by the minimally augmented system of :mod:`.foldcurve` on the
return map (single shooting: the Jacobian and both parameter columns from the variational
equations and the parameter sensitivities, :func:`~stickslip_fast.bifurcation.returnmap.return_map`)."""

from __future__ import annotations

import dataclasses
import functools
import math
import os

import numpy as np

from ..base.blas import one_blas_thread
from ..base.journal import journal
from ..base.messages import plain
from ..base.threads import run_concurrently
from ..model.system import SWEEPABLE
from .branch import Bifurcation, Branch
from .corrector import _locate_change
from .curverecord import Codim2Point, Curve
from .detection import _sorted_eigs
from .eqcurve import EQUILIBRIUM_CURVE_KINDS, continue_equilibrium_curve
from .foldcurve import CURVE_KINDS, follow_curve
from .nscurve import NS_KIND, follow_ns_curve
from .progress import points_bar
from .returnmap import SECTION_INDEX, return_map
from .sbcurve import SB_KIND, follow_sb_curve
from .stickcurve import STICK_KIND, follow_stick_curve, nearest_stick_event
from .stickphases import GRAZE_TOL, section_graze_margin, stick_phases
from .synchrony import synchronous_point


class StickWatch:
    """Counts the stick phases of the orbit at every point of a fold, period-doubling or
    Neimark-Sacker curve, and locates where the count changes (:func:`.foldcurve.run_curve`'s ``watch``).

    Such a place is a codim-2 point "stick-phase": the curve meets a stick-phase event
    curve (:mod:`.stickcurve`), where the orbit's stick structure changes (the smoothed
    counterpart of a curve leaving its smooth regime). ``count_at(x)`` gives the count at
    a point of the curve; ``found`` collects (kind, index, x): x is the first point past
    the change, located on the curve by bisection to ``locate_tol`` in param2.
    """

    def __init__(self, count_at, tol: float, locate_tol: float = 1e-8):
        self.count_at, self.tol, self.locate_tol = count_at, tol, locate_tol
        self.found: list = []
        self.evaluate, self.prev = None, None

    def _count(self, x):
        try:
            return int(self.count_at(x))
        except ValueError:  # the orbit could not be sampled there
            return -1

    def start(self, evaluate, x_start):
        self.evaluate, self.prev = evaluate, (x_start.copy(), self._count(x_start))

    def __call__(self, x, walk):
        count = self._count(x)
        x_prev, c_prev = self.prev
        if count >= 0 and c_prev >= 0 and count != c_prev:
            loc = _locate_change(self.evaluate, x_prev, x, c_prev, self.count_at, self.tol,
                                 self.locate_tol)  # fmt: skip
            self.found.append(("stick-phase", len(walk.xs) - 2, loc))
        self.prev = (x.copy(), count)


def _system_at(system0, param, param2, x):
    """``system0`` at a curve point x = (..., param, param2)."""
    return dataclasses.replace(system0, **{param: float(x[-2]), param2: float(x[-1])})


def _two_param_evaluator(system0, param, param2, p, rtol, atol, fd_step):
    """base(x) of :func:`follow_curve` at x = (section coordinates, param, param2)."""
    n = system0.n_state
    mask = np.arange(n) != SECTION_INDEX
    periods: dict[bytes, float] = {}

    def base(x):
        try:
            s = _system_at(system0, param, param2, x)
            s.to_array()
        except ValueError:
            return False, None, None, None
        z = np.zeros(n)
        z[mask] = x[:-2]
        # the map with each parameter's sensitivity: two independent integrations, side by side
        maps = run_concurrently([
            functools.partial(return_map, s, z, p, rtol=rtol, atol=atol, param=name,
                              param_step=fd_step)
            for name in (param, param2)
        ])  # fmt: skip
        if any(m[0] != "ok" for m in maps):
            return False, None, None, None
        cols = [m[3][:, -1:] for m in maps]
        _, pts, times, jac = maps[-1]
        A = jac[:, :-1]
        periods[x.tobytes()] = float(times[-1])
        DG = np.hstack([A - np.eye(n - 1), *cols])
        return True, pts[-1][mask] - x[:-2], DG, A

    return base, periods


#: :func:`continue_bifurcation`'s docstring (kept out of the function body, as for
#: :func:`~stickslip_fast.continue_orbit`: the layout rule counts a function's lines).
_CONTINUE_BIFURCATION_DOC = """Follow a fold, period-doubling, Neimark-Sacker or symmetry-breaking
point of periodic orbits, or a fold or Hopf point of equilibria, in a second parameter.

A minimally augmented system whose borders are taken again where the null vectors
have turned by 60 degrees (docs/orbits.md, "Borders along long curves").

Parameters
----------
branch : Branch
    An orbit branch from :func:`~stickslip_fast.continue_orbit`, or an equilibrium
    branch from :func:`~stickslip_fast.continue_equilibrium` (``period == 0``).
bifurcation : Bifurcation
    One of ``branch.bifurcations``, of kind "fold", "period-doubling",
    "neimark-sacker" (orbits; :mod:`~stickslip_fast.bifurcation.nscurve`: the angle
    theta of the multipliers e^{+-i theta} is an unknown, ``Curve.theta``),
    "symmetry-breaking" (in-phase orbits of disks on one DC motor:
    :mod:`~stickslip_fast.bifurcation.sbcurve`) or "stick-phase" (orbits); "fold"
    or "hopf" (equilibria).
param2 : str
    A :class:`System` field other than ``branch.param``.
bounds2 : (float, float)
    The interval of ``param2``; it must contain the branch's value. The curve
    ends on the first bound it reaches (status "bounds").
direction : float
    +1: start towards increasing ``param2``; -1: decreasing.
ds, ds_min, ds_max, max_points, tol : float
    Of the pseudo-arclength continuation in (section coordinates, param, param2)
    (equilibria: (state, param, param2), and omega^2 before the parameters on a
    Hopf curve); ``tol`` on the residual and the test functions together.
rtol, atol, fd_step : float
    Of the return map and its parameter sensitivities (:func:`continue_orbit`);
    equilibria: ``fd_step`` of the central differences in the parameters.
h : float
    Step of the directional difference of the Jacobian (the test functions'
    gradients; docs/orbits.md, "Two-parameter curves").
lyap_step : float, optional
    Equilibria, Hopf curves: step of the differences of the Jacobian in the
    state for the first Lyapunov coefficient (the "bautin" test). Default
    0.01 ``eps``: the friction law varies on the scale eps (at the DC motor's
    Hopf point l1 = 1.2464e8 with steps 1e-6 to 1e-8, 1.8e9 with 1e-4).
stick_events : bool
    Orbit fold, period-doubling and NS curves: name a codim-2 point "stick-phase"
    where the orbit's count of stick phases changes (located to 1e-8 in ``param2``).
progress : bool, optional
    Show a progress bar of the points, with both parameters' values (default: when
    standard error is a terminal).

Returns
-------
Curve

Raises
------
ValueError
    For a bifurcation of another kind, an unknown or equal ``param2``, or bounds
    without the start (naming the argument).
"""


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
    lyap_step: float | None = None,
    stick_events: bool = True,
    progress: bool | None = None,
    checkpoint: str | os.PathLike | None = None,
) -> Curve:
    kind, system0, lo, hi = _check(branch, bifurcation, param2, bounds2)
    settings = dict(ds=ds, ds_min=ds_min, ds_max=ds_max, max_points=max_points, tol=tol)
    names = [branch.param, param2]
    arguments = dict(branch=branch, bifurcation=bifurcation, param2=param2, bounds2=(lo, hi),
                     direction=direction, rtol=rtol, atol=atol, fd_step=fd_step, h=h,
                     lyap_step=lyap_step, stick_events=stick_events, **settings)  # fmt: skip
    with (journal(checkpoint, "continue_bifurcation", arguments),
          points_bar(progress, max_points, f"continue_bifurcation {kind}", names)):  # fmt: skip
        if branch.period == 0:
            return continue_equilibrium_curve(branch, bifurcation, param2, (lo, hi), system0,
                                              direction=direction, h=h, fd_step=fd_step,
                                              lyap_step=lyap_step or 0.01 * system0.eps,
                                              **settings)  # fmt: skip
        return _orbit_curve(branch, bifurcation, param2, (lo, hi), system0, direction,
                            (rtol, atol, fd_step, h), settings, stick_events)  # fmt: skip


continue_bifurcation.__doc__ = _CONTINUE_BIFURCATION_DOC


@one_blas_thread()  # its return maps run on threads (base/threads.py): BLAS must not spin
def _orbit_curve(branch, bifurcation, param2, bounds2, system0, direction, steps, settings,
                 stick_events):  # fmt: skip
    """:func:`continue_bifurcation` for an orbit branch (arguments checked)."""
    rtol, atol, fd_step, h = steps
    kind, p, n = bifurcation.kind, branch.period, system0.n_state
    base, periods = _two_param_evaluator(system0, branch.param, param2, p, rtol, atol, fd_step)
    mask = np.arange(n) != SECTION_INDEX
    x0 = np.r_[bifurcation.point[mask], bifurcation.value, getattr(system0, param2)]

    def full(x):
        z = np.zeros(n)
        z[mask] = x[:-2]
        return z

    system_at = functools.partial(_system_at, system0, branch.param, param2)
    extra, watch = {}, None
    if stick_events and kind != STICK_KIND:
        count_at = _stick_counter(system_at, p, full, periods, rtol, atol)
        if kind == NS_KIND:  # x = (z, theta, l1, l2): theta apart
            count_at = functools.partial(_without_theta, count_at, n - 1)
        watch = StickWatch(count_at, settings["tol"])
    if kind == NS_KIND:
        xs, mults, codim2, status = follow_ns_curve(base, x0, direction, bounds2, h=h,
                                                    watch=watch, **settings)  # fmt: skip
        extra["theta"] = np.full(1, np.nan)
        if xs is not None:  # x = (z, theta, l1, l2): theta apart
            extra["theta"] = xs[:, n - 1].copy()
            xs = np.delete(xs, n - 1, axis=1)
            codim2 = [(k, i, np.delete(x, n - 1)) for k, i, x in codim2]
    elif kind == SB_KIND:
        xs, mults, codim2, status = follow_sb_curve(base, system_at, full, x0, direction,
                                                    bounds2, h=h, watch=watch,
                                                    periods=periods, **settings)  # fmt: skip
    elif kind == STICK_KIND:
        xs, mults, codim2, status, extra = _stick(branch, bifurcation, param2, system0, x0,
                                                  base, full, direction, bounds2,
                                                  (rtol, atol, fd_step), settings)  # fmt: skip
    else:
        xs, mults, codim2, status, _ = follow_curve(base, x0, kind, direction, bounds2, h=h,
                                                    spectrum=_sorted_eigs, watch=watch,
                                                    **settings)  # fmt: skip
    if xs is None:
        xs, mults = x0[None, :], np.full((1, n - 1), np.nan, complex)
    T = np.array([periods.get(x.tobytes(), math.nan) for x in xs])
    if status in ("step-too-small", "precision-limit") and math.isfinite(T[-1]):
        # a curve can stop where its orbit grazes the section: the return map is not
        # smooth there (a crossing appears or vanishes), so the curve ends
        if section_graze_margin(system_at(xs[-1]), full(xs[-1]), float(T[-1])) < GRAZE_TOL:
            codim2 = [*codim2, ("section-grazing", len(xs) - 1, xs[-1].copy())]
    return Curve(
        system=system0, param=branch.param, param2=param2, kind=kind, period=p,
        values=xs[:, -2:].copy(), points=np.array([full(x) for x in xs]), T=T,
        multipliers=mults,
        codim2=[Codim2Point(k, x[-2:].copy(), i, full(x)) for k, i, x in codim2],
        status=status, **extra,
    )  # fmt: skip


def _without_theta(count_at, i, x):
    """``count_at`` at a Neimark-Sacker curve point x with its angle theta (x[i]) left out."""
    return count_at(np.delete(x, i))


def _stick_counter(system_at, period, full, periods, rtol, atol):
    """count_at(x): the stick phases of the orbit at a curve point x = (z, param, param2)."""

    def count_at(x):
        s = system_at(x)
        T = periods.get(x.tobytes(), math.nan)
        if not math.isfinite(T):
            st, _, times, _ = return_map(s, full(x), period, rtol=rtol, atol=atol,
                                         tangents=False)  # fmt: skip
            if st != "ok":
                raise ValueError(f"no return to the section: {st}")
            T = float(times[-1])
        return stick_phases(s, full(x), T).size

    return count_at


def _stick(branch, bifurcation, param2, system0, x0, base, full, direction, bounds2, steps,
           settings):  # fmt: skip
    """The stick-phase event curve (:mod:`.stickcurve`) through the branch's event: the
    slip-speed extremum of the orbit at the event nearest the stick threshold, followed."""
    rtol, atol, fd_step = steps
    st, _, times, _ = return_map(system0, bifurcation.point, branch.period, rtol=rtol,
                                 atol=atol, tangents=False)  # fmt: skip
    if st != "ok":
        return None, None, [], "start-failed", {"event_time": np.full(1, np.nan)}
    T0 = float(times[-1])
    event = nearest_stick_event(system0, bifurcation.point, T0, rtol=rtol, atol=atol)
    info = {"disk": event.disk, "extremum": event.extremum, "threshold": event.threshold}

    system_at = functools.partial(_system_at, system0, branch.param, param2)
    xs, mults, codim2, status, t_star = follow_stick_curve(
        base, system_at, full, x0, event, direction, bounds2, width=0.01 * T0,
        fd_step=max(fd_step, 1e-6), rtol=rtol, atol=atol, **settings,
    )  # fmt: skip
    t_star = np.full(1, np.nan) if t_star is None else t_star
    return xs, mults, codim2, status, {"event": info, "event_time": t_star}


def _check(branch, bifurcation, param2, bounds2):
    if not isinstance(branch, Branch) or branch.period < 0:
        raise ValueError("branch must be a Branch from continue_orbit or continue_equilibrium")
    kinds = (
        sorted([*CURVE_KINDS, NS_KIND, STICK_KIND, SB_KIND])
        if branch.period
        else list(EQUILIBRIUM_CURVE_KINDS)
    )
    if not isinstance(bifurcation, Bifurcation) or bifurcation.kind not in kinds:
        what = "an orbit" if branch.period else "an equilibrium"
        raise ValueError(f"bifurcation must be a Bifurcation of kind {kinds} ({what} branch), "
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
    if bifurcation.kind == SB_KIND and not synchronous_point(system0, bifurcation.point):
        raise ValueError("bifurcation: a symmetry-breaking point must lie on in-phase orbits")
    return bifurcation.kind, system0, lo, hi
