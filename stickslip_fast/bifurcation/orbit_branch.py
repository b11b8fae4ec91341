"""Continuation of periodic orbits: fixed points of the Poincare map P^p(., lambda)."""

from __future__ import annotations

import dataclasses
import math
import os
from typing import Any

import numpy as np

from ..base.journal import journal
from .arclength import pseudo_arclength
from .branch import Bifurcation, Branch
from .corrector import _locate_change
from .multishoot import DEFAULT_SEGMENTS, MAX_SEGMENTS, MESH_LIMIT
from .multishoot_branch import append_branch, continue_multiple, ms_start
from .orbit_record import branch_point_marks, multipliers_stable
from .orbits import (
    EQUILIBRIUM_SPEED,
    SECTION_INDEX,
    Orbit,
    _field,
    check_shooting,
    return_map,
    stick_phases,
)
from .progress import points_bar
from .synchrony import in_phase_walk
from .walk_args import (
    MS_TOL_FLOOR,
    SHARP_END_STAGES,
    WalkSettings,
    _check_args,
    _walk_defaults,
)


# ------------------------------------------------------------------ orbits
def _orbit_evaluator(
    system0,
    param: str,
    p: int,
    rtol: float,
    atol: float,
    fd_step: float,
    periods: dict[bytes, float] | None = None,
):
    """The residual G(z, lambda) = P^p(z) - z of an orbit branch, and its helpers.

    Returns ``(evaluate, full, system_at, periods)``: ``evaluate(x)`` for
    :func:`pseudo_arclength` (x = section coordinates and lambda; the map's
    Jacobian in z and its derivative in lambda from the variational equations
    and the parameter sensitivity, integrated together), ``full(x)`` the state
    on the section, ``system_at(lam)`` and
    ``periods`` (the return time of every evaluated x, keyed by its bytes; pass
    a dict to share it between evaluators of different tolerances).
    """
    n = system0.n_state
    mask = np.arange(n) != SECTION_INDEX
    kw = dict(rtol=rtol, atol=atol)

    def full(x):
        z = np.zeros(n)
        z[mask] = x[:-1]
        return z

    def system_at(lam):
        return dataclasses.replace(system0, **{param: float(lam)})

    cache: dict[bytes, Any] = {}
    if periods is None:
        periods = {}

    def evaluate(x):
        key = x.tobytes()
        if key in cache:
            return cache[key]
        lam = float(x[-1])
        try:
            s = system_at(lam)
        except ValueError:  # outside the parameter's valid range
            return False, None, None, None
        z = full(x)
        # [D_z P^p, dP^p/dlambda] in one integration: the tangents and the parameter
        # sensitivity together (a central difference of the map would take two more)
        st, pts, times, jac_full = return_map(s, z, p, param=param, param_step=fd_step, **kw)
        if st != "ok":
            return False, None, None, None
        jac = jac_full[:, :-1]
        G = pts[-1][mask] - x[:-1]
        DG = jac_full.copy()
        DG[:, :-1] -= np.eye(n - 1)
        out = (True, G, DG, jac)
        periods[key] = float(times[-1])
        cache.clear()
        cache[key] = out
        return out

    return evaluate, full, system_at, periods


