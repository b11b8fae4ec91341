"""Continuation of periodic orbits by multiple shooting (``continue_orbit(shooting=...)``).

The branch is followed in x = (u, lambda), u the unknowns of :class:`.multishoot.MultiShooting`
(the segment starts and T), with the predictor-corrector of :mod:`.arclength`. The
multipliers come from the segments' factors (:func:`.multishoot.periodic_multipliers`),
never from their product."""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from ..base.blas import one_blas_thread
from .arclength import pseudo_arclength
from .branch import Bifurcation, Branch, segments_of
from .corrector import NOISE_FLOOR, _correct, _locate_change
from .equilibria import EQUILIBRIUM_SPEED
from .multishoot import (
    MAX_SEGMENTS,
    REMESH_LIMIT,
    MultiShooting,
    periodic_multipliers,
    refine_mesh,
    remesh,
)
from .multishoot_orbit import initial_segments, newton_multiple
from .multishoot_sync import in_phase_marks, in_phase_start, project_segments
from .orbit_record import branch_point_marks, multipliers_stable
from .returnmap import _TANGENT_ATOL, _field
from .stickphases import stick_phases
from .walk_args import WalkSettings


def multiplier_tests(A, t: np.ndarray, multipliers=periodic_multipliers) -> dict[str, float]:
    """The test functions of :func:`.detection._tests` from the segments' factors ``A``
    (their multipliers by ``multipliers``)."""
    mu = multipliers(A)
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


#: How far above ``tol`` a start's correction on the coarse mesh may stall and still be
#: refined (:func:`ms_start`): the refined mesh must then reach ``tol`` itself.
COARSE_RES = 1e3


def ms_start(system, z, T, param, segments, rtol, atol, fd_step, tol, mesh_limit=None,
             known=None, max_segments=MAX_SEGMENTS):  # fmt: skip
    """(x, mesh): x = (u, lambda) of the orbit through z (period T) on the section, corrected
    by Newton at fixed lambda, or None if it does not converge. With ``mesh_limit``, the
    mesh is refined where a segment amplifies more than that (:func:`refine_mesh`, up to
    ``max_segments``) and the orbit corrected again on it. ``known``: (mesh, starts) of
    the orbit already cut into segments (``Orbit.segments``); they replace ``segments``
    and the one trajectory from z, which for a very unstable orbit leaves it within the
    period."""
    if known is not None:
        segments = np.asarray(known[0], dtype=float)
    _, _, shooting_at = ms_evaluator(system, param, segments, rtol, atol, fd_step)
    ms = shooting_at(getattr(system, param), None)
    if known is None:
        st, Y = initial_segments(ms, z, T)
    else:
        st, Y = "ok", np.array(known[1], dtype=float)
    if st != "ok":
        return None, ms.mesh
    status, _, u, _, res, _, _ = newton_multiple(ms, ms.pack(Y, T), tol, 12)
    if mesh_limit is not None and status in ("max-iter", "no-progress") and res <= COARSE_RES * tol:
        # the coarse mesh's rounding noise can lie above tol where the refined mesh's
        # does not (measured: 7e-12 on 14 segments, 3e-15 on 29, at multiplier 1e8):
        # close enough to refine, and the refined mesh is then corrected to tol itself
        status = "converged"
    if status == "converged" and mesh_limit is not None:
        Y, T = ms.unpack(u)
        mesh = refine_mesh(ms, Y, T, mesh_limit, max_segments)
        st, Y = ms.states_at(Y, T, mesh[:-1] * T, mesh=ms.mesh)
        _, _, shooting_at = ms_evaluator(system, param, mesh, rtol, atol, fd_step)
        ms = shooting_at(getattr(system, param), None)
        status, _, u, _, _, _, _ = newton_multiple(ms, ms.pack(Y, T), tol, 12)
    if status != "converged":
        return None, ms.mesh
    return np.r_[u, float(getattr(system, param))], ms.mesh


