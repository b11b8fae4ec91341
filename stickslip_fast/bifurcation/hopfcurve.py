"""Curves of folds and Hopf points of an ODE's equilibria in two parameters.

The equilibria solve f(y, l1, l2) = 0 with Jacobian J = D_y f. A fold curve adds the
test function of :mod:`.foldcurve` (M = J singular). A Hopf point (eigenvalues +-i omega)
is where M = J^2 + kappa I, kappa = omega^2, has a two-dimensional kernel (Govaerts,
Guckenheimer and Khibnik; MatCont's "bordered J^2" formulation). With borders B, C (n x 2,
the singular vectors of M's two smallest singular values at the start), the bordered system

    [ M    B ] [V]   [0 ]          [ M^T  C ] [W]   [0 ]
    [ C^T  0 ] [G] = [I2],         [ B^T  0 ] [.] = [I2],

gives a 2 x 2 matrix G that vanishes where M's rank drops by two; two of its entries (the
pair with the best-conditioned Jacobian at the start) join f = 0, in x = (y, kappa, l1, l2).
Their gradient is dG_ij / dx_k = -W_i^T (dM / dx_k) V_j with dM / dx_k V = (dJ / dx_k)(J V)
+ J (dJ / dx_k) V, and (dJ / dx_k) u is the k-th column of the derivative of [J | f_l1 |
f_l2] along u: four directional differences per point (u = V_1, V_2, J V_1, J V_2).
kappa < 0 continues the curve as a neutral saddle (eigenvalues +-sqrt(-kappa)).

Codim-2 points. On a fold curve: "bogdanov-takens" (the other eigenvalues' product
changes sign: a second zero eigenvalue), "zero-hopf" (the product of the real parts of
the other complex pairs changes sign). On a Hopf curve: "bogdanov-takens" (kappa = 0),
"zero-hopf" (the product of the eigenvalues other than the pair changes sign), "bautin"
(the first Lyapunov coefficient :func:`first_lyapunov` changes sign).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .detection import _eigs_by_real_part
from .foldcurve import BORDER_DRIFT, _others, _product, curve_tests, follow_curve, run_curve


# ------------------------------------------------------------ Lyapunov coefficient
def first_lyapunov(jac: Callable, y: np.ndarray, J: np.ndarray, omega: float,
                   h: float = 1e-4) -> float:  # fmt: skip
    """The first Lyapunov coefficient l1 of a Hopf point (eigenvalues +-i omega of J).

    Kuznetsov's formula (Elements of Applied Bifurcation Theory, (3.20)) with J q =
    i omega q, J^T p = -i omega p, <q, q> = <p, q> = 1:

        l1 = Re[<p, C(q, q, q*)> - 2 <p, B(q, J^-1 B(q, q*))>
                + <p, B(q*, (2 i omega I - J)^-1 B(q, q))>] / (2 omega),

    B and C (the second and third derivatives of f) from central differences of
    ``jac`` (y -> J) along Re q, Im q and their sum and difference, step ``h``. l1 < 0:
    supercritical (a stable cycle is born), l1 > 0: subcritical.
    """
    n = y.size
    eye = np.eye(n)
    q = np.linalg.svd(J - 1j * omega * eye)[2][-1].conj()
    q /= np.linalg.norm(q)
    p = np.linalg.svd(J.T + 1j * omega * eye)[2][-1].conj()
    p /= np.conj(np.vdot(p, q))
    a, b = q.real, q.imag

    def diffs(u):
        jp, jm = jac(y + h * u), jac(y - h * u)
        return (jp - jm) / (2 * h), (jp - 2 * J + jm) / (h * h)

    d1a, d2a = diffs(a)
    d1b, d2b = diffs(b)
    d2ab = 0.25 * (diffs(a + b)[1] - diffs(a - b)[1])
    dq, dqbar = d1a + 1j * d1b, d1a - 1j * d1b  # B(q, .), B(q*, .)
    c = (d2a - d2b + 2j * d2ab) @ q.conj()  # C(q, q, q*)
    h11 = np.linalg.solve(J, dq @ q.conj())
    h20 = np.linalg.solve(2j * omega * eye - J, dq @ q)
    val = np.vdot(p, c) - 2 * np.vdot(p, dq @ h11) + np.vdot(p, dqbar @ h20)
    return float(val.real / (2 * omega))


# ------------------------------------------------------------------- test functions
def _pair_real_parts(values: np.ndarray) -> float:
    """Product of Re over the complex pairs (upper halves) of ``values``; NaN without one."""
    upper = values[values.imag > 1e-12 * np.maximum(1.0, np.abs(values))]
    return float(np.prod(upper.real)) if upper.size else math.nan


def equilibrium_fold_tests(J, t):
    """Tests along a fold curve of equilibria (A = J): the turns, "bogdanov-takens" and
    "zero-hopf"."""
    rest = _others(np.linalg.eigvals(J), 0.0)
    return {**curve_tests(J, t), "bogdanov-takens": _product(rest),
            "zero-hopf": _pair_real_parts(rest)}  # fmt: skip


@dataclass
class HopfData:
    """What the Hopf curve's evaluator hands to its tests and spectrum (as ``A``)."""

    J: np.ndarray
    kappa: float
    y: np.ndarray
    jac: Callable  # y -> J at this point's parameters
    lyap_step: float