#: :func:`continue_orbit`'s docstring (kept out of the function body, as for
#: :func:`~stickslip_fast.analysis.census.census`: the layout rule counts a
#: function's lines, and its parameters take more lines than its code).
_CONTINUE_ORBIT_DOC = """Continue a periodic orbit in one parameter (pseudo-arclength).

Parameters
----------
orbit : Orbit
    A converged orbit from :func:`find_orbit`.
param : str
    A :class:`System` field (one of ``SWEEPABLE``), e.g. "eta".
bounds : (float, float)
    The parameter interval; it must contain the orbit's value.
ds, ds_min, ds_max : float
    First, smallest and largest step in arclength (section coordinates and
    the parameter together). ``ds`` defaults to 0.01; from an orbit that
    :func:`~stickslip_fast.switch_branch` found at a branch point in ``param``
    (``orbit.origin``), to ``walk_args.BRANCH_POINT_DS`` (1e-3): a larger one can
    land back on the branch it left.
max_points : int
    Most branch points.
direction : float, optional
    +1: towards increasing ``param``; -1: decreasing. Default: +1, or away from
    ``orbit.origin`` (:func:`~stickslip_fast.switch_branch`) in its parameter.
tol : float
    Corrector tolerance on ``max |P^p(z) - z|``.
rtol, atol : float
    Integration tolerances of the return map.
fd_step : float
    Relative step of the central difference of the vector field and its
    Jacobian in the parameter, which drives the parameter sensitivity that
    gives dP/dlambda (one-sided at the edge of the parameter's valid range;
    see :func:`~stickslip_fast.bifurcation.returnmap.return_map`).
stick_events : bool
    Record the stick phases of every point (``Branch.stick_count``,
    ``stick_time``; :func:`~stickslip_fast.bifurcation.stickphases.stick_phases`) and locate
    every change of their number between two points (bisection on the
    branch to 1e-8 in the parameter) as a "stick-phase" bifurcation.
sharp_ends : bool
    Where the corrector fails at ``ds_min``, go on with the tighter
    settings of :data:`SHARP_END_STAGES` in turn (corrector tolerance, integration
    tolerances, smallest step; each only where tighter than the ones given), from the
    last point corrected again with them. This passes folds narrower than the
    defaults resolve, e.g. both ends of Fig. 6's period-1 branch (docs/limits.md).
    The branch keeps the tighter settings from there on; ``T`` and the points are
    those of the stage that computed them.
shooting : {"single", "multiple", "auto"}
    "single": fixed points of the return map. "multiple": the orbit as ``segments``
    segments (:mod:`.multishoot`; the arclength measures the segment starts, T over the
    power of two nearest the first period, and the parameter, docs/orbits.md; in-phase
    orbits stay in phase and get their symmetry-breaking points too). "auto": single,
    and where it ends with "step-too-small" or "precision-limit", multiple shooting
    from its last point on (same direction in the parameter, the tightest stage's
    tolerances), appended to the branch (``status`` names both ends).
segments : int
    m >= 1, the segments of multiple shooting (even cuts in time). An orbit
    found by multiple shooting starts on its own segments (``Orbit.segments``)
    instead: its mesh, and its segment starts as the first guess.
remesh : bool
    Multiple shooting only: cut the segments again along the branch wherever
    one amplifies by more than ``multishoot.REMESH_LIMIT`` (merge neighbours that
    amplify little, bisect those above ``MESH_LIMIT``, up to ``max_segments``;
    :func:`~stickslip_fast.bifurcation.multishoot.remesh`), re-sampling the
    current orbit on the new mesh. Without it the mesh is fixed at the start,
    and the branch ends where its segment through the sharpest passage reaches
    the precision limit (docs/orbits.md). Where a re-sampled point cannot be
    corrected on its new mesh, the branch goes on on the old one.
    ``shooting="auto"`` gives multiple shooting a corrector tolerance of at
    least :data:`MS_TOL_FLOOR` (its residual carries the segments'
    integration error).
max_segments : int
    Multiple shooting only: the most segments a mesh gets, at the start (where a
    segment amplifies by more than ``MESH_LIMIT``) and in each re-mesh; an integer
    >= ``segments``. The far ends of re-meshed branches stop at the cap (μ ~
    1e36-1e48 at the default 64; 256 reached μ = 6.2e178 at ~4x the cost per point).
    ``max_segments=segments`` (even cuts only) keeps single shooting's pace on long
    walks of moderate multipliers; refined cuts locate bifurcations more precisely.
progress : bool, optional
    Show a progress bar of the points, with the parameter's value (default:
    when standard error is a terminal).
checkpoint : str or os.PathLike, optional
    A file that records the branch's integrations as they are made
    (:mod:`~stickslip_fast.base.journal`). Run the same call with the same file after
    a kill or Ctrl-C, and it replays what was done in seconds and goes on: the
    branch is bit-identical to one never interrupted. A file written for other
    arguments or other code is an error naming what differs. Once done, the file
    answers the same call again at once; delete it when the branch is saved.

Returns
-------
Branch
    Its ``status`` says how it ended; "nonsmooth" (with a "section-grazing" point
    last) where the return time of the next point would jump by more than 5 %: a
    crossing of the section appears or vanishes, and a branch never joins two
    families of fixed points of P^p.

Raises
------
ValueError
    For an unconverged orbit, an unknown ``param``, bounds that do not
    contain the start, or non-positive step sizes (naming the argument).
"""