@one_blas_thread()
def continue_multiple(system0, param, period, x0, direction, bounds, walk: WalkSettings, *,
                      segments, stages, remesh=False, chord=None,
                      max_segments=MAX_SEGMENTS) -> Branch:  # fmt: skip
    """The branch through x0 = (u, lambda) by multiple shooting (``walk``: ``continue_orbit``'s
    settings; ``stages``: its sharp-end stages, (tol, rtol, atol, ds_min)). With ``remesh`` the
    segments are cut again (:func:`.multishoot.remesh`) wherever one amplifies by more
    than :data:`.multishoot.REMESH_LIMIT` (into at most ``max_segments``); the branch is
    then followed in pieces, one per mesh (:func:`walk_pieces`). ``chord``: (d_state,
    d_lambda), the way the branch goes on from x0 (a section point's change and the
    parameter's: the tangent of the walk that came to x0); when given, the first tangent
    is oriented along it instead of by ``direction`` in lambda, which is undefined at a
    fold."""
    settings = [(walk.tol, walk.rtol, walk.atol, walk.ds_min)]
    if walk.sharp_ends:
        for stage in stages:
            nxt = tuple(min(a, b) for a, b in zip(settings[-1], stage))
            if nxt != settings[-1]:
                settings.append(nxt)
    # an in-phase start on a DC motor: the walk stays in phase and marks SB points
    ms0 = MultiShooting(system0, segments, walk.rtol, walk.atol, _TANGENT_ATOL)
    in_phase = in_phase_start(system0, ms0, x0)
    kw = dict(ds=walk.ds, ds_max=walk.ds_max, max_points=walk.max_points,
              fd_step=walk.fd_step, chord=chord, max_segments=max_segments,
              in_phase=in_phase)  # fmt: skip
    pieces, status = walk_pieces(system0, param, x0, direction, bounds, segments, settings,
                                 remesh, kw)  # fmt: skip
    _, system_at, _ = ms_evaluator(system0, param, segments, walk.rtol, walk.atol, walk.fd_step)
    if status == "nonsmooth":
        last = pieces[-1]
        last.bifs.append(("section-grazing", float(last.xs[-1][-1]), len(last.xs) - 1,
                          last.xs[-1].copy()))  # fmt: skip
    vals, pts, Ts, mults, counts, times, bifs, segs = [], [], [], [], [], [], [], []
    for k, pc in enumerate(pieces):
        skip = 1 if k else 0  # a piece starts at its predecessor's last point, re-meshed
        off = len(vals) - skip
        starts = [pc.ms.unpack(x[:-1])[0] for x in pc.xs]
        T = pc.xs[:, -2].copy()
        if walk.stick_events:
            c, t = _stick_events(pc.xs, starts, T, system_at, pc.ms, pc.evaluate, pc.tol,
                                 pc.bifs)  # fmt: skip
            counts.extend(c[skip:])
            times.extend(t[skip:])
        vals.extend(pc.xs[skip:, -1])
        pts.extend(Y[0] for Y in starts[skip:])
        segs.extend((pc.ms.mesh.copy(), Y) for Y in starts[skip:])
        Ts.extend(T[skip:])
        mults.extend(pc.mults[skip:])
        bifs.extend((b, v, i + off, pc.ms.unpack(x[:-1])[0][0]) for b, v, i, x in pc.bifs)
    bifs.sort(key=lambda b: (b[2], b[1] if direction >= 0 else -b[1]))
    mults = np.array(mults)
    return Branch(
        system=system0, param=param, period=period, values=np.array(vals),
        points=np.array(pts), T=np.array(Ts), multipliers=mults,
        stable=multipliers_stable(system0, mults),
        bifurcations=[Bifurcation(*b) for b in bifs], status=status,
        stick_count=np.array(counts, dtype=np.int64) if walk.stick_events else None,
        stick_time=np.array(times) if walk.stick_events else None, segments=segs,
    )  # fmt: skip


@dataclasses.dataclass
class _Piece:
    """A stretch of a branch followed on one mesh: its shooting system, its first stage's
    evaluator and tolerance, and :func:`pseudo_arclength`'s results."""

    ms: MultiShooting
    evaluate: object
    tol: float
    xs: np.ndarray
    mults: np.ndarray
    bifs: list


