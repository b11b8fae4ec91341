"""Seeds for the stable-manifold tracer from a saddle alone: a scan of g_n over a grid.

:func:`scan_seeds` evaluates the manifold condition of
:mod:`stickslip_fast.analysis.basins_manifold`,

    g_n(p) = w . (P^n(p) - x*_j),     ||P^n(p) - x*_j|| <= r,

at every node of a grid over the plane for n = 1 .. ``n_max``, and looks for
grid edges (neighbouring nodes along either axis) across which g_n changes sign
while the images of both ends lie within ``r_scan`` of the same saddle point
x*_j at the same n. Such an edge straddles the zero set of g_n: the root along
the edge is found by the Illinois rule, and then n is raised (by the period)
until the image of the root lies within ``r_local`` of x*_j (the root moved
along the edge each time), which is the tracer's own condition. These roots are
the seeds; :func:`~stickslip_fast.analysis.basins_manifold.trace_manifold`
traces each (skipping those on a curve already traced).

The sign change can only find a piece of W^s whose two sides leave the saddle
along opposite branches of its unstable manifold, and only where both sides'
images come within ``r_scan`` at the same crossing; a piece thinner than a grid
cell (a tongue bounded by two pieces of W^s, with the same sign of g on both
outer sides) is not seen. ``closest`` (per node: the smallest distance of its
images to the saddle orbit) says how near the grid came.

Pure NumPy: the map enters only as ``crossings(uv, n)``, as for the tracer.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .basins_manifold import LocalSaddle, _Condition, _illinois, _root_on_line

__all__ = ["scan_seeds", "check_axis"]

#: What became of a sign-change edge (``scan_seeds(...)["edge_status"]``).
EDGE_STATUSES = ("seed", "no-root", "n-max", "outside")


def check_axis(name: str, g: Any) -> np.ndarray:
    """``g`` as a 1-D float array of at least two strictly increasing finite values.

    Raises
    ------
    ValueError
        Naming ``name`` otherwise.
    """
    a = np.asarray(g, dtype=float)
    if a.ndim != 1 or a.size < 2 or not np.all(np.isfinite(a)) or not np.all(np.diff(a) > 0):
        raise ValueError(
            f"{name} must be at least two strictly increasing finite values, got {g!r}"
        )
    return a


def _check_numbers(**kw: Any) -> None:
    """ValueError naming the first of ``period``, ``n_max`` (positive integers) or the
    radii and tolerance (positive, finite) that is not."""
    for name, val in kw.items():
        if name in ("period", "n_max"):
            if int(val) != val or int(val) < 1:
                raise ValueError(f"{name} must be a positive integer, got {val!r}")
        elif not (np.isfinite(val) and val > 0):
            raise ValueError(f"{name} must be positive and finite, got {val!r}")


def _node_values(cond: _Condition, uv: np.ndarray, n_max: int) -> tuple:
    """(g, dist, stable) of every node, each (k, n_max, p): g_n, ||P^n - x*_j|| and the
    stable part ||P^n - x*_j - g_n v_j|| (NaN, inf, inf where the map failed)."""
    y = np.asarray(cond.crossings(uv, int(n_max)), dtype=float)  # (k, n_max, d)
    cond.n_evals += len(uv)
    g = np.stack([(y - s.point) @ s.left for s in cond.saddles], axis=-1)
    d = np.stack([np.max(np.abs(y - s.point), axis=-1) for s in cond.saddles], axis=-1)
    st = np.stack(
        [np.max(np.abs(y - s.point - g[..., k, None] * s.right), axis=-1)
         for k, s in enumerate(cond.saddles)], axis=-1,
    )  # fmt: skip
    bad = ~np.isfinite(g) | ~np.isfinite(d) | ~np.isfinite(st)
    return np.where(bad, np.nan, g), np.where(bad, np.inf, d), np.where(bad, np.inf, st)


def _sign_edges(g: np.ndarray, st: np.ndarray, shape: tuple, r_scan: float) -> list:
    """Edges (a, b, n, j) (node indices, 1-based n) with a sign change of g_n at x*_j and
    the stable parts of both images within ``r_scan``; the smallest n (then j) of each."""
    idx = np.arange(shape[0] * shape[1]).reshape(shape)
    pairs = np.concatenate([
        np.stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()], 1),  # along the second axis
        np.stack([idx[:-1, :].ravel(), idx[1:, :].ravel()], 1),  # along the first axis
    ])  # fmt: skip
    a, b = pairs[:, 0], pairs[:, 1]
    with np.errstate(invalid="ignore"):
        ok = (st[a] <= r_scan) & (st[b] <= r_scan) & (np.sign(g[a]) * np.sign(g[b]) < 0)
    ok = ok.reshape(len(pairs), -1)  # (edge, n * p + j)
    hit = np.flatnonzero(ok.any(axis=1))
    first = np.argmax(ok[hit], axis=1)
    p = g.shape[2]
    return [(int(a[e]), int(b[e]), int(f // p) + 1, int(f % p)) for e, f in zip(hit, first)]


def _edge_root(cond: _Condition, ua, ub, n: int, j: int, fa, fb, o: dict) -> tuple:
    """The root of g_n on the edge ua -> ub, with n raised until its image is within
    ``r_local``: ((uv, n, g, dist), "seed") or (None, why)."""
    e = ub - ua
    length = float(np.linalg.norm(e))
    e = e / length
    r = _illinois(cond, ua, e, n, j, (0.0, fa), (length, fb), o["tol"])
    if r is None or not np.isfinite(r[1]):
        return None, "no-root"
    q, g, dist = ua + r[0] * e, r[1], r[2]
    while dist > o["r_local"]:
        n += cond.period
        if n > o["n_max"]:
            return None, "n-max"
        r = _root_on_line(cond, q, e, n, j, length, o["tol"])
        if r is None:
            return None, "no-root"
        q, g, dist = q + r[0] * e, r[1], r[2]
    if not (np.all(q >= o["box"][:, 0]) and np.all(q <= o["box"][:, 1])):
        return None, "outside"
    return (q, n, g, dist), "seed"


def scan_seeds(
    crossings: Callable[[np.ndarray, int], np.ndarray],
    saddles: list[LocalSaddle],
    g1: Any,
    g2: Any,
    *,
    period: int = 1,
    n_max: int = 30,
    r_scan: float = 1e-2,
    r_local: float = 1e-4,
    tol: float = 1e-11,
) -> dict[str, Any]:
    """Seeds on the stable manifold of a saddle from a scan of g_n over a grid.

    Parameters
    ----------
    crossings : callable
        ``crossings(uv, n)`` -> (m, n, d): the images P^1 .. P^n of the plane
        points uv (m, 2), NaN where the map failed (as for :func:`trace_manifold`).
    saddles : list of LocalSaddle
        The saddle orbit's points (:func:`~stickslip_fast.analysis.basins_manifold.local_saddles`).
    g1, g2 : array_like
        The grid's axes (strictly increasing); node (i, k) is (g1[i], g2[k]).
    period : int
        p of the orbit: n is raised in steps of p.
    n_max : int
        Largest n scanned (every node is mapped n_max times) and reached by the
        refinement of a root.
    r_scan : float
        Radius (max norm, section units) within which the images of both ends of
        an edge must lie for a sign change of g_n to count.
    r_local : float
        Radius within which the image of a seed must lie (the tracer's ``r_local``).
    tol : float
        Bracket length of the root on an edge (plane units).

    Returns
    -------
    dict with ``uv`` (k, 2) the seeds, ``n``, ``target``, ``residual`` (``|g_n|``),
    ``distance`` (k,) at each; ``edges`` (e, 2, 2) the sign-change edges' ends,
    ``edge_n``, ``edge_target`` (e,) the (n, j) of their sign change and
    ``edge_status`` (list: "seed", or why none came of it: "no-root", "n-max",
    "outside"); ``closest`` (len(g1), len(g2)) the smallest distance of a node's
    images to the saddle orbit; ``n_evals`` (evaluations of P^n, a node counting one).

    Raises
    ------
    ValueError
        Naming the argument: ``g1``/``g2`` not increasing, ``n_max`` or ``period``
        below 1, ``r_scan``, ``r_local`` or ``tol`` not positive.
    """
    g1, g2 = check_axis("g1", g1), check_axis("g2", g2)
    _check_numbers(period=period, n_max=n_max, r_scan=r_scan, r_local=r_local, tol=tol)
    cond = _Condition(crossings, saddles, int(period))
    uu, vv = np.meshgrid(g1, g2, indexing="ij")
    nodes = np.stack([uu.ravel(), vv.ravel()], axis=1)
    g, d, st = _node_values(cond, nodes, int(n_max))
    box = np.array([[g1[0], g1[-1]], [g2[0], g2[-1]]])
    o = dict(tol=float(tol), r_local=float(r_local), n_max=int(n_max), box=box)
    edges, seeds, status = [], [], []
    for a, b, n, j in _sign_edges(g, st, uu.shape, float(r_scan)):
        fa, fb = (g[a, n - 1, j], d[a, n - 1, j]), (g[b, n - 1, j], d[b, n - 1, j])
        pt, why = _edge_root(cond, nodes[a], nodes[b], n, j, fa, fb, o)
        edges.append((nodes[a], nodes[b], n, j))
        status.append(why)
        if pt is not None:
            seeds.append((*pt, j))
    return {
        "uv": np.array([s[0] for s in seeds]).reshape(-1, 2),
        "n": np.array([s[1] for s in seeds], dtype=int),
        "target": np.array([s[4] for s in seeds], dtype=int),
        "residual": np.abs(np.array([s[2] for s in seeds], dtype=float)),
        "distance": np.array([s[3] for s in seeds], dtype=float),
        "edges": np.array([[e[0], e[1]] for e in edges]).reshape(-1, 2, 2),
        "edge_n": np.array([e[2] for e in edges], dtype=int),
        "edge_target": np.array([e[3] for e in edges], dtype=int),
        "edge_status": status,
        "closest": np.min(d, axis=(1, 2)).reshape(uu.shape),
        "n_evals": cond.n_evals,
    }
