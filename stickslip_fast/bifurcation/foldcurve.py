"""Curves of codim-1 points in two parameters by a minimally augmented system.

For a map's fixed points G(z, l1, l2) = P(z) - z = 0 (or an ODE's equilibria, G = f), a
fold (a multiplier at +1) is where M = D_z G is singular, a period-doubling where
M = D_z G + 2 I is. The test function g comes from the bordered system

    [ M    b ] [v]   [0]          [ M^T  c ] [w]   [0]
    [ c^T  0 ] [g] = [1],         [ b^T  0 ] [.] = [1],

(b, c: the left and right null vectors of M at the start), g = 0 exactly where M is
singular, and its gradient is dg/dx_k = -w^T (dM/dx_k) v. The second derivatives need no
difference of the map: dM/dx_k v is the derivative along v of the k-th column of D G,
(D G(x + h v) - D G(x - h v)) / 2h, two more Jacobian evaluations per point. The curve
F(z, l1, l2) = (G, g) = 0 is followed by :func:`.arclength.pseudo_arclength` in
x = (z, l1, l2), with l2 the "lambda" its bounds apply to.

Codim-2 points on a fold curve: where the tangent's l2 component changes sign the curve
turns back in l2 (an "extremum": on one side of it, at fixed l2, the two folds of a
one-parameter branch meet and vanish); where both parameter components vanish there the
curve has a "cusp" (the fold's quadratic coefficient vanishes: x' = a + b x - x^3 at
a = b = 0).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np

from ..base.threads import run_concurrently
from .arclength import pseudo_arclength
from .corrector import _correct, _tangent

#: Kinds of codim-1 curves :func:`follow_curve` continues (the shift of M = D_z G + shift I).
CURVE_KINDS = {"fold": 0.0, "period-doubling": 2.0}

#: A located sign change of a parameter component of the tangent is a cusp where the
#: tangent's parameter components are both below this (it is a unit vector).
CUSP_SPEED = 1e-3


def border(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(b, c): the left and right singular vectors of M's smallest singular value."""
    U, _, Vt = np.linalg.svd(M)
    return U[:, -1].copy(), Vt[-1].copy()


def _bordered(M, b, c):
    n = M.shape[0]
    K = np.zeros((n + 1, n + 1))
    K[:n, :n] = M
    K[:n, n] = b
    K[n, :n] = c
    rhs = np.zeros(n + 1)
    rhs[-1] = 1.0
    sol = np.linalg.solve(K, rhs)
    solT = np.linalg.solve(K.T, rhs)
    return sol[:n], solT[:n], float(sol[n])


def central_differences(base: Callable, x: np.ndarray, directions: list[np.ndarray], n_z: int,
                        h: float, norm: float) -> list[np.ndarray] | None:  # fmt: skip
    """DG(x + dx) - DG(x - dx) for each direction, dx = h direction / norm in the first
    ``n_z`` coordinates (times norm / (2 h): DG's derivative along it), or None where
    ``base`` fails anywhere. The evaluations are independent and run side by side
    (:func:`~stickslip_fast.base.threads.run_concurrently`)."""
    shifts = []
    for d in directions:
        dx = np.zeros_like(x)
        dx[:n_z] = h * d / norm
        shifts += [x + dx, x - dx]
    out = run_concurrently([functools.partial(base, y) for y in shifts])
    if not all(o[0] for o in out):
        return None
    return [out[k][2] - out[k + 1][2] for k in range(0, len(out), 2)]


def central_difference(base: Callable, x: np.ndarray, direction: np.ndarray, n_z: int,
                       h: float, norm: float):  # fmt: skip
    """:func:`central_differences` along one direction. Shared by the fold/PD, NS and SB
    test functions."""
    diffs = central_differences(base, x, [direction], n_z, h, norm)
    return None if diffs is None else diffs[0]


def augmented(base: Callable, n_z: int, kind: str, b: np.ndarray, c: np.ndarray, h: float,
              scale: float = 1.0):  # fmt: skip
    """The evaluator of F = (G, scale g) for :func:`pseudo_arclength`, from ``base``.

    ``base(x)`` -> (ok, G (n_z,), DG (n_z x (n_z + 2)), A) at x = (z, l1, l2): the
    residual, its Jacobian in (z, l1, l2), and the map's Jacobian (whatever the
    spectrum function wants). ``h``: the step of the directional difference along v.
    ``scale``: 1 / |grad g| at the start, so that the corrector's tolerance on the test
    function is a distance (near a sharp fold of Fig. 6, |grad g| ~ 1e6).

    The evaluator keeps the borders, the scale and the last bordered solutions (v, w)
    in ``evaluate.state``, which :func:`refresh_borders` reads and updates (an NS
    curve's evaluator, :func:`.nscurve.ns_augmented`, keeps the same record).
    """
    shift = CURVE_KINDS[kind]
    eye = np.eye(n_z)
    state = dict(b=b, c=c, scale=scale, v=None, w=None, rows=1)

    def evaluate(x):
        ok, G, DG, A = base(x)
        if not ok:
            return False, None, None, None
        try:
            v, w, g = _bordered(DG[:, :n_z] + shift * eye, state["b"], state["c"])
        except np.linalg.LinAlgError:
            return False, None, None, None
        state["v"], state["w"] = v, w
        nv = float(np.linalg.norm(v))
        diff = central_difference(base, x, v, n_z, h, nv)
        if diff is None:
            return False, None, None, None
        grad = -(w @ diff) * (nv / (2 * h))
        sc = state["scale"]
        return True, np.r_[G, sc * g], np.vstack([DG, sc * grad]), A

    evaluate.state = state
    return evaluate