class _RemeshTrigger:
    """``pseudo_arclength``'s ``stop``: True where a segment of ``ms`` amplifies by more
    than the limit and :func:`remesh` gives another mesh of at most ``max_segments``
    segments (kept in ``mesh``, with the walk's step size and the number of its stages
    left). ``system_at``: the system at a parameter value, at which :func:`remesh`
    integrates the point's segments."""

    def __init__(
        self, ms: MultiShooting, system_at, limit: float = REMESH_LIMIT,
        max_segments: int = MAX_SEGMENTS,
    ) -> None:  # fmt: skip
        self.ms, self.system_at, self.limit = ms, system_at, limit
        self.max_segments = max_segments
        self.mesh, self.ds, self.stages_left, self.limit_hit = None, math.nan, 0, math.nan

    def __call__(self, x, A, walk) -> bool:
        if isinstance(A, tuple):  # an in-phase walk's (factors, x)
            A = A[0]
        norms = np.array([np.linalg.norm(a, 2) for a in A])
        if not float(np.max(norms)) > self.limit:
            return False
        Y, T = self.ms.unpack(x[:-1])
        ms = MultiShooting(self.system_at(x[-1]), self.ms.mesh, *self.ms.kw)
        mesh = remesh(ms, Y, T, norms, max_segments=self.max_segments)
        if mesh.size == self.ms.mesh.size and np.allclose(mesh, self.ms.mesh, rtol=0, atol=1e-12):
            self.limit = 10.0 * float(np.max(norms))  # no better mesh: check again later
            return False
        self.mesh, self.ds, self.stages_left = mesh, walk.ds, len(walk.stages)
        self.limit_hit = float(np.max(norms))
        return True


def _jump_test(ms0: MultiShooting, system_at):
    """The ``jump`` of :func:`pseudo_arclength`: T moved by more than 5 %, or a rest point."""

    def jump(x_old, x_new):
        t_old, t_new = float(x_old[-2]), float(x_new[-2])
        if not abs(t_new - t_old) <= 0.05 * t_old:
            return True
        Y, _ = ms0.unpack(x_new[:-1])
        return bool(np.max(np.abs(_field(system_at(x_new[-1]), Y[0]))) < EQUILIBRIUM_SPEED)

    return jump


def _resume(ms_old: MultiShooting, ms_new: MultiShooting, evaluate, xs, tol, system_at):
    """(x, orient): the last point of ``xs`` re-sampled on ``ms_new``'s mesh and corrected
    there (on the hyperplane through it normal to the re-sampled last chord, which also
    orients the next tangent), or (None, None). Each point is re-sampled at its own
    parameter value (``system_at``), not at that of ``ms_old`` (the piece's first point)."""
    out = []
    for x in (xs[-2], xs[-1]):
        old = MultiShooting(system_at(x[-1]), ms_old.mesh, *ms_old.kw)
        Y, T = old.unpack(x[:-1])
        st, Yn = old.states_at(Y, T, ms_new.mesh[:-1] * T, mesh=old.mesh)
        if st != "ok":
            return None, None
        out.append(np.r_[ms_new.pack(Yn, T), x[-1]])
    chord = out[1] - out[0]
    normal = chord / np.linalg.norm(chord)
    okc, x, data, _ = _correct(evaluate, out[1], normal, out[1], tol, 8)
    if not okc or data is NOISE_FLOOR:
        return None, None
    return x, chord


class _LastMultipliers:
    """:func:`periodic_multipliers` of the factors asked for last, kept: a walk's test
    functions and its spectrum take them from the same factors at every point (twice the
    periodic QR per point otherwise, 2.4 s of a 21.5 s walk of two disks)."""

    def __init__(self) -> None:
        self.factors, self.mu = None, None

    def __call__(self, factors) -> np.ndarray:
        if factors is not self.factors:  # the object itself is kept: no reused id
            self.factors, self.mu = factors, periodic_multipliers(factors)
        return self.mu