def continue_orbit(
    orbit: Orbit,
    param: str,
    bounds: tuple[float, float],
    *,
    ds: float | None = None,
    ds_min: float = 1e-8,
    ds_max: float = 0.05,
    max_points: int = 200,
    direction: float | None = None,
    tol: float = 1e-10,
    rtol: float = 1e-11,
    atol: float = 1e-13,
    fd_step: float = 1e-7,
    stick_events: bool = True,
    sharp_ends: bool = True,
    shooting: str = "single",
    segments: int = DEFAULT_SEGMENTS,
    remesh: bool = False,
    max_segments: int = MAX_SEGMENTS,
    progress: bool | None = None,
    checkpoint: str | os.PathLike | None = None,
) -> Branch:
    if not isinstance(orbit, Orbit) or not orbit.converged:
        raise ValueError("orbit must be a converged Orbit from find_orbit")
    ds, direction = _walk_defaults(orbit, param, ds, direction)
    lam0, lo, hi = _check_args(orbit.system, "orbit", param, bounds, ds, ds_min, ds_max, tol,
                               max_points)  # fmt: skip
    check_shooting(shooting, segments, max_segments)
    if remesh and shooting == "single":
        raise ValueError("remesh needs shooting='multiple' or 'auto', got shooting='single'")
    walk = WalkSettings(ds=ds, ds_min=ds_min, ds_max=ds_max, max_points=max_points, tol=tol,
                        rtol=rtol, atol=atol, fd_step=fd_step, stick_events=stick_events,
                        sharp_ends=sharp_ends)  # fmt: skip
    mesh_args = (int(segments), bool(remesh), int(max_segments))
    arguments = dict(orbit=orbit, param=param, bounds=(lo, hi), direction=direction,
                     shooting=shooting, segments=segments, remesh=remesh,
                     max_segments=max_segments, **dataclasses.asdict(walk))  # fmt: skip
    with (journal(checkpoint, "continue_orbit", arguments),
          points_bar(progress, max_points, f"continue_orbit {param}", [param])):  # fmt: skip
        if shooting == "multiple":
            return _continue_multiple_from(orbit, param, (lo, hi), direction, mesh_args, walk)
        branch, way_on = _continue_single(orbit, param, lam0, lo, hi, direction, walk)
        if shooting == "auto" and branch.status in ("step-too-small", "precision-limit"):
            branch = _go_on_multiple(branch, orbit, (lo, hi), mesh_args, walk, way_on)
    return branch


continue_orbit.__doc__ = _CONTINUE_ORBIT_DOC


