"""The two tableau records (explicit Runge-Kutta, Rosenbrock): fields read-only float64 arrays.

The coefficients themselves are data in :mod:`.tableaus` (which re-exports these records)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def _frozen(values: object) -> FloatArray:
    """Return ``values`` as a read-only, C-contiguous ``float64`` array.

    Parameters
    ----------
    values : array_like
        Nested sequence of numbers.

    Returns
    -------
    numpy.ndarray
        A fresh array with ``flags.writeable == False``.
    """
    arr = np.ascontiguousarray(np.array(values, dtype=np.float64))
    arr.flags.writeable = False
    return arr


class ExplicitRKTableau(NamedTuple):
    """Embedded explicit Runge-Kutta pair with polynomial dense output.

    Attributes
    ----------
    c : ndarray, shape (s,)
        Stage abscissae (row sums of ``A``).
    A : ndarray, shape (s, s)
        Strictly lower-triangular stage matrix.
    b : ndarray, shape (s,)
        Weights of the propagated (higher-order) solution.
    b_err : ndarray, shape (s,)
        ``b - b_hat``; the local error estimate is ``h * b_err @ k``.
    dense : ndarray, shape (s, n_poly)
        Dense-output matrix ``P``:
        ``y(t0 + theta h) = y0 + h * sum_i k_i * sum_m P[i, m] * theta**(m+1)``.
    order : int
        Order of the solution built with ``b``.
    embedded_order : int
        Order of the embedded solution built with ``b - b_err``.
    dense_order : int
        Order of the continuous extension.
    fsal : bool
        True if the last row of ``A`` equals ``b`` (first same as last).
    """

    c: FloatArray
    A: FloatArray
    b: FloatArray
    b_err: FloatArray
    dense: FloatArray
    order: int = 5
    embedded_order: int = 4
    dense_order: int = 4
    fsal: bool = True

    @property
    def n_stages(self) -> int:
        """Number of stages ``s``."""
        return int(self.b.shape[0])


class RosenbrockTableau(NamedTuple):
    """Rosenbrock-Wanner method in transformed (Rodas) form.

    See the module docstring for the exact step and interpolation formulas.

    Attributes
    ----------
    gamma : float
        Diagonal coefficient; the iteration matrix is ``I/(h*gamma) - J``.
    a : ndarray, shape (s, s)
        Strictly lower-triangular stage-argument coefficients
        (``u_i = y0 + sum_{j<i} a[i, j] k_j``).
    C : ndarray, shape (s, s)
        Strictly lower-triangular coupling coefficients
        (right-hand side ``f(u_i) + sum_{j<i} C[i, j]/h k_j``).
    c : ndarray, shape (s,)
        Stage times (``t0 + c[i] h``); unused for autonomous problems.
    d : ndarray, shape (s,)
        Coefficients of ``h * df/dt``; unused for autonomous problems.
    H : ndarray, shape (n_dense, s)
        Dense-output coefficients, ``h_r = sum_j H[r, j] k_j``.
    order : int
        Order of ``y1``.
    embedded_order : int
        Order of the embedded solution ``y1 - k[s-1]``.
    dense_order : int
        Order of the dense output.
    """

    gamma: float
    a: FloatArray
    C: FloatArray
    c: FloatArray
    d: FloatArray
    H: FloatArray
    order: int = 5
    embedded_order: int = 4
    dense_order: int = 4

    @property
    def n_stages(self) -> int:
        """Number of stages ``s``."""
        return int(self.a.shape[0])

    @property
    def b(self) -> FloatArray:
        """Solution weights: ``y1 = y0 + sum_j b[j] k_j`` (stiffly accurate form).

        The last stage's argument plus its increment: ``b = a[s-1] + e_{s-1}``.
        """
        w = self.a[-1].copy()
        w[-1] += 1.0
        return w

    @property
    def b_err(self) -> FloatArray:
        """Error weights: ``err = sum_j b_err[j] k_j = k_{s-1}`` (y1 minus the embedded solution)."""
        w = np.zeros(self.a.shape[0])
        w[-1] = 1.0
        return w