#: The borders are refreshed once the null vectors have turned more than 60 degrees
#: away from them: c . v = 1 (the bordered system's last row) with |c| = 1, so the
#: angle's cosine is 1 / |v|.
BORDER_DRIFT = 2.0


def refresh_borders(evaluate: Callable, x: np.ndarray) -> bool:
    """New borders from the null vectors at ``x``, where they have drifted from the old.

    Real (fold, period-doubling) or complex (Neimark-Sacker) borders alike. Along a
    long curve the singular vectors of M turn; where one comes near to
    orthogonal to its border the bordered matrix becomes singular and the corrector
    fails (MatCont and BifurcationKit.jl adapt their borders for the same reason).
    ``evaluate`` (from :func:`augmented`) must have been called last at or near ``x``
    (the corrector ends at the point it accepts; locating a codim-2 point between two
    points evaluates between them). When |v| or |w| exceeds
    :data:`BORDER_DRIFT`, the borders become w / |w| and v / |v| and the scale is
    taken again (one more evaluation); otherwise nothing changes, so a curve that
    never drifts that far is computed as with fixed borders. Returns True if
    refreshed.
    """
    st = evaluate.state
    v, w = st["v"], st["w"]
    if v is None or max(np.linalg.norm(v), np.linalg.norm(w)) <= BORDER_DRIFT:
        return False
    st["b"], st["c"] = w / np.linalg.norm(w), v / np.linalg.norm(v)
    st["scale"] = 1.0
    ok, _, DF, _ = evaluate(x)
    if ok:  # the test function's rows: one (fold, period-doubling), two (NS: Re g, Im g)
        st["scale"] = 1.0 / max(float(np.linalg.norm(DF[-st["rows"] :])), 1e-300)
    return True


def curve_tests(A, t: np.ndarray) -> dict[str, float]:
    """Test functions along a curve: the tangent's components in l1 and l2."""
    return {"turn-1": float(t[-2]), "turn-2": float(t[-1])}


def _others(values: np.ndarray, target: complex, k: int = 1) -> np.ndarray:
    """``values`` without the ``k`` entries nearest ``target`` (the critical ones)."""
    order = np.argsort(np.abs(values - target), kind="stable")
    return values[order[k:]]


def _product(values: np.ndarray) -> float:
    """prod(values).real, as +-1 or +-inf times its magnitude (only its sign is used)."""
    return float(np.prod(values).real) if values.size else math.nan


#: The codim-2 points on the curves of maps' fixed points: the remaining multipliers'
#: products prod(mu - 1) and prod(mu + 1) (a complex pair contributes |mu -+ 1|^2 > 0, so
#: they change sign only where a real multiplier passes +1 or -1).
MAP_CODIM2 = {"fold": (("1:1", 1.0), ("fold-flip", -1.0)),
              "period-doubling": (("fold-flip", 1.0), ("1:2", -1.0))}  # fmt: skip


def map_curve_tests(kind: str) -> Callable:
    """Tests along a fold (+1) or period-doubling (-1) curve of a map's fixed points: the
    turns of :func:`curve_tests` and the second multiplier at +1 or -1
    (:data:`MAP_CODIM2`; A is the map's Jacobian)."""
    critical = 1.0 if kind == "fold" else -1.0

    def tests(A, t):
        rest = _others(np.linalg.eigvals(A), critical)
        out = curve_tests(A, t)
        for name, target in MAP_CODIM2[kind]:
            out[name] = _product(rest - target)
        return out

    return tests


