"""Continuation of periodic orbits by multiple shooting (``continue_orbit(shooting=...)``).

The branch is followed in x = (u, lambda), u the unknowns of :class:`.multishoot.MultiShooting`
(the segment starts and T), with the predictor-corrector of :mod:`.arclength`. The
multipliers come from the segments' factors (:func:`.multishoot.periodic_multipliers`),
never from their product."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .arclength import _locate_change, pseudo_arclength
from .branch import Bifurcation, Branch
from .equilibria import EQUILIBRIUM_SPEED
from .multishoot import MultiShooting, periodic_multipliers, refine_mesh
from .multishoot_orbit import initial_segments, newton_multiple
from .returnmap import _TANGENT_ATOL, _field
from .stickphases import stick_phases


def multiplier_tests(A, t: np.ndarray) -> dict[str, float]:
    """The test functions of :func:`.detection._tests` from the segments' factors ``A``."""
    mu = periodic_multipliers(A)
    cplx = mu[np.abs(mu.imag) > 1e-12 * np.maximum(1.0, np.abs(mu))]
    ns = math.nan
    if cplx.size:
        ns = float((np.abs(cplx) - 1.0)[np.argmin(np.abs(np.abs(cplx) - 1.0))])
    return {
        "fold": float(t[-1]),
        "period-doubling": float(np.prod(mu + 1.0).real),
        "neimark-sacker": ns,
    }


def ms_evaluator(system0, param: str, segments: int, rtol: float, atol: float, fd_step: float):
    """(evaluate, system_at, shooting_at) for :func:`pseudo_arclength` on x = (u, lambda)."""

    def system_at(lam):
        return dataclasses.replace(system0, **{param: float(lam)})

    def shooting_at(lam, param_=param):
        return MultiShooting(system_at(lam), segments, rtol, atol, _TANGENT_ATOL, param_, fd_step)

    cache: dict[bytes, tuple] = {}

    def evaluate(x):
        key = x.tobytes()
        if key in cache:
            return cache[key]
        try:
            ms = shooting_at(x[-1])
        except ValueError:  # outside the parameter's valid range
            return False, None, None, None
        st, G, DG, factors = ms.evaluate(x[:-1])
        out = (st == "ok", G, DG, factors)
        cache.clear()
        cache[key] = out
        return out

    return evaluate, system_at, shooting_at


def ms_start(system, z, T, param, segments, rtol, atol, fd_step, tol, mesh_limit=None):
    """(x, mesh): x = (u, lambda) of the orbit through z (period T) on the section, corrected
    by Newton at fixed lambda, or None if it does not converge. With ``mesh_limit``, the
    mesh is refined where a segment amplifies more than that (:func:`refine_mesh`) and
    the orbit corrected again on it."""
    _, _, shooting_at = ms_evaluator(system, param, segments, rtol, atol, fd_step)
    ms = shooting_at(getattr(system, param), None)
    st, Y = initial_segments(ms, z, T)
    if st != "ok":
        return None, ms.mesh
    status, _, u, _, _, _, _ = newton_multiple(ms, ms.pack(Y, T), tol, 12)
    if status == "converged" and mesh_limit is not None:
        Y, T = ms.unpack(u)
        mesh = refine_mesh(ms, Y, T, mesh_limit)
        st, Y = ms.states_at(Y, T, mesh[:-1] * T, mesh=ms.mesh)
        _, _, shooting_at = ms_evaluator(system, param, mesh, rtol, atol, fd_step)
        ms = shooting_at(getattr(system, param), None)
        status, _, u, _, _, _, _ = newton_multiple(ms, ms.pack(Y, T), tol, 12)
    if status != "converged":
        return None, ms.mesh
    return np.r_[u, float(getattr(system, param))], ms.mesh