def _continue_multiple_from(
    orbit: Orbit,
    param: str,
    bounds: tuple[float, float],
    direction: float,
    mesh_args: tuple[int, bool, int],
    walk: WalkSettings,
) -> Branch:
    """continue_orbit with shooting="multiple": the orbit corrected by multiple shooting
    (``segments`` even cuts, or the orbit's own segments if it was found by multiple
    shooting; refined by :data:`MESH_LIMIT`), then continued. ``mesh_args``:
    (segments, remesh, max_segments) of :func:`continue_orbit`."""
    segments, remesh, max_segments = mesh_args
    x0, mesh = ms_start(orbit.system, orbit.points[0], orbit.T, param, segments, walk.rtol,
                        walk.atol, walk.fd_step, walk.tol, MESH_LIMIT, known=orbit.segments,
                        max_segments=max_segments)  # fmt: skip
    if x0 is None:
        raise ValueError("orbit could not be corrected by multiple shooting")
    return continue_multiple(orbit.system, param, orbit.period, x0, direction, bounds, walk,
                             segments=mesh, stages=SHARP_END_STAGES, remesh=remesh,
                             max_segments=max_segments)  # fmt: skip


def _stick_events(xs, T, system_at, full, evaluate, periods, tol, bifs):
    """Stick phases of every branch point, and their changes located (appended to bifs)."""
    stick_count = np.full(len(xs), -1, dtype=np.int64)
    stick_time = np.full(len(xs), np.nan)

    def geometry(x, T_x):
        d = stick_phases(system_at(x[-1]), full(x), T_x)
        return d.size, float(d.sum())

    for i, x in enumerate(xs):
        if math.isfinite(T[i]):
            try:
                stick_count[i], stick_time[i] = geometry(x, T[i])
            except ValueError:  # the orbit could not be sampled: left as not computed
                pass
    for i in range(len(xs) - 1):
        a, b = stick_count[i], stick_count[i + 1]
        if a >= 0 and b >= 0 and a != b:
            loc = _locate_change(
                evaluate, xs[i], xs[i + 1], a,
                lambda x: geometry(x, periods.get(x.tobytes(), math.nan))[0], tol, 1e-8,
            )  # fmt: skip
            bifs.append(("stick-phase", float(loc[-1]), i, loc))
    return stick_count, stick_time


def _go_on_multiple(
    branch: Branch,
    orbit: Orbit,
    bounds,
    mesh_args: tuple[int, bool, int],
    walk: WalkSettings,
    way_on=None,
) -> Branch:
    """``branch`` continued by multiple shooting from its last point (shooting="auto"),
    along ``way_on`` (the single-shooting walk's last tangent) or against it.
    ``mesh_args``: (segments, remesh, max_segments) of :func:`continue_orbit`."""
    segments, remesh, max_segments = mesh_args
    if branch.values.size < 2 or walk.max_points - branch.values.size < 2:
        return branch
    # the tightest tolerances the single-shooting branch used (the last sharp-end stage)
    tol, rtol, atol, ds_min = walk.tol, walk.rtol, walk.atol, walk.ds_min
    if walk.sharp_ends:
        for stage in SHARP_END_STAGES:
            tol, rtol, atol, ds_min = (min(a, b) for a, b in zip((tol, rtol, atol, ds_min), stage))
    # not below the segments' integration noise (docs/orbits.md, "Multiple shooting")
    tol = max(tol, MS_TOL_FLOOR)
    param = branch.param
    lam = float(branch.values[-1])
    system = dataclasses.replace(orbit.system, **{param: lam})
    x0, mesh = ms_start(system, branch.points[-1], float(branch.T[-1]), param, segments, rtol,
                        atol, walk.fd_step, tol, MESH_LIMIT,
                        max_segments=max_segments)  # fmt: skip
    if x0 is None:
        return branch
    direction = float(np.sign(branch.values[-1] - branch.values[-2]) or 1.0)
    walk2 = dataclasses.replace(
        walk, tol=tol, rtol=rtol, atol=atol, ds=min(max(walk.ds_min, ds_min * 100), walk.ds_max),
        ds_min=ds_min, max_points=walk.max_points - branch.values.size + 1,
    )  # fmt: skip
    way_on = way_on or (np.zeros(branch.points.shape[1]), direction)
    # A probe of a few points first: where single shooting stopped in a crawl at a fold,
    # its last tangent can point back along the branch it came by (k12 = -0.8316, eta =
    # 2.5706); the leading multiplier tells: onwards it moves away from its values before.
    probe = continue_multiple(system, param, orbit.period, x0, direction, bounds,
                              dataclasses.replace(walk2, max_points=PROBE_POINTS,
                                                  stick_events=False),
                              segments=mesh, stages=(), remesh=False, chord=way_on)  # fmt: skip
    if _turns_back(branch, probe):
        way_on, direction = (-way_on[0], -way_on[1]), -direction
    second = continue_multiple(system, param, orbit.period, x0, direction, bounds, walk2,
                               segments=mesh, stages=(), remesh=remesh, chord=way_on,
                               max_segments=max_segments)  # fmt: skip
    second.system = orbit.system
    return append_branch(branch, second, f"single shooting: {branch.status}")


