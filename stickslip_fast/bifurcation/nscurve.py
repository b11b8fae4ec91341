"""Curves of Neimark-Sacker points of a map's fixed points in two parameters.

A Neimark-Sacker (NS) point of G(z, l1, l2) = P(z) - z = 0 is where the map's Jacobian A
has a pair of multipliers e^{+-i theta}, 0 < theta < pi. The minimally augmented system
keeps theta as an unknown and borders the complex matrix M = A - e^{i theta} I:

    [ M    b ] [v]   [0]          [ M^H  c ] [w]   [0]
    [ c^H  0 ] [g] = [1],         [ b^H  0 ] [.] = [1],

(b, c: M's left and right singular vectors of its smallest singular value at the start).
The complex g vanishes exactly where e^{i theta} is a multiplier; Re g = Im g = 0 join
G = 0 in x = (z, theta, l1, l2), n + 2 equations in n + 3 unknowns. The gradient is
dg/dx_k = -w^H (dA/dx_k) v, and (dA/dx_k) v is the k-th column of the derivative of
D G = [A - I | G_l1 | G_l2] along v = Re v + i Im v: two directional differences, four
Jacobian evaluations per point; dg/dtheta = i e^{i theta} w^H v.

Why this and not the bialternate product or MatCont's bordered A^2 - 2 kappa A + I: the
bialternate product A (.) A - I is of size n(n - 1)/2 and vanishes also at neutral
saddles (real mu1 mu2 = 1), and the A^2 formulation needs a 2 x 2 bordering and
directional differences along four vectors (u = V_1, V_2, A V_1, A V_2); the complex
bordering needs one n + 1 system, two directions, and returns the angle theta itself.
Its price: at a 1:1 or 1:2 resonance (theta -> 0 or pi) the curve in the parameter
plane ends (the parameters are even in theta, resp. theta - pi, and the curve would
retrace itself), where the other two continue as a neutral-saddle curve.

Codim-2 points (sign changes along the curve, located like one-parameter bifurcations):
"1:1" (theta = 0) and "1:2" (theta = pi), where the curve ends (status "1:1" / "1:2");
the strong resonances "1:3" (theta = 2 pi / 3) and "1:4" (theta = pi / 2); "fold-ns"
and "flip-ns" (another multiplier at +1, resp. -1); and the turns of :func:`.foldcurve.run_curve`
("extremum" in l2, "cusp"). The Chenciner point (the NS point's first Lyapunov coefficient
changes sign) is not detected.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .detection import _sorted_eigs
from .foldcurve import _product, central_differences, curve_tests, refresh_borders, run_curve

#: The kind name of an NS curve (as :class:`~.branch.Bifurcation`'s).
NS_KIND = "neimark-sacker"

#: How far past 0 and pi the angle may go (radians): far enough for the steps that
#: bracket a 1:1 or 1:2 point, and a stop to the retrace beyond it.
THETA_MARGIN = 0.3

#: The strong resonances: theta at each (the curve ends at the first two).
RESONANCES = {"1:1": 0.0, "1:2": math.pi, "1:3": 2 * math.pi / 3, "1:4": math.pi / 2}


def ns_border(A: np.ndarray, theta: float) -> tuple[np.ndarray, np.ndarray]:
    """(b, c): the left and right singular vectors of A - e^{i theta} I's smallest singular value."""
    U, _, Vh = np.linalg.svd(A - np.exp(1j * theta) * np.eye(A.shape[0]))
    return U[:, -1].copy(), Vh[-1].conj().copy()


def _bordered(M, b, c):
    n = M.shape[0]
    K = np.zeros((n + 1, n + 1), complex)
    K[:n, :n] = M
    K[:n, n] = b
    K[n, :n] = c.conj()
    rhs = np.zeros(n + 1, complex)
    rhs[-1] = 1.0
    sol = np.linalg.solve(K, rhs)
    solH = np.linalg.solve(K.conj().T, rhs)
    return sol[:n], solH[:n], complex(sol[n])


def ns_augmented(base: Callable, n_z: int, b: np.ndarray, c: np.ndarray, h: float,
                 scale: float = 1.0):  # fmt: skip
    """The evaluator of F = (G, scale Re g, scale Im g) at x = (z, theta, l1, l2) for
    :func:`.arclength.pseudo_arclength`, from ``base`` of :func:`.foldcurve.augmented`
    (at (z, l1, l2)). Its "A" is the pair (A, theta) (for :func:`ns_tests`). Fails
    where theta is more than :data:`THETA_MARGIN` outside [0, pi]. Borders, scale and
    the last (v, w) live in ``evaluate.state``, as in :func:`.foldcurve.augmented`."""
    state = dict(b=b, c=c, scale=scale, v=None, w=None, rows=2)

    def evaluate(x):
        theta = float(x[n_z])
        if not -THETA_MARGIN <= theta <= math.pi + THETA_MARGIN:
            return False, None, None, None
        y = np.r_[x[:n_z], x[n_z + 1 :]]
        ok, G, DG, A = base(y)
        if not ok:
            return False, None, None, None
        e = np.exp(1j * theta)
        try:
            v, w, g = _bordered(A - e * np.eye(n_z), state["b"], state["c"])
        except np.linalg.LinAlgError:
            return False, None, None, None
        state["v"], state["w"] = v, w
        nv = float(np.linalg.norm(v))
        diffs = central_differences(base, y, [v.real, v.imag], n_z, h, nv)
        if diffs is None:
            return False, None, None, None
        cols = [diff * (nv / (2 * h)) for diff in diffs]
        grad_y = -(w.conj() @ (cols[0] + 1j * cols[1]))
        grad = np.r_[grad_y[:n_z], 1j * e * np.vdot(w, v), grad_y[n_z:]]
        sc = state["scale"]
        DF = np.vstack([np.insert(DG, n_z, 0.0, axis=1), sc * grad.real, sc * grad.imag])
        return True, np.r_[G, sc * g.real, sc * g.imag], DF, (A, theta)

    evaluate.state = state
    return evaluate