def continue_multiple(system0, param, period, x0, direction, bounds, *, segments, ds, ds_min,
                      ds_max, max_points, tol, rtol, atol, fd_step, stick_events,
                      sharp_ends, stages) -> Branch:  # fmt: skip
    """The branch through x0 = (u, lambda) by multiple shooting (``continue_orbit``'s arguments;
    ``stages``: its sharp-end stages, (tol, rtol, atol, ds_min))."""
    evaluate, system_at, shooting_at = ms_evaluator(system0, param, segments, rtol, atol, fd_step)
    ms0 = shooting_at(x0[-1], None)

    def jump(x_old, x_new):
        t_old, t_new = float(x_old[-2]), float(x_new[-2])
        if not abs(t_new - t_old) <= 0.05 * t_old:
            return True
        Y, _ = ms0.unpack(x_new[:-1])
        return bool(np.max(np.abs(_field(system_at(x_new[-1]), Y[0]))) < EQUILIBRIUM_SPEED)

    refine = []
    if sharp_ends:
        cur = (tol, rtol, atol, ds_min)
        for stage in stages:
            nxt = tuple(min(a, b) for a, b in zip(cur, stage))
            if nxt != cur:
                ev, _, _ = ms_evaluator(system0, param, segments, nxt[1], nxt[2], fd_step)
                refine.append((ev, nxt[0], nxt[3]))
                cur = nxt
    xs, mults, bifs, status = pseudo_arclength(
        evaluate, x0, direction, bounds, ds=ds, ds_min=ds_min, ds_max=ds_max,
        max_points=max_points, tol=tol, jump=jump, refine=refine,
        tests=multiplier_tests, spectrum=periodic_multipliers,
    )  # fmt: skip
    if status == "nonsmooth":
        bifs.append(("section-grazing", float(xs[-1][-1]), len(xs) - 1, xs[-1].copy()))
    starts = [ms0.unpack(x[:-1])[0] for x in xs]
    T = xs[:, -2].copy()
    stick_count = stick_time = None
    if stick_events:
        stick_count, stick_time = _stick_events(xs, starts, T, system_at, ms0, evaluate, tol, bifs)
    bifs.sort(key=lambda b: (b[2], b[1] if direction >= 0 else -b[1]))
    return Branch(
        system=system0, param=param, period=period, values=xs[:, -1].copy(),
        points=np.array([Y[0] for Y in starts]), T=T, multipliers=mults,
        stable=np.all(np.abs(mults) < 1.0, axis=1),
        bifurcations=[Bifurcation(k, v, i, ms0.unpack(x[:-1])[0][0]) for k, v, i, x in bifs],
        status=status, stick_count=stick_count, stick_time=stick_time,
    )  # fmt: skip


def _stick_events(xs, starts, T, system_at, ms0, evaluate, tol, bifs):
    """Stick phases per point (each segment sampled from its own start) and their changes."""
    count = np.full(len(xs), -1, dtype=np.int64)
    total = np.full(len(xs), np.nan)

    def geometry(x):
        Y, T_x = ms0.unpack(x[:-1])
        d = stick_phases(system_at(x[-1]), Y[0], T_x, starts=Y)
        return d.size, float(d.sum())

    for i, x in enumerate(xs):
        try:
            count[i], total[i] = geometry(x)
        except ValueError:  # the orbit could not be sampled: left as not computed
            pass
    for i in range(len(xs) - 1):
        a, b = count[i], count[i + 1]
        if a >= 0 and b >= 0 and a != b:
            loc = _locate_change(evaluate, xs[i], xs[i + 1], a, lambda x: geometry(x)[0], tol, 1e-8)
            bifs.append(("stick-phase", float(loc[-1]), i, loc))
    return count, total


def append_branch(first: Branch, second: Branch, joined_at: str) -> Branch:
    """``second`` (continued from ``first``'s last point) appended to ``first``."""
    k = first.values.size - 1

    def cat(a, b):
        if a is None or b is None:
            return None
        return np.concatenate([a, b[1:]])

    bifs = list(first.bifurcations) + [
        Bifurcation(b.kind, b.value, k + b.index, b.point) for b in second.bifurcations
    ]
    return Branch(
        system=first.system, param=first.param, period=first.period,
        values=cat(first.values, second.values), points=cat(first.points, second.points),
        T=cat(first.T, second.T), multipliers=cat(first.multipliers, second.multipliers),
        stable=cat(first.stable, second.stable), bifurcations=bifs,
        status=f"{joined_at}; then multiple shooting: {second.status}",
        stick_count=cat(first.stick_count, second.stick_count),
        stick_time=cat(first.stick_time, second.stick_time),
    )  # fmt: skip