def hopf_tests(d: HopfData, t):
    """Tests along a Hopf curve: the turns, "bogdanov-takens" (kappa), "zero-hopf" and
    "bautin" (the first Lyapunov coefficient; NaN where kappa <= 0)."""
    ev = np.linalg.eigvals(d.J)
    k = d.kappa
    root = math.sqrt(abs(k))
    pair = (1j * root, -1j * root) if k > 0 else (root, -root)
    rest = _others(_others(ev, pair[0]), pair[1])
    lyap = math.nan
    if k > 0:
        lyap = first_lyapunov(d.jac, d.y, d.J, root, d.lyap_step)
    return {**curve_tests(d.J, t), "bogdanov-takens": float(k), "zero-hopf": _product(rest),
            "bautin": lyap}  # fmt: skip


def hopf_spectrum(d: HopfData) -> np.ndarray:
    return _eigs_by_real_part(d.J)


# ------------------------------------------------------------------- the Hopf system
def _bordered2(M, B, C):
    n = M.shape[0]
    K = np.zeros((n + 2, n + 2))
    K[:n, :n], K[:n, n:], K[n:, :n] = M, B, C.T
    rhs = np.zeros((n + 2, 2))
    rhs[n:] = np.eye(2)
    sol = np.linalg.solve(K, rhs)
    solT = np.linalg.solve(K.T, rhs)
    return sol[:n], solT[:n], sol[n:]


class HopfSystem:
    """x = (y, kappa, l1, l2) -> (ok, (f, the chosen entries of G), DF, HopfData).

    ``base(xb)``, xb = (y, l1, l2): (ok, f, [J | f_l1 | f_l2], J). ``entries``: the two
    (i, j) of G enforced, ``scale`` their rows' factors; ``h`` the directional step.
    """

    def __init__(self, base, n, B, C, h, lyap_step, entries=((0, 0), (1, 1)), scale=(1.0, 1.0)):
        self.base, self.n, self.B, self.C, self.h = base, n, B, C, h
        self.lyap_step, self.entries, self.scale = lyap_step, entries, scale
        self.last = None  # (V, W) of the last evaluation, for refresh()

    def refresh(self, x) -> bool:
        """New borders, entries and scales at x (:func:`hopf_system` there) where the
        kernel of J^2 + kappa I has turned from the borders: C^T V = I, so the largest
        singular value of V is 1 / cos of the largest angle between span C and the
        kernel; refreshed where it (or W's) exceeds :data:`.foldcurve.BORDER_DRIFT`, as
        :func:`.foldcurve.refresh_borders`. The last evaluation must be at or near x."""
        if self.last is None:
            return False
        V, W = self.last
        if max(np.linalg.norm(V, 2), np.linalg.norm(W, 2)) <= BORDER_DRIFT:
            return False
        new = hopf_system(self.base, x, self.h, self.lyap_step)
        if new is None:
            return False
        self.B, self.C, self.entries, self.scale = new.B, new.C, new.entries, new.scale
        self.last = None
        return True

    def _along(self, xb, u):
        """D(u): the derivative of [J | f_l1 | f_l2] along (u, 0, 0), or None."""
        nu = float(np.linalg.norm(u))
        if nu == 0.0:
            return np.zeros((self.n, xb.size))
        dx = np.zeros_like(xb)
        dx[: self.n] = self.h * u / nu
        okp, _, DGp, _ = self.base(xb + dx)
        okm, _, DGm, _ = self.base(xb - dx)
        return (DGp - DGm) * (nu / (2 * self.h)) if okp and okm else None

    def gradients(self, x):
        """(ok, f, DG, J, G (2x2), gradients (2, 2, n + 3) over x)."""
        n = self.n
        xb = np.r_[x[:n], x[n + 1 :]]
        ok, f, DG, J = self.base(xb)
        if not ok:
            return (False,) + (None,) * 5
        try:
            V, W, G = _bordered2(J @ J + x[n] * np.eye(n), self.B, self.C)
        except np.linalg.LinAlgError:
            return (False,) + (None,) * 5
        self.last = (V, W)
        D = [self._along(xb, u) for u in (V[:, 0], V[:, 1], J @ V[:, 0], J @ V[:, 1])]
        if any(d is None for d in D):
            return (False,) + (None,) * 5
        grads = np.zeros((2, 2, n + 3))
        for i, j in itertools.product(range(2), range(2)):
            g = -(W[:, i] @ D[2 + j] + (J.T @ W[:, i]) @ D[j])
            grads[i, j] = np.r_[g[:n], -W[:, i] @ V[:, j], g[n:]]
        return True, f, DG, J, G, grads

    def __call__(self, x):
        ok, f, DG, J, G, grads = self.gradients(x)
        if not ok:
            return False, None, None, None
        n = self.n
        DF = np.zeros((n + 2, n + 3))
        DF[:n, :n], DF[:n, n + 1 :] = DG[:, :n], DG[:, n:]
        F = np.r_[f, 0.0, 0.0]
        for r, ((i, j), s) in enumerate(zip(self.entries, self.scale)):
            F[n + r], DF[n + r] = s * G[i, j], s * grads[i, j]
        l12 = x[n + 1 :]
        data = HopfData(J, float(x[n]), x[:n].copy(),
                        lambda yy: self.base(np.r_[yy, l12])[2][:, :n], self.lyap_step)  # fmt: skip
        return True, F, DF, data