#: Points of the probe that checks the way on (:func:`_go_on_multiple`), and how far back
PROBE_POINTS, WAY_BACK = 3, 1e-6  # along the branch it compares (section point, parameter)


def _lead(mults: np.ndarray) -> np.ndarray:
    """The largest multiplier modulus of every point (NaN-safe)."""
    return np.nanmax(np.where(np.isfinite(np.abs(mults)), np.abs(mults), np.nan), axis=1)


def _turns_back(branch: Branch, probe: Branch) -> bool:
    """True where the probe's leading multiplier moves (from the probe's own first point:
    the two methods' multipliers differ, by 8e-4 at mu ~ 1 at k12 = -0.8316) back towards
    its value at the branch's point :data:`WAY_BACK` or more before the end (section point
    and parameter), which lies before any crawl of the end: the probe is retracing."""
    end = np.r_[branch.points[-1], branch.values[-1]]
    k = len(branch.values) - 2
    while k > 0 and np.linalg.norm(end - np.r_[branch.points[k], branch.values[k]]) < WAY_BACK:
        k -= 1
    lead, probe_lead = _lead(branch.multipliers), _lead(probe.multipliers)
    moved = probe_lead[-1] - probe_lead[0]
    return bool(abs(moved) > 1e-9 and np.sign(moved) == np.sign(lead[k] - lead[-1]))


def _return_times(xs, periods, compute) -> np.ndarray:
    """The return time T of every branch point: from the corrector's record, else computed."""
    T = np.empty(len(xs))
    for i, x in enumerate(xs):
        T[i] = periods.get(x.tobytes(), math.nan)
        if not math.isfinite(T[i]):
            T[i] = compute(x)
    return T


def _cut_at_period_jump(xs, mults, T, bifs, status):
    """The branch up to the first step whose return time jumps by more than 5 %.

    The corrector refuses such steps (``jump`` in :func:`_continue_single`), but the
    return time recorded for a point is that of its latest evaluation, and the sharp
    ends' tighter stages evaluate recent points again. Near a tangency of the orbit with
    the section, whether a crossing is counted can depend on the integration, so a point
    accepted with one T can carry another: Fig. 6's period-4 branch went from T = 42.38 to
    31.99 within 1.5e-6 in eta (refusing such restarts in
    :func:`~stickslip_fast.bifurcation.arclength.pseudo_arclength` did not prevent it).
    A branch never joins two such families: it ends "nonsmooth" at the last point before
    the jump, and the bifurcations after it are dropped.
    """
    rel = np.abs(np.diff(T)) / np.abs(T[:-1])
    bad = np.flatnonzero(np.isfinite(rel) & (rel > 0.05))
    if bad.size == 0:
        return xs, mults, T, status
    k = int(bad[0])
    bifs[:] = [b for b in bifs if b[2] <= k]
    return xs[: k + 1], mults[: k + 1], T[: k + 1], "nonsmooth"


