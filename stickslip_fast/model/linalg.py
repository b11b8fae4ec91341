"""Linear solves with W = sigma I - J for the bordered block-diagonal Jacobian.

J has N dense 4x4 diagonal blocks; for the DC motor it also has a border column
(every disk's equations depend on v_b), a border row (v_b depends on every
disk) and a corner. W is factored blockwise and the border is eliminated by a
scalar Schur complement, so factor and solve cost O(N), not O((4N+1)^3).
"""

from __future__ import annotations

import numpy as np

from ..base.jit import JIT as _JIT
from ..base.jit import njit


@njit(inline="always", **_JIT)
def lu_inplace(a: np.ndarray, piv: np.ndarray, n: int) -> bool:
    """In-place LU of the n x n matrix ``a`` with partial pivoting. False if singular.

    Inlined, so that a literal ``n`` (4 for the model's blocks) becomes a
    compile-time loop bound.
    """
    for k in range(n):
        p = k
        big = abs(a[k, k])
        for r in range(k + 1, n):
            if abs(a[r, k]) > big:
                big = abs(a[r, k])
                p = r
        piv[k] = p
        if big == 0.0:
            return False
        if p != k:
            for q in range(n):
                tmp = a[k, q]
                a[k, q] = a[p, q]
                a[p, q] = tmp
        inv = 1.0 / a[k, k]
        for r in range(k + 1, n):
            a[r, k] *= inv
            f = a[r, k]
            if f != 0.0:
                for q in range(k + 1, n):
                    a[r, q] -= f * a[k, q]
    return True


@njit(inline="always", **_JIT)
def lu_solve(a: np.ndarray, piv: np.ndarray, b: np.ndarray, off: int, n: int) -> None:
    """Solve in place for the n entries b[off:off+n] with a :func:`lu_inplace` factor."""
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[off + k]
            b[off + k] = b[off + p]
            b[off + p] = tmp
    for k in range(n):
        s = b[off + k]
        for q in range(k):
            s -= a[k, q] * b[off + q]
        b[off + k] = s
    for k in range(n - 1, -1, -1):
        s = b[off + k]
        for q in range(k + 1, n):
            s -= a[k, q] * b[off + q]
        # the reciprocal depends on the factor only, so it is ready before s is:
        # a multiplication, not a division, on the solve's dependency chain
        b[off + k] = s * (1.0 / a[k, k])


@njit(inline="always", **_JIT)
def blocks_factor(
    sigma: float, blocks: np.ndarray, n_osc: int, lu: np.ndarray, piv: np.ndarray
) -> bool:
    """Factor the diagonal blocks of W = sigma I - J into ``lu``/``piv``; False if singular.

    All of W for a constant belt. Inlined, so that a literal ``n_osc`` gives
    constant loop bounds.
    """
    for i in range(n_osc):
        a = lu[i]
        for r in range(4):
            for q in range(4):
                a[r, q] = -blocks[i, r, q]
            a[r, r] += sigma
        if not lu_inplace(a, piv[i], 4):
            return False
    return True


@njit(inline="always", **_JIT)
def blocks_solve(lu: np.ndarray, piv: np.ndarray, b: np.ndarray, n_osc: int) -> None:
    """Solve with the factors of :func:`blocks_factor` in place (the disks' rows of b)."""
    for i in range(n_osc):
        lu_solve(lu[i], piv[i], b, 4 * i, 4)