def hopf_system(base: Callable, x0: np.ndarray, h: float = 1e-7, lyap_step: float = 1e-4):
    """The Hopf curve's evaluator at x0 = (y, kappa, l1, l2) near a Hopf point: borders from
    J^2 + kappa I there, the two entries of G whose gradients (with f's Jacobian) are best
    conditioned, each row divided by its gradient's norm. None if x0 cannot be evaluated."""
    n = x0.size - 3
    ok, _, _, J = base(np.r_[x0[:n], x0[n + 1 :]])
    if not ok:
        return None
    U, _, Vt = np.linalg.svd(J @ J + x0[n] * np.eye(n))
    system = HopfSystem(base, n, U[:, -2:].copy(), Vt[-2:].T.copy(), h, lyap_step)
    ok, f, DG, _, _, grads = system.gradients(x0)
    if not ok:
        return None
    top = np.zeros((n, n + 3))
    top[:, :n], top[:, n + 1 :] = DG[:, :n], DG[:, n:]
    best, choice = -1.0, None
    for pair in itertools.combinations(((0, 0), (0, 1), (1, 0), (1, 1)), 2):
        rows = [grads[i, j] / max(np.linalg.norm(grads[i, j]), 1e-300) for i, j in pair]
        sv = np.linalg.svd(np.vstack([top, *rows]), compute_uv=False)[-1]
        if sv > best:
            best, choice = sv, pair
    system.entries = choice
    system.scale = tuple(1.0 / max(float(np.linalg.norm(grads[i, j])), 1e-300) for i, j in choice)
    return system


def follow_hopf_curve(base: Callable, x0: np.ndarray, direction: float,
                      bounds2: tuple[float, float], *, h: float = 1e-7,
                      lyap_step: float = 1e-4, borders: str = "adapt", **settings):  # fmt: skip
    """Follow a Hopf curve through x0 = (y, kappa, l1, l2), a point near it.

    ``borders``: "adapt" (:meth:`HopfSystem.refresh` after every accepted point) or
    "fixed" (the start's). ``settings``: those of :func:`.foldcurve.run_curve` (ds,
    ds_min, ds_max, max_points, tol required). Returns (xs, eigenvalues, codim2, status,
    x_start) as :func:`.foldcurve.run_curve`, xs in (y, kappa, l1, l2).
    """
    if borders not in ("adapt", "fixed"):
        raise ValueError(f'borders must be "adapt" or "fixed", got {borders!r}')
    system = hopf_system(base, x0, h, lyap_step)
    if system is None:
        return None, None, [], "start-failed", x0
    system.after_step = system.refresh if borders == "adapt" else None
    return run_curve(system, x0, direction, bounds2, tests=hopf_tests, spectrum=hopf_spectrum,
                     **settings)  # fmt: skip


def follow_equilibrium_fold(base: Callable, x0: np.ndarray, direction: float,
                            bounds2: tuple[float, float], *, h: float = 1e-7, **settings):  # fmt: skip
    """Follow a fold curve of equilibria through x0 = (y, l1, l2): :func:`.foldcurve.follow_curve`
    with M = J and the tests :func:`equilibrium_fold_tests`."""
    return follow_curve(base, x0, "fold", direction, bounds2, h=h, tests=equilibrium_fold_tests,
                        spectrum=_eigs_by_real_part, **settings)  # fmt: skip
