"""The stable manifold of a saddle fixed point of a map, traced as a curve in a plane of starts.

A saddle x* of a map P (a periodic orbit's point on the Poincare section, P its
return map) with one unstable multiplier mu has a stable set W^s of codimension
one; its intersection with a 2-D plane of starts p(u, v) is a curve. Backward
integration is not used (the friction law makes it unstable). Instead a plane
point is on the curve when its n-th image lies on the saddle's local stable
subspace (a boundary-value condition, as in shooting to the local manifold /
Lin's method)::

    g_n(p) = w . (P^n(p) - x*) = 0,     ||P^n(p) - x*|| <= r_local,

with w the left eigenvector of mu (normalised w . v = 1 for its right
eigenvector v, so g_n is the unstable coordinate of P^n(p)). Because P^n
stretches the unstable coordinate by mu^n, g_n changes sign across W^s and a
root of g_n is a point of W^s up to the local manifold's curvature at distance
r_local, shrunk by mu^n.

:func:`trace_manifold` follows the zero set of g_n by predictor-corrector
continuation: a secant predictor of length ``ds``, a corrector along the normal
that brackets the root and refines it by the Illinois (regula falsi) rule, and
``n`` adapted so that P^n(p) stays within ``r_local`` of x*. The map enters only
through a callable, so the tracer is pure NumPy and is tested on maps whose
stable manifold is known (tests/test_basins_manifold.py);
:func:`stickslip_fast.bifurcation.stable_manifold.stable_manifold` gives it the
model's return map. The result, :class:`StableManifold`, is stored in a basins
file's ``/basins/manifold`` group (:mod:`stickslip_fast.io.basins`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["StableManifold", "LocalSaddle", "local_saddles", "trace_manifold"]

#: Why a traced branch ended (``StableManifold.branch_status``).
BRANCH_STATUSES = ("box", "closed", "max-points", "ds-min", "n-max")


@dataclass
class LocalSaddle:
    """The linear data of one saddle point x* of P^p (section coordinates).

    Attributes
    ----------
    point : ndarray (d,)
    mu : float
        The unstable multiplier (real, ``|mu| > 1``).
    right, left : ndarray (d,)
        Its right and left eigenvectors, ``left . right = 1``, ``|right| = 1``.
    """

    point: np.ndarray
    mu: float
    right: np.ndarray
    left: np.ndarray


def local_saddles(points: Any, jacobians: Any) -> list[LocalSaddle]:
    """:class:`LocalSaddle` of each point from D P^p there.

    Raises
    ------
    ValueError
        Unless each Jacobian has exactly one multiplier outside the unit circle,
        and it is real (a saddle of index one, whose stable set is a hypersurface).
    """
    out = []
    for k, (z, jac) in enumerate(zip(np.atleast_2d(points), np.atleast_3d(jacobians))):
        ev, vr = np.linalg.eig(np.asarray(jac, dtype=float))
        big = np.flatnonzero(np.abs(ev) > 1.0)
        if big.size != 1 or abs(ev[big[0]].imag) > 1e-12 * abs(ev[big[0]]):
            raise ValueError(
                f"orbit point {k}: multipliers {np.round(ev, 6).tolist()}; the stable manifold "
                "needs exactly one real multiplier outside the unit circle (a saddle of index one)"
            )
        i = int(big[0])
        right = np.real(vr[:, i])
        right /= np.linalg.norm(right)
        evl, vl = np.linalg.eig(np.asarray(jac, dtype=float).T)
        left = np.real(vl[:, int(np.argmin(np.abs(evl - ev[i])))])
        left = left / float(left @ right)
        out.append(LocalSaddle(np.asarray(z, dtype=float), float(ev[i].real), right, left))
    return out


@dataclass
class StableManifold:
    """The intersection of a saddle orbit's stable manifold with a plane, as curves.

    Attributes
    ----------
    u, v : ndarray (m,)
        Points of the curve (plane coordinates), in order along each branch.
    branch : ndarray of int (m,)
        Which traced branch a point belongs to (a seed starts two half-branches,
        traced in opposite directions and stored as two branches).
    n : ndarray of int (m,)
        Crossings n of the condition at that point.
    target : ndarray of int (m,)
        Which of the orbit's points P^n(p) lands near.
    residual : ndarray (m,)
        ``|g_n(p)|``: the unstable coordinate of P^n(p) - x* (section units).
    distance : ndarray (m,)
        ||P^n(p) - x*|| (max norm): how far along the stable directions it landed.
    branch_status : list of str
        Why each branch ended (:data:`BRANCH_STATUSES`).
    saddle_points : ndarray (p, d_state)
        The saddle orbit's points (as the orbit gives them).
    saddle_period : int
    mu : ndarray (p,)
        The unstable multiplier at each orbit point (equal up to rounding).
    r_local, tol, ds : float
        The tracer's settings: neighbourhood radius, corrector tolerance (plane
        units) and initial step.
    n_evals : int
        Evaluations of P^n the tracing took.
    """

    u: np.ndarray
    v: np.ndarray
    branch: np.ndarray
    n: np.ndarray
    target: np.ndarray
    residual: np.ndarray
    distance: np.ndarray
    branch_status: list
    saddle_points: np.ndarray
    saddle_period: int
    mu: np.ndarray
    r_local: float
    tol: float
    ds: float
    n_evals: int
    settings: dict = field(default_factory=dict, repr=False)

    @property
    def uv(self) -> np.ndarray:
        """The curve points as an (m, 2) array."""
        return np.stack([self.u, self.v], axis=1)

    def distance_to(self, uv: Any) -> np.ndarray:
        """Distance (Euclidean, plane units) of each point ``uv`` (k, 2) to the traced curve
        (the polyline of each branch)."""
        q = np.atleast_2d(np.asarray(uv, dtype=float))
        pts = self.uv
        d = [_polyline_distance(q, pts[self.branch == b]) for b in np.unique(self.branch)]
        return np.min(d, axis=0) if d else np.full(len(q), np.inf)


# ------------------------------------------------------------------ the tracer
class _Condition:
    """g_n(p) and the distances of P^k(p) to the saddle points, counting evaluations."""

    def __init__(self, crossings: Callable, saddles: list[LocalSaddle], period: int) -> None:
        self.crossings, self.saddles, self.period = crossings, saddles, period
        self.n_evals = 0

    def images(self, uv: np.ndarray, n: int) -> np.ndarray:
        self.n_evals += 1
        return np.asarray(self.crossings(np.asarray(uv, dtype=float)[None], int(n))[0])

    def value(self, uv: np.ndarray, n: int, j: int) -> tuple[float, float]:
        """(g_n, ||P^n - x*_j||) at uv (NaN, inf when the map failed)."""
        y = self.images(uv, n)[n - 1]
        s = self.saddles[j]
        if not np.all(np.isfinite(y)):
            return np.nan, np.inf
        return float(s.left @ (y - s.point)), float(np.max(np.abs(y - s.point)))

    def closest(self, uv: np.ndarray, n_max: int, r_local: float) -> tuple[int, int]:
        """(n, j): the first image P^n(uv), n <= n_max, within ``r_local`` of a saddle
        point x*_j, or else the closest one."""
        y = self.images(uv, n_max)
        d = np.array([np.max(np.abs(y - s.point), axis=1) for s in self.saddles])  # (p, n_max)
        d = np.where(np.isfinite(d), d, np.inf)
        inside = np.flatnonzero(np.min(d, axis=0) <= r_local)
        k = int(inside[0]) if inside.size else int(np.argmin(np.min(d, axis=0)))
        return k + 1, int(np.argmin(d[:, k]))

    def first_inside(self, uv: np.ndarray, n: int, j: int, r_local: float) -> int:
        """The smallest m = n (mod p), m <= n, with ||P^m(uv) - x*_j|| <= r_local (else n)."""
        y = self.images(uv, n)[n - 1 :: -self.period][::-1]
        d = np.max(np.abs(y - self.saddles[j].point), axis=1)
        ok = np.flatnonzero(d <= r_local)
        return n - self.period * (len(y) - 1 - int(ok[0])) if ok.size else n


def _root_on_line(cond: _Condition, q, nrm, n, j, s_max, tol, g0=None) -> tuple:
    """Root s of g_n(q + s nrm), |s| <= s_max: bracket by doubling from a secant guess, then
    Illinois. Returns (s, g, dist) or None (no sign change within s_max, or a failed map)."""
    f0 = cond.value(q, n, j) if g0 is None else g0
    if not np.isfinite(f0[0]):
        return None
    if f0[0] == 0.0:
        return 0.0, f0[0], f0[1]
    h = max(tol * 16, s_max * 1e-3)
    fh = cond.value(q + h * nrm, n, j)
    if not np.isfinite(fh[0]):
        return None
    slope = (fh[0] - f0[0]) / h
    step = -f0[0] / slope if slope != 0 and np.isfinite(slope) else h
    step = float(np.clip(step, -s_max, s_max)) or h
    a, fa = 0.0, f0
    b, fb = step, cond.value(q + step * nrm, n, j)
    while np.isfinite(fb[0]) and np.sign(fb[0]) == np.sign(fa[0]):
        if abs(b) >= s_max:
            return None
        a, fa = b, fb
        b = float(np.clip(2.0 * b, -s_max, s_max))
        fb = cond.value(q + b * nrm, n, j)
    if not np.isfinite(fb[0]):
        return None
    return _illinois(cond, q, nrm, n, j, (a, fa), (b, fb), tol)


def _illinois(cond, q, nrm, n, j, lo, hi, tol, max_iter: int = 80) -> tuple | None:
    """Illinois regula falsi on a sign-change bracket ``lo``, ``hi`` = (s, (g, dist)); returns
    (s, g, dist) at the end with the smaller |g| once the bracket is shorter than ``tol``."""
    (a, fa), (b, fb) = lo, hi
    ga, gb, side = fa[0], fb[0], 0
    for _ in range(max_iter):
        if abs(b - a) <= tol:
            break
        c = (a * gb - b * ga) / (gb - ga)
        if not (min(a, b) < c < max(a, b)):
            c = 0.5 * (a + b)
        fc = cond.value(q + c * nrm, n, j)
        if not np.isfinite(fc[0]):
            return None
        if fc[0] == 0.0:
            return c, 0.0, fc[1]
        if np.sign(fc[0]) == np.sign(gb):
            b, fb, gb = c, fc, fc[0]
            ga = ga * 0.5 if side == -1 else ga
            side = -1
        else:
            a, fa, ga = c, fc, fc[0]
            gb = gb * 0.5 if side == 1 else gb
            side = 1
    else:
        return None
    return (a, fa[0], fa[1]) if abs(fa[0]) < abs(fb[0]) else (b, fb[0], fb[1])


def _correct(cond: _Condition, q: np.ndarray, nrm: np.ndarray, n: int, j: int, o: dict) -> tuple:
    """q moved along ``nrm`` onto g_n = 0, with n raised (by the period) until
    ||P^n - x*|| <= r_local. Returns ((uv, n, j, g, dist), None) or (None, why)."""
    s_max = o["s_max"]
    for _ in range(o["n_max"]):
        r = _root_on_line(cond, q, nrm, n, j, s_max, o["tol"])
        if r is None:
            return None, "ds-min"
        q = q + r[0] * nrm
        if r[2] <= o["r_local"]:
            m = cond.first_inside(q, n, j, o["r_local"])  # the next point starts from it
            return (q, n, j, r[1], r[2], m), None
        if n + cond.period > o["n_max"]:
            return None, "n-max"
        n += cond.period
        s_max = max(abs(r[0]), 64 * o["tol"])
    return None, "n-max"


def _unit(x: np.ndarray) -> np.ndarray:
    return x / np.linalg.norm(x)


def _gradient(cond: _Condition, uv: np.ndarray, n: int, j: int, h: float) -> np.ndarray:
    g0 = cond.value(uv, n, j)[0]
    return np.array([(cond.value(uv + h * e, n, j)[0] - g0) / h for e in np.eye(2)])


def _seed(cond: _Condition, uv0: np.ndarray, o: dict) -> tuple:
    """A first curve point near ``uv0`` and the curve's tangent there, or (None, why)."""
    n, j = cond.closest(uv0, o["n_max"], o["r_local"])
    grad = _gradient(cond, uv0, n, j, o["h"])
    if not np.all(np.isfinite(grad)) or not np.any(grad):
        return None, "ds-min"
    pt, why = _correct(cond, uv0, _unit(grad), n, j, dict(o, s_max=o["seed_radius"]))
    if pt is None:
        return None, why
    grad = _gradient(cond, pt[0], pt[1], pt[2], o["h"])
    if not np.all(np.isfinite(grad)) or not np.any(grad):
        return None, "ds-min"
    return pt, _unit(np.array([-grad[1], grad[0]]))