@njit(**_JIT)
def w_factor(
    sigma: float,
    blocks: np.ndarray,
    border_col: np.ndarray,
    border_row: np.ndarray,
    corner: float,
    n_osc: int,
    dc: bool,
    lu: np.ndarray,
    piv: np.ndarray,
    z: np.ndarray,
) -> float:
    """Factor W = sigma I - J. Returns the Schur complement (NaN if singular).

    ``lu`` (N, 4, 4) and ``piv`` (N, 4) receive the block factors; for the DC
    motor ``z`` (N, 4) receives A_i^{-1} w_i, where w_i = -border_col[i] is W's
    border column. For a constant belt the return value is 1.0.
    """
    if not blocks_factor(sigma, blocks, n_osc, lu, piv):
        return np.nan
    if not dc:
        return 1.0
    schur = sigma - corner
    for i in range(n_osc):
        zi = z[i]
        for r in range(4):
            zi[r] = -border_col[i, r]
        lu_solve(lu[i], piv[i], zi, 0, 4)
        for r in range(4):
            # W's border row is -border_row
            schur += border_row[i, r] * zi[r]
    if schur == 0.0:
        return np.nan
    return schur


@njit(**_JIT)
def w_solve(
    lu: np.ndarray,
    piv: np.ndarray,
    z: np.ndarray,
    border_row: np.ndarray,
    schur: float,
    n_osc: int,
    dc: bool,
    b: np.ndarray,
) -> None:
    """Solve W x = b in place with the factors from :func:`w_factor`."""
    blocks_solve(lu, piv, b, n_osc)
    if dc:
        n = 4 * n_osc
        s = b[n]
        for i in range(n_osc):
            for r in range(4):
                s += border_row[i, r] * b[4 * i + r]
        xv = s * (1.0 / schur)  # the reciprocal is ready before s (see lu_solve)
        for i in range(n_osc):
            for r in range(4):
                b[4 * i + r] -= z[i, r] * xv
        b[n] = xv


# The same two functions inlined at Numba IR level, for kernels that know N and
# the belt at compile time (problems.StickSlipSmall): with literal sizes every
# loop has constant bounds. Not cached on their own: they only exist inlined.
_INLINE = dict(_JIT, cache=False, inline="always")
w_factor_inline = njit(**_INLINE)(w_factor.py_func)
w_solve_inline = njit(**_INLINE)(w_solve.py_func)


@njit(**_JIT)
def bordered_matvec(
    blocks: np.ndarray,
    border_col: np.ndarray,
    border_row: np.ndarray,
    corner: float,
    n_osc: int,
    dc: bool,
    u: np.ndarray,
    out: np.ndarray,
) -> None:
    """out = J u for J in bordered block-diagonal form (see :func:`model.jacobian_blocks`)."""
    nb = 4 * n_osc
    uvb = u[nb] if dc else 0.0
    acc = 0.0
    for i in range(n_osc):
        j = 4 * i
        b = blocks[i]
        for r in range(4):
            out[j + r] = (
                b[r, 0] * u[j] + b[r, 1] * u[j + 1] + b[r, 2] * u[j + 2] + b[r, 3] * u[j + 3]
            )
        if dc:
            for r in range(4):
                out[j + r] += border_col[i, r] * uvb
                acc += border_row[i, r] * u[j + r]
    if dc:
        out[nb] = acc + corner * uvb


bordered_matvec_inline = njit(**_INLINE)(bordered_matvec.py_func)


# ------------------------------------------------------------- dense (test problems)
@njit(**_JIT)
def dense_w_factor(sigma: float, jac: np.ndarray, lu: np.ndarray, piv: np.ndarray) -> bool:
    """Factor W = sigma I - J (dense, n x n) into ``lu``; False if singular.

    For small test problems (:mod:`stickslip_fast.core.testproblems`); the model uses
    the bordered O(N) factorisation above.
    """
    n = jac.shape[0]
    for r in range(n):
        for q in range(n):
            lu[r, q] = -jac[r, q]
        lu[r, r] += sigma
    return lu_inplace(lu, piv, n)


@njit(**_JIT)
def dense_w_solve(lu: np.ndarray, piv: np.ndarray, b: np.ndarray) -> None:
    """Solve W x = b in place with the factors from :func:`dense_w_factor`."""
    lu_solve(lu, piv, b, 0, lu.shape[0])
