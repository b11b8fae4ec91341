"""The model with its variational equations on the one driver: flows of tangent vectors.

:func:`propagate_tangents` integrates y' = f(y) together with k tangent vectors
u_j' = J(y) u_j (the problem :class:`problems.StickSlipTangent`) with Rodas5P
and the analytic Jacobian; :func:`propagate_sensitivity` also the sensitivity
s = dy/dlambda to one parameter (s' = J s + df/dlambda). With U(0) = I they
return the state-transition matrix Phi(t) = dy(t)/dy(0), from which monodromy matrices and the Jacobian of
the Poincare return map follow. The largest Lyapunov exponent
(:mod:`stickslip_fast.analysis.lyapunov`) runs the same problem on the same driver with
k = 1 and a renormalising observer.
"""

from __future__ import annotations

import numpy as np

from ..base.jit import ENTRY, JIT, njit
from ..base.status import ST_ERROR
from ..model.params import N_PARAMS
from .driver import (
    STOP_AFTER_CROSSINGS,
    STOP_AT_END,
    Controls,
    PoincareObserver,
    drive,
    simple_stop,
)
from .problems import alloc_bordered_linear
from .steppers import RODAS5P_METHOD, alloc_workspace
from .tangent import make_sensitivity, make_tangent, tangent_variant
from .trajectory import X1_MINIMA, variant_matches

__all__ = ["propagate_tangents", "propagate_sensitivity"]

_JIT = JIT


def propagate_tangents(
    y0: np.ndarray,
    U0: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    variant: tuple,
    t_end: float,
    n_crossings: int,
    rtol: float,
    atol: float,
    tangent_atol: float,
    max_steps: int,
    abort: np.ndarray,
):
    """Integrate y and the k columns of U0 (n x k) to ``t_end`` or a section crossing.

    With ``n_crossings`` > 0 the run stops at the step that completes the
    ``n_crossings``-th upward crossing of dx1 = 0 (t > 0), and the augmented
    state *at* that crossing is returned, from the dense output. Otherwise it
    runs to ``t_end``.

    ``variant`` is ``trajectory.kernel_variant(n_osc, dc)`` (the
    :class:`~stickslip_fast.core.problems.StickSlipTangentSmall` kernel for small N,
    bit-identical to the generic one and faster) or ``()`` (the generic kernel).
    A token that does not match (n_osc, dc) gives status "error".

    This is :func:`propagate_sensitivity` with its sensitivity off (``inv`` = 0):
    the same arithmetic as a kernel without one, bit for bit, from the one
    compiled kernel that continuation needs as well. Two kernels compiled for
    about 17 and 19 s on a fresh install; a newcomer's first ``find_orbit``
    and ``continue_orbit`` paid both (docs/performance.md, "The first run").

    Returns
    -------
    (status, y, U, t): the driver's status code, the state (n,), the tangent
    vectors (n, k) and the time, at the last crossing (``n_crossings`` > 0,
    t = NaN if it was not reached) or at the final time.
    """
    p2 = np.stack((p, p))
    return propagate_sensitivity(
        y0, U0, p, n_osc, dc, variant, t_end, n_crossings, rtol, atol, tangent_atol, p2, 0.0,
        max_steps, abort,
    )  # fmt: skip


@njit(**ENTRY)
def propagate_sensitivity(
    y0: np.ndarray,
    U0: np.ndarray,
    p: np.ndarray,
    n_osc: int,
    dc: bool,
    variant: tuple,
    t_end: float,
    n_crossings: int,
    rtol: float,
    atol: float,
    tangent_atol: float,
    p2: np.ndarray,
    inv: float,
    max_steps: int,
    abort: np.ndarray,
):
    """:func:`propagate_tangents` whose last column of U0 is the sensitivity dy/dlambda.

    ``p2`` (2, N_PARAMS) holds the packed parameters at lambda + h and
    lambda - h, ``inv`` = 1 / (their difference in lambda): the last column
    follows s' = J s + df/dlambda, with df/dlambda and dJ/dlambda central
    differences of the model's equations (start it at 0 for d phi_t / d lambda).
    The other columns are tangent vectors as in :func:`propagate_tangents`, and
    the returns are the same. ``inv`` = 0 turns the sensitivity off: every
    column is then a tangent vector (:func:`propagate_tangents`).
    """
    if (
        not variant_matches(variant, n_osc, dc)
        or (inv != 0.0 and U0.shape[1] < 1)
        or p2.shape[0] != 2
    ):
        return _failed(y0, U0)
    sens = make_sensitivity(p2, inv, n_osc, dc)
    plain = make_tangent(p, n_osc, dc, U0.shape[1], tangent_atol, np.empty(N_PARAMS), sens)
    prob = tangent_variant(plain, variant)
    # the driver run, in this function: a compiled level of its own (shared by two
    # kernels until 2026-11-28) re-optimised the whole driver once more (~1.5 s cold)
    n = y0.size
    k = U0.shape[1]
    m = n * (1 + k)
    y = np.empty(m)
    for i in range(n):
        y[i] = y0[i]
        for j in range(k):
            y[(j + 1) * n + i] = U0[i, j]
    cap = 1 if n_crossings > 0 else 0
    obs = PoincareObserver(
        X1_MINIMA, 0.0, np.full((cap, m), np.nan), np.full(cap, np.nan), np.empty((0, m)), 1.0,
        np.empty(m), np.empty(m), np.zeros(2, dtype=np.int64),
    )  # fmt: skip
    stop = simple_stop(STOP_AFTER_CROSSINGS if n_crossings > 0 else STOP_AT_END, n_crossings, 0)
    istat = np.zeros(2, dtype=np.int64)
    fstat = np.zeros(1)
    status = drive(
        RODAS5P_METHOD, prob, alloc_bordered_linear(n_osc, m), alloc_workspace(RODAS5P_METHOD, m),
        y, t_end, Controls(rtol, atol, 0.0, max_steps), obs, stop, abort, istat, fstat,
    )  # fmt: skip
    src = y
    t = fstat[0]
    if n_crossings > 0:
        src = obs.pts[0]
        t = obs.tpts[0] if obs.counts[0] >= n_crossings else np.nan
    y_out = src[:n].copy()
    U = np.empty((n, k))
    for i in range(n):
        for j in range(k):
            U[i, j] = src[(j + 1) * n + i]
    return status, y_out, U, t


@njit(**_JIT)
def _failed(y0, U0):
    n, k = U0.shape
    return ST_ERROR, np.full(n, np.nan), np.full((n, k), np.nan), np.nan