def _continue_single(orbit, param, lam0, lo, hi, direction, walk: WalkSettings):
    """continue_orbit with shooting="single" (its settings): (the Branch, its way on).

    The way on is (d_state, d_lambda): the walk's unit tangent at its last point, oriented
    onwards (by continuity along the branch), in the full state (0 at the section's
    coordinate) and the parameter; None if the walk accepted no point."""
    system0 = orbit.system
    p = orbit.period
    tol, rtol, atol, fd_step = walk.tol, walk.rtol, walk.atol, walk.fd_step
    evaluate, full, system_at, periods = _orbit_evaluator(system0, param, p, rtol, atol, fd_step)
    kw = dict(rtol=rtol, atol=atol)
    mask = np.arange(system0.n_state) != SECTION_INDEX

    def jump(x_old, x_new):
        t_old = periods.get(x_old.tobytes(), math.nan)
        t_new = periods.get(x_new.tobytes(), math.nan)
        if not abs(t_new - t_old) <= 0.05 * t_old:
            return True
        # a rest point is a fixed point of the map too (near a stable focus): not the branch
        f = _field(system_at(x_new[-1]), full(x_new))
        return bool(np.max(np.abs(f)) < EQUILIBRIUM_SPEED)

    refine = []
    if walk.sharp_ends:
        cur = (tol, rtol, atol, walk.ds_min)
        for stage in SHARP_END_STAGES:
            nxt = tuple(min(a, b) for a, b in zip(cur, stage))
            if nxt != cur:
                ev, _, _, _ = _orbit_evaluator(system0, param, p, nxt[1], nxt[2], fd_step,
                                               periods)  # fmt: skip
                refine.append((ev, nxt[0], nxt[3]))
                cur = nxt
    x0 = np.r_[orbit.points[0][mask], lam0]
    evaluate(x0)
    last = {}
    # an in-phase branch also marks where a transverse multiplier passes +1; most, branch points
    evaluate, refine, marks = in_phase_walk(orbit, system_at, full, evaluate, refine, periods)
    marks.update(branch_point_marks(system0))

    def keep_tangent(x, data, walk):  # the tangent at each accepted point, oriented onwards
        last["t"] = walk.t.copy()
        return False

    xs, mults, bifs, status = pseudo_arclength(
        evaluate, x0, direction, (lo, hi), ds=walk.ds, ds_min=walk.ds_min, ds_max=walk.ds_max,
        max_points=walk.max_points, tol=tol, jump=jump, refine=refine, stop=keep_tangent, **marks,
    )  # fmt: skip
    T = _return_times(
        xs, periods, lambda x: return_map(system_at(x[-1]), full(x), p, tangents=False, **kw)[2][-1]
    )
    xs, mults, T, status = _cut_at_period_jump(xs, mults, T, bifs, status)
    if status == "nonsmooth":
        # the fixed point of P^p ends: its return time jumps (a crossing of the section
        # appears or vanishes: the orbit grazes dx1 = 0), within ds_min of the last point
        bifs.append(("section-grazing", float(xs[-1][-1]), len(xs) - 1, xs[-1].copy()))
    points = np.array([full(x) for x in xs])
    stick_count = stick_time = None
    if walk.stick_events:
        stick_count, stick_time = _stick_events(xs, T, system_at, full, evaluate, periods, tol,
                                                bifs)  # fmt: skip
        bifs.sort(key=lambda b: (b[2], b[1] if direction >= 0 else -b[1]))
    way_on = None
    if "t" in last:
        d_state = np.zeros(system0.n_state)
        d_state[mask] = last["t"][:-1]
        way_on = (d_state, float(last["t"][-1]))
    return Branch(
        system=system0,
        param=param,
        period=p,
        values=xs[:, -1].copy(),
        points=points,
        T=T,
        multipliers=mults,
        stable=multipliers_stable(system0, mults),
        bifurcations=[Bifurcation(k, v, i, full(x)) for k, v, i, x in bifs],
        status=status,
        stick_count=stick_count,
        stick_time=stick_time,
    ), way_on
