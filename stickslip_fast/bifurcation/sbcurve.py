"""Curves of symmetry-breaking points of in-phase orbits in two parameters.

At a symmetry-breaking point (:mod:`.synchrony`) a transverse multiplier of an in-phase
orbit is +1: the 4 x 4 transverse monodromy Phi_d, less the identity, is singular. With
the in-phase orbit's fixed-point residual G(z, l1, l2) = P(z) - z, the curve is

    F(z, l1, l2) = (G, g) = 0,   g from   [ M_t  b ] [v]   [0]
                                          [ c^T  0 ] [g] = [1],   M_t = Phi_d - I,

the minimally augmented system of :mod:`.foldcurve` with the 4 x 4 matrix M_t in place
of D_z G. Phi_d = (1/2) P^T D P U with U = [u_1 .. u_4], u_j = P e_j - (P e_j)_dx1 / f_dx1 f
(P e_j: e_j on disk 1, -e_j on disk 2; f the field at z), so for the null vector v,

    d(M_t v)/dx_k = (1/2) P^T [ d(D P)/dx_k u + D P du/dx_k ],   u = U v:

the first term is the derivative along u of the k-th column of D G (second derivatives
are symmetric), two more Jacobian evaluations per point as on a fold curve; the second
comes from central differences of the field f, which carries no integration error. The
gradient is dg/dx_k = -w^T d(M_t v)/dx_k.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .detection import _sorted_eigs
from .foldcurve import (
    _bordered,
    border,
    central_difference,
    map_curve_tests,
    refresh_borders,
    run_curve,
)
from .returnmap import SECTION_INDEX, _field
from .synchrony import (
    in_phase_projector,
    monodromy_across,
    pair_matrix,
    project_in_phase,
    section_directions,
)

#: The kind of the curves :func:`follow_sb_curve` follows.
SB_KIND = "symmetry-breaking"

#: Relative step of the central differences of the field in z and the parameters.
FIELD_STEP = 1e-7


def _field_at(system_at, full, x: np.ndarray) -> np.ndarray | None:
    try:
        return _field(system_at(x), full(x))
    except ValueError:  # a parameter outside its range
        return None


def _field_derivatives(system_at, full, x, pair_v, n_x):
    """d(c f)/dx_k for every coordinate k, c = (P v)_dx1 / f_dx1, by central differences
    (columns; None where the field cannot be evaluated)."""
    out = []
    for k in range(n_x):
        dx = np.zeros_like(x)
        dx[k] = FIELD_STEP * max(1.0, abs(float(x[k])))
        fp, fm = _field_at(system_at, full, x + dx), _field_at(system_at, full, x - dx)
        if fp is None or fm is None:
            return None
        cp = pair_v[SECTION_INDEX] / fp[SECTION_INDEX]
        cm = pair_v[SECTION_INDEX] / fm[SECTION_INDEX]
        out.append((cp * fp - cm * fm) / (2.0 * dx[k]))
    return np.column_stack(out)


def sb_augmented(base: tuple[Callable, Callable], system_at: Callable, full: Callable,
                 n_z: int, b: np.ndarray, c: np.ndarray, h: float, scale: float = 1.0):  # fmt: skip
    """The evaluator of F = (G, scale g) on a symmetry-breaking curve.

    ``base``: (the evaluator kept in phase, :func:`.synchrony.project_in_phase`; the
    plain one, whose Jacobian is differenced along u, across the disks), each ``base(x)``
    as for :func:`.foldcurve.augmented` (its fourth output the return map's Jacobian A
    in section coordinates); ``system_at(x)`` and ``full(x)`` give the system
    and the state at x = (z, l1, l2); ``b``, ``c``: the borders (4-vectors). Its fourth
    output is (A, M_t). It keeps ``state`` as :func:`.foldcurve.augmented` does, for
    :func:`.foldcurve.refresh_borders`.
    """
    state = dict(b=b, c=c, scale=scale, v=None, w=None, rows=1)
    in_phase, plain = base

    def evaluate(x):
        ok, G, DG, A = in_phase(x)
        f = _field_at(system_at, full, x) if ok else None
        if f is None:
            return False, None, None, None
        mask = np.arange(f.size) != SECTION_INDEX
        pair = pair_matrix(f.size)
        U = section_directions(pair, f)
        M_t = monodromy_across(A, pair, U) - np.eye(4)
        try:
            v, w, g = _bordered(M_t, state["b"], state["c"])
        except np.linalg.LinAlgError:
            return False, None, None, None
        state["v"], state["w"] = v, w
        u = (U @ v)[mask]
        nu = float(np.linalg.norm(u))
        diff = central_difference(plain, x, u, n_z, h, nu)
        dcf = _field_derivatives(system_at, full, x, pair @ v, x.size)
        if diff is None or dcf is None:
            return False, None, None, None
        # d(A u)/dx_k = dA/dx_k u + A du/dx_k, du/dx_k = -d(c f)/dx_k
        dAu = diff * (nu / (2.0 * h)) - A @ dcf[mask]
        grad = -(w @ (0.5 * pair[mask].T @ dAu))
        sc = state["scale"]
        return True, np.r_[G, sc * g], np.vstack([DG, sc * grad]), (A, M_t)

    evaluate.state = state
    return evaluate


def sb_tests() -> Callable:
    """Codim-2 tests along a symmetry-breaking curve: its turns, and a second multiplier
    of the whole map at +1 ("1:1": e.g. the curve meets a fold of the in-phase orbits) or
    at -1 ("fold-flip"), as on a fold curve (:func:`.foldcurve.map_curve_tests`)."""
    tests = map_curve_tests("fold")
    return lambda A, t: tests(A[0], t)


def follow_sb_curve(
    base: Callable,
    system_at: Callable,
    full: Callable,
    x0: np.ndarray,
    direction: float,
    bounds2: tuple[float, float],
    *,
    h: float = 1e-7,
    watch=None,
    periods: dict[bytes, float] | None = None,
    **settings,
):
    """Follow a symmetry-breaking curve through x0 = (z, l1, l2), a point near it.

    The walk stays in the in-phase subspace (:func:`.synchrony.project_in_phase`;
    ``periods``, the evaluator's return times, follow it there). Borders adapt as on
    fold curves (:func:`.foldcurve.refresh_borders`). ``settings``:
    ds, ds_min, ds_max, max_points, tol of :func:`.foldcurve.run_curve`. Returns
    (xs, mults, codim2, status) (``xs`` None when the start could not be corrected).
    """
    n_z = x0.size - 2
    ok, _, _, A = base(x0)
    f = _field_at(system_at, full, x0) if ok else None
    if f is None:
        return None, None, [], "start-failed"
    pair = pair_matrix(f.size)
    b, c = border(monodromy_across(A, pair, section_directions(pair, f)) - np.eye(4))
    bases = (project_in_phase(base, in_phase_projector(system_at(x0)), 2, periods), base)
    ok, _, DF, _ = sb_augmented(bases, system_at, full, n_z, b, c, h)(x0)
    if not ok:
        return None, None, [], "start-failed"
    scale = 1.0 / max(float(np.linalg.norm(DF[-1])), 1e-300)
    evaluate = sb_augmented(bases, system_at, full, n_z, b, c, h, scale)
    evaluate.after_step = lambda x: refresh_borders(evaluate, x)
    xs, mults, codim2, status, _ = run_curve(
        evaluate, x0, direction, bounds2, tests=sb_tests(),
        spectrum=lambda A: _sorted_eigs(A[0]), watch=watch, **settings,
    )  # fmt: skip
    return xs, mults, codim2, status