class _WalkCoordinates:
    """The coordinates a multiple-shooting walk steps in: x̃ = x with T divided by
    2**k, the power of two nearest the branch's first period (exact in floating point).

    Single shooting's arclength measures the section point and the parameter. Here T
    is an unknown too, in time units, and its change per unit parameter (3.5 on Fig. 6's
    period-1 branch, where the section point moves by 0.03) set the step: with T as it
    is, the defaults took 77 points where single shooting took 24 over eta 2 -> 3, and
    the two-disk in-phase walk from eta = 3 ended "max-points" at 3.67 where single
    shooting reached 5 in 44. With T / 2**k: 26 points, and 5.0 in 87. (Weighting the
    segment starts by 1/sqrt(m) as well changed neither walk by more than 3 points, so
    they stay as they are.) ``evaluate``, ``refine``, ``jump`` and ``stop`` are given in
    x and wrapped for x̃; the walk's points come back with :meth:`from_walk`."""

    def __init__(self, x0, evaluate, refine, jump, stop) -> None:
        self.scale = 2.0 ** -round(math.log2(abs(float(x0[-2]))))
        self.evaluate = self._wrap(evaluate)
        self.refine = [(self._wrap(ev), tol, ds_min) for ev, tol, ds_min in refine]
        unscale = self.from_walk
        self.jump = None if jump is None else (lambda a, b: jump(unscale(a), unscale(b)))
        self.stop = None if stop is None else (lambda x, A, w: stop(unscale(x), A, w))

    def to_walk(self, x: np.ndarray) -> np.ndarray:
        out = np.array(x, dtype=float)
        out[..., -2] *= self.scale
        return out

    def from_walk(self, x: np.ndarray) -> np.ndarray:
        out = np.array(x, dtype=float)
        out[..., -2] /= self.scale
        return out

    def _wrap(self, evaluate):
        def in_walk(x):
            ok, G, DG, A = evaluate(self.from_walk(x))
            if DG is not None:  # d/dx̃ = d/dx diag(1, ..., 1/scale, 1)
                DG = DG.copy()
                DG[:, -2] /= self.scale
            return ok, G, DG, A

        return in_walk