def _passes(p0: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
    """Does the step a -> b pass p0 (within a quarter of its length): the curve closed?"""
    seg = b - a
    t = float(np.clip((p0 - a) @ seg / (seg @ seg), 0.0, 1.0))
    return bool(np.linalg.norm(a + t * seg - p0) < 0.25 * np.linalg.norm(seg))


def _inside(uv: np.ndarray, box: np.ndarray) -> bool:
    return bool(np.all(uv >= box[:, 0]) and np.all(uv <= box[:, 1]))


def _half_branch(cond: _Condition, start: tuple, t: np.ndarray, box: np.ndarray, o: dict):
    """Continue from the curve point ``start`` along the unit tangent ``t`` until the box's
    edge, a closed loop, ``max_points``, a step below ``ds_min`` or n above ``n_max``."""
    pts, ds = [start], o["ds"]
    while len(pts) < o["max_points"]:
        last = pts[-1]
        evals = cond.n_evals
        pt, why = _correct(cond, last[0] + ds * t, np.array([-t[1], t[0]]), last[5], last[2],
                           dict(o, s_max=ds))  # fmt: skip
        ok = pt is not None
        if ok:
            sec = pt[0] - last[0]
            ok = np.linalg.norm(sec) > 0 and float(_unit(sec) @ t) >= np.cos(o["max_angle"])
        if not ok:
            if why == "n-max":
                return pts, why
            ds *= 0.5
            if ds < o["ds_min"]:
                return pts, "ds-min"
            continue
        if not _inside(pt[0], box):  # step closer to the edge, down to 1 % of the first ds
            if ds < 0.02 * o["ds"]:
                return pts, "box"
            ds *= 0.5
            continue
        t = _unit(pt[0] - last[0])
        pts.append(pt)
        if len(pts) > 3 and _passes(pts[0][0], last[0], pt[0]):
            return pts, "closed"
        if cond.n_evals - evals <= 8:
            ds = min(1.5 * ds, o["ds_max"])
    return pts, "max-points"


def trace_manifold(
    crossings: Callable[[np.ndarray, int], np.ndarray],
    saddles: list[LocalSaddle],
    seeds: Any,
    box: Any,
    *,
    period: int = 1,
    ds: float = 1e-3,
    ds_min: float = 1e-7,
    ds_max: float | None = None,
    tol: float = 1e-11,
    r_local: float = 1e-4,
    n_max: int = 30,
    max_points: int = 400,
    max_angle: float = 0.3,
    seed_radius: float | None = None,
    skip_radius: float | None = None,
) -> dict[str, Any]:
    """Trace the zero set of g_n(p) = w . (P^n(p) - x*) in a plane (the stable manifold).

    Parameters
    ----------
    crossings : callable
        ``crossings(uv, n)`` -> (m, n, d): the images P^1 .. P^n (section
        coordinates; NaN where the map failed) of the plane points uv (m, 2).
    saddles : list of LocalSaddle
        The saddle orbit's points with their unstable eigenvectors (:func:`local_saddles`).
    seeds : array_like (k, 2)
        Plane points near the curve; each is corrected onto it (along the
        gradient of g_n, within ``seed_radius``) and traced both ways.
    box : array_like (2, 2)
        [[u_min, u_max], [v_min, v_max]]: tracing stops at its edge.
    period : int
        p of the orbit: n moves in steps of p.
    ds, ds_min, ds_max : float
        First, smallest and largest step along the curve (plane units).
    tol : float
        Bracket length of the corrector (plane units).
    r_local : float
        Radius (max norm, section units) of the neighbourhood of x* in which P^n must land.
    n_max : int
        Largest n.
    max_points : int
        Points per half-branch.
    max_angle : float
        Largest turn (radians) between consecutive secants; a larger one halves ds.
    seed_radius, skip_radius : float
        Largest correction of a seed (default 10 ds); a seed whose corrected
        point is closer than ``skip_radius`` (default ds / 100) to a curve already
        traced is skipped (the plane may hold many pieces of W^s close together:
        the preimages of different order n).

    Returns
    -------
    dict with ``uv`` (m, 2), ``branch``, ``n``, ``target``, ``residual``,
    ``distance`` (m,), ``branch_status`` (list), ``seed_status`` (list: "traced",
    "skipped" or why the seed could not be corrected) and ``n_evals``.
    """
    box = np.asarray(box, dtype=float)
    o = dict(ds=ds, ds_min=ds_min, ds_max=ds_max or 20 * ds, tol=tol, r_local=r_local,
             n_max=int(n_max), max_points=int(max_points), max_angle=max_angle,
             seed_radius=seed_radius or 10 * ds, h=max(64 * tol, 1e-3 * ds))  # fmt: skip
    cond = _Condition(crossings, saddles, int(period))
    branches, status, seed_status = _trace_seeds(cond, seeds, box, o, skip_radius or 1e-2 * ds)
    return _collect(branches, status, seed_status, cond.n_evals)


def _trace_seeds(cond: _Condition, seeds: Any, box: np.ndarray, o: dict, skip: float) -> tuple:
    """Correct each seed onto the curve and trace it both ways: (branches, why each
    ended, what became of each seed)."""
    branches: list = []
    status: list = []
    seed_status: list = []  # "traced", "skipped" or why the seed could not be corrected
    for uv0 in np.atleast_2d(np.asarray(seeds, dtype=float)):
        start, t = _seed(cond, uv0, o)
        if start is None:
            seed_status.append(t)
            continue
        if branches and _near_any(branches, start[0], skip):
            seed_status.append("skipped")  # its curve is traced already
            continue
        seed_status.append("traced")
        for sign in (1.0, -1.0):
            pts, why = _half_branch(cond, start, sign * t, box, o)
            branches.append(pts if sign > 0 else pts[1:])
            status.append(why)
            if why == "closed":  # the whole loop: no other half
                break
    return branches, status, seed_status


def _near_any(branches: list, uv: np.ndarray, radius: float) -> bool:
    """Is uv within ``radius`` of a traced branch (of its polyline)?"""
    q = uv[None]
    return any(_polyline_distance(q, np.array([p[0] for p in b]))[0] < radius for b in branches)


def _polyline_distance(q: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Distance of the points q (k, 2) to the polyline through c (m, 2) (a point if m = 1)."""
    if len(c) == 1:
        return np.linalg.norm(q - c[0], axis=1)
    a, seg = c[:-1], c[1:] - c[:-1]
    t = np.einsum("ksd,sd->ks", q[:, None, :] - a[None], seg) / np.maximum(
        np.einsum("sd,sd->s", seg, seg), 1e-300
    )
    proj = a[None] + np.clip(t, 0.0, 1.0)[..., None] * seg[None]
    return np.min(np.linalg.norm(q[:, None, :] - proj, axis=2), axis=1)


def _collect(branches: list, status: list, seed_status: list, n_evals: int) -> dict:
    rows = [(k, *p) for k, b in enumerate(branches) for p in b]
    return {
        "uv": np.array([r[1] for r in rows]).reshape(-1, 2),
        "branch": np.array([r[0] for r in rows], dtype=int),
        "n": np.array([r[2] for r in rows], dtype=int),
        "target": np.array([r[3] for r in rows], dtype=int),
        "residual": np.abs(np.array([r[4] for r in rows], dtype=float)),
        "distance": np.array([r[5] for r in rows], dtype=float),
        "branch_status": status,
        "seed_status": seed_status,
        "n_evals": n_evals,
    }