def ns_tests(At, t: np.ndarray) -> dict[str, float]:
    """Tests along an NS curve: the turns of :func:`.foldcurve.curve_tests`, theta minus
    each resonance's angle (:data:`RESONANCES`), and the products over the other
    multipliers of (mu - 1) ("fold-ns") and (mu + 1) ("flip-ns")."""
    A, theta = At
    mu = np.linalg.eigvals(A)
    # without the pair nearest e^{+-i theta}
    e = np.exp(1j * theta)
    rest = np.delete(mu, [int(np.argmin(np.abs(mu - e))), int(np.argmin(np.abs(mu - e.conj())))])
    if np.argmin(np.abs(mu - e)) == np.argmin(np.abs(mu - e.conj())):  # a real pair (theta ~ 0, pi)
        order = np.argsort(np.abs(mu - e), kind="stable")
        rest = mu[order[2:]]
    out = curve_tests(A, t)
    out.update({k: theta - a for k, a in RESONANCES.items()})
    out["fold-ns"] = _product(rest - 1.0)
    out["flip-ns"] = _product(rest + 1.0)
    return out


def ns_angle(A: np.ndarray) -> float:
    """theta in (0, pi) of the complex multiplier nearest the unit circle (NaN if none)."""
    mu = np.linalg.eigvals(A)
    up = mu[mu.imag > 1e-12 * np.maximum(1.0, np.abs(mu))]
    if not up.size:
        return math.nan
    return float(np.angle(up[np.argmin(np.abs(np.abs(up) - 1.0))]))


def follow_ns_curve(
    base: Callable,
    x0: np.ndarray,
    direction: float,
    bounds2: tuple[float, float],
    *,
    h: float = 1e-7,
    borders: str = "adapt",
    **settings,
):
    """Follow the NS curve through x0 = (z, l1, l2), a point near it.

    ``borders``: "adapt" (refreshed where the complex null vectors have turned away
    from them, :func:`.foldcurve.refresh_borders`) or "fixed" (the start's).
    ``settings``: those of :func:`.foldcurve.run_curve` (ds, ds_min, ds_max, max_points,
    tol). Returns (xs, mults, codim2, status) with xs (k, n + 3) = (z, theta, l1, l2);
    ``status`` as :func:`.foldcurve.run_curve`'s, "1:1" or "1:2" where the curve ended
    at that resonance (its last point), or "no-complex-pair" (the start has none).
    """
    if borders not in ("adapt", "fixed"):
        raise ValueError(f'borders must be "adapt" or "fixed", got {borders!r}')
    n_z = x0.size - 2
    ok, _, _, A = base(x0)
    theta = ns_angle(A) if ok else math.nan
    if not math.isfinite(theta):
        return None, None, [], "start-failed" if not ok else "no-complex-pair"
    x0t = np.r_[x0[:n_z], theta, x0[n_z:]]
    b, c = ns_border(A, theta)
    ok, _, DF, _ = ns_augmented(base, n_z, b, c, h)(x0t)
    if not ok:
        return None, None, [], "start-failed"
    scale = 1.0 / max(float(np.linalg.norm(DF[-2:])), 1e-300)
    evaluate = ns_augmented(base, n_z, b, c, h, scale)
    if borders == "adapt":
        evaluate.after_step = lambda x: refresh_borders(evaluate, x)
    xs, mults, codim2, status, _ = run_curve(
        evaluate, x0t, direction, bounds2, tests=ns_tests,
        spectrum=lambda At: _sorted_eigs(At[0]), **settings,
    )  # fmt: skip
    if xs is None:
        return None, None, [], status
    return _end_at_resonance(evaluate, xs, mults, codim2, status)


def _end_at_resonance(evaluate, xs, mults, codim2, status):
    """Cut the curve at its first 1:1 or 1:2 point (appended as its last point), and drop
    the turns there (the parameters' tangent vanishes where theta reaches 0 or pi).

    The augmented system is singular at these points (the pair is a Jordan block there:
    w^H v = 0, and A - I or A + I is singular), so the located point is not corrected:
    the coordinates are even functions of theta - theta_r, and a quadratic in
    (theta - theta_r)^2 through the last four points before it gives their values at
    theta_r (error ~ (theta - theta_r)^6)."""
    ends = [(i, k) for k, i, _ in codim2 if k in ("1:1", "1:2")]
    if not ends:
        return xs, mults, codim2, status
    i_end, kind = ends[0]
    n_z = xs.shape[1] - 3
    near = xs[max(0, i_end - 3) : i_end + 1]
    d = (near[:, n_z] - RESONANCES[kind]) ** 2
    coef = np.polyfit(d, near, min(2, len(d) - 1))
    x_end = coef[-1].copy()
    x_end[n_z] = RESONANCES[kind]
    ok, _, _, At = evaluate(x_end)
    turn = ("cusp", "extremum")
    keep = [e for e in codim2 if e[1] < i_end and not (e[0] in turn and i_end - e[1] <= 1)]
    keep.append((kind, i_end, x_end))
    mu = _sorted_eigs(At[0]) if ok else np.full(mults.shape[1], np.nan, complex)
    return np.vstack([xs[: i_end + 1], x_end]), np.vstack([mults[: i_end + 1], mu]), keep, kind