def walk_pieces(system0, param, x0, direction, bounds, segments, settings, remesh_, kw):
    """The branch by :func:`pseudo_arclength`, one piece per mesh: (pieces, status).

    ``settings``: the stages (tol, rtol, atol, ds_min), the first in force at x0. With
    ``remesh_``, a piece stops where :class:`_RemeshTrigger` finds a better mesh (of at most
    ``kw["max_segments"]`` segments); the next
    starts from its last point re-sampled on that mesh, in the stage and with the step
    size reached, its tangent oriented along the last chord. Where that point cannot be
    corrected on the new mesh, the walk goes on on the old one (re-meshing again once a
    segment amplifies 10 times more)."""
    pieces, stage, mesh, x_start, orient = [], 0, segments, x0, None
    ds, left, limit = kw["ds"], kw["max_points"], REMESH_LIMIT
    while True:
        tol, rtol, atol, ds_min = settings[stage]
        evaluate, system_at, shooting_at = ms_evaluator(system0, param, mesh, rtol, atol,
                                                        kw["fd_step"])  # fmt: skip
        ms = shooting_at(x_start[-1], None)
        if orient is None and kw.get("chord") is not None:  # the first piece: the way on
            d_state, d_lam = kw["chord"]
            orient = np.zeros_like(x_start)
            orient[: ms.n - 1] = np.asarray(d_state)[ms.mask]
            orient[-1] = d_lam
        refine = []
        for t2, r2, a2, d2 in settings[stage + 1 :]:
            ev, _, _ = ms_evaluator(system0, param, mesh, r2, a2, kw["fd_step"])
            refine.append((ev, t2, d2))
        spectrum = _LastMultipliers()
        tests = functools.partial(multiplier_tests, multipliers=spectrum)
        marks = {"tests": tests, "spectrum": spectrum}
        if kw["in_phase"]:
            evaluate = project_segments(evaluate, system0, ms)
            refine = [(project_segments(ev, system0, ms), t2, d2) for ev, t2, d2 in refine]
            marks = in_phase_marks(system_at, ms, tests, spectrum)
        trigger = _RemeshTrigger(ms, system_at, limit, kw["max_segments"]) if remesh_ else None
        walk_in = _WalkCoordinates(x0, evaluate, refine, _jump_test(ms, system_at), trigger)
        # a crawl: the last steps together below the first stage's ds_min or its tol (steps
        # smaller than the corrector's tolerance do not move the branch; a walk handed on by
        # shooting="auto" has ds_min = 1e-16 and tol 1e-12, and crawled for 60+ points)
        xs, mults, bifs, status = pseudo_arclength(
            walk_in.evaluate, walk_in.to_walk(x_start), direction, bounds, ds=ds, ds_min=ds_min,
            ds_max=kw["ds_max"], max_points=left, tol=tol, jump=walk_in.jump,
            refine=walk_in.refine, orient=None if orient is None else walk_in.to_walk(orient),
            stall_ds_min=max(settings[0][3], settings[0][0]), stop=walk_in.stop,
            **marks, **branch_point_marks(system0),
        )  # fmt: skip
        xs, bifs = walk_in.from_walk(xs), [(k, v, i, walk_in.from_walk(x)) for k, v, i, x in bifs]
        pieces.append(_Piece(ms, evaluate, tol, xs, np.asarray(mults), bifs))
        if status != "stopped":
            return pieces, status
        left -= len(xs) - 1
        stage += len(refine) - trigger.stages_left
        ds, limit = trigger.ds, REMESH_LIMIT
        tol, rtol, atol, _ = settings[stage]
        ev_new, _, shoot_new = ms_evaluator(system0, param, trigger.mesh, rtol, atol,
                                            kw["fd_step"])  # fmt: skip
        if kw["in_phase"]:
            ev_new = project_segments(ev_new, system0, shoot_new(xs[-1][-1], None))
        # the last point, in the stage reached: correct it with that stage's evaluator
        ms_cur = MultiShooting(ms.system, ms.mesh, rtol, atol, _TANGENT_ATOL)
        x_new, orient = _resume(ms_cur, shoot_new(xs[-1][-1], None), ev_new, xs, tol, system_at)
        if x_new is None:  # go on on the old mesh from the last point
            x_new, orient, limit = xs[-1], xs[-1] - xs[-2], 10.0 * trigger.limit_hit
        else:
            mesh = trigger.mesh
        x_start = x_new


def _stick_events(xs, starts, T, system_at, ms0, evaluate, tol, bifs):
    """Stick phases per point (each segment sampled from its own start) and their changes."""
    count = np.full(len(xs), -1, dtype=np.int64)
    total = np.full(len(xs), np.nan)

    def geometry(x):
        Y, T_x = ms0.unpack(x[:-1])
        d = stick_phases(system_at(x[-1]), Y[0], T_x, starts=Y, mesh=ms0.mesh)
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

    # a point the first branch located at its end, located again by the other method
    # (their multipliers differ by ~1e-4 at a sharp fold: one fold, two places 3e-12 apart)
    def again(b) -> bool:
        return any(a.kind == b.kind and abs(a.value - b.value) <= 1e-9 * max(1.0, abs(a.value))
                   for a in first.bifurcations)  # fmt: skip

    bifs = list(first.bifurcations) + [
        Bifurcation(b.kind, b.value, k + b.index, b.point)
        for b in second.bifurcations
        if not again(b)
    ]
    return Branch(
        system=first.system, param=first.param, period=first.period,
        values=cat(first.values, second.values), points=cat(first.points, second.points),
        T=cat(first.T, second.T), multipliers=cat(first.multipliers, second.multipliers),
        stable=cat(first.stable, second.stable), bifurcations=bifs,
        status=f"{joined_at}; then multiple shooting: {second.status}",
        stick_count=cat(first.stick_count, second.stick_count),
        stick_time=cat(first.stick_time, second.stick_time),
        segments=segments_of(first) + segments_of(second)[1:],
    )  # fmt: skip