def follow_curve(
    base: Callable,
    x0: np.ndarray,
    kind: str,
    direction: float,
    bounds2: tuple[float, float],
    *,
    h: float = 1e-7,
    tests: Callable | None = None,
    borders: str = "adapt",
    **settings,
):
    """Follow a fold or period-doubling curve through x0 = (z, l1, l2), a point near it.

    ``tests``: the codim-2 test functions (default :func:`map_curve_tests` of ``kind``).
    ``borders``: "adapt" (refreshed where the null vectors have turned away from them,
    :func:`refresh_borders`) or "fixed" (those of the start throughout).
    ``settings``: ds, ds_min, ds_max, max_points, tol (required), spectrum, locate_tol of
    :func:`run_curve`. Returns (xs, mults, codim2, status, x_start) as :func:`run_curve`.
    """
    if borders not in ("adapt", "fixed"):
        raise ValueError(f'borders must be "adapt" or "fixed", got {borders!r}')
    n_z = x0.size - 2
    ok, G, DG, _ = base(x0)
    if not ok:
        return None, None, [], "start-failed", x0
    b, c = border(DG[:, :n_z] + CURVE_KINDS[kind] * np.eye(n_z))
    ok, _, DF, _ = augmented(base, n_z, kind, b, c, h)(x0)
    if not ok:
        return None, None, [], "start-failed", x0
    evaluate = augmented(base, n_z, kind, b, c, h, 1.0 / max(float(np.linalg.norm(DF[-1])), 1e-300))
    if borders == "adapt":
        evaluate.after_step = lambda x: refresh_borders(evaluate, x)
    return run_curve(evaluate, x0, direction, bounds2, tests=tests or map_curve_tests(kind),
                     **settings)  # fmt: skip


def _never_stop(after_step, watch=None):
    """``after_step`` (and ``watch(x, walk)``) as :func:`pseudo_arclength`'s per-point
    ``stop`` hook, which never stops."""
    if after_step is None and watch is None:
        return None

    def stop(x, data, walk):
        if after_step is not None:
            after_step(x)
        if watch is not None:
            watch(x, walk)
        return False

    return stop


def run_curve(
    evaluate: Callable,
    x0: np.ndarray,
    direction: float,
    bounds2: tuple[float, float],
    *,
    ds: float,
    ds_min: float,
    ds_max: float,
    max_points: int,
    tol: float,
    tests: Callable = curve_tests,
    spectrum: Callable | None = None,
    locate_tol: float = 1e-9,
    watch: Callable | None = None,
):
    """Continue the augmented system ``evaluate`` from x0 (corrected first at fixed l2, the
    last coordinate; l1 is the one before it) and name the codim-2 points.

    ``evaluate.after_step(x)``, where the evaluator has one (not None), is called at every
    accepted point after its tests (the borders' refresh of :func:`follow_curve`).
    ``watch``, optional: ``watch.start(evaluate, x_start)`` before the walk and
    ``watch(x, walk)`` at every accepted point after that; its ``found`` list of
    (kind, index, x) is added to the codim-2 points (:class:`.curve.StickWatch`).

    Sign changes of "turn-1"/"turn-2" are a "cusp" where both parameter components of the
    tangent are below :data:`CUSP_SPEED`, else "turn-2" is an "extremum" (and "turn-1"
    nothing); every other test's sign change is a codim-2 point of the test's name.
    Returns (xs, mults, codim2, status, x_start) with codim2 a list of (kind, index, x);
    ``status`` as :func:`pseudo_arclength`'s, or "start-failed" (x0 could not be corrected).
    """
    e2 = np.zeros_like(x0)
    e2[-1] = 1.0
    okc, x_start, _, _ = _correct(evaluate, x0, e2, x0, tol, 12)
    if not okc:
        return None, None, [], "start-failed", x0
    if watch is not None:
        watch.start(evaluate, x_start)
    xs, mults, bifs, status = pseudo_arclength(
        evaluate, x_start, direction, bounds2, ds=ds, ds_min=ds_min, ds_max=ds_max,
        max_points=max_points, tol=tol, locate_tol=locate_tol, tests=tests,
        spectrum=spectrum, stop=_never_stop(getattr(evaluate, "after_step", None), watch),
    )  # fmt: skip
    codim2 = [] if watch is None else list(watch.found)
    for name, _, index, x in bifs:
        if name not in ("turn-1", "turn-2"):
            codim2.append((name, index, x))
            continue
        ok, _, DF, _ = evaluate(x)
        t = _tangent(DF, xs[index + 1] - xs[index]) if ok else np.full(x.size, np.nan)
        if abs(t[-1]) < CUSP_SPEED and abs(t[-2]) < CUSP_SPEED:
            codim2.append(("cusp", index, x))
        elif name == "turn-2":
            codim2.append(("extremum", index, x))
    # a cusp shows as a sign change of one component and a double zero of the other:
    # keep one entry per place
    out = []
    for entry in sorted(codim2, key=lambda e: e[1]):
        if not out or entry[0] != out[-1][0] or abs(entry[1] - out[-1][1]) > 1:
            out.append(entry)
    return xs, mults, out, status, x_start
