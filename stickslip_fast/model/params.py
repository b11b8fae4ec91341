"""Slots of the packed parameter array, and eta'(eta): shared by System and the model.

The compiled kernels get a :class:`~stickslip_fast.model.system.System` packed into a
float64 array (:meth:`System.to_array`); these are its slots. Slot ``P_ETAP``
(eta') is derived from eta by :func:`eta_prime`, never set by hand. This module
imports nothing else from the package, so system.py and model.py can both use it.
"""

from __future__ import annotations

import math

from ..base.jit import JIT, njit

__all__ = ["ETA_MIN", "ETA_MAX", "N_PARAMS", "PARAM_INDEX", "eta_prime"]

#: The range of eta covered by the paper's cubic fit for eta'.
ETA_MIN, ETA_MAX = 1.0, 10.0

P_M, P_K12, P_C, P_C12, P_MU, P_EPS, P_ETA, P_ETAP, P_VB, P_VB0, P_TB, P_BETA = range(12)
N_PARAMS = 12

#: Field name of :class:`System` -> slot in the packed array.
PARAM_INDEX: dict[str, int] = {
    "m": P_M,
    "k12": P_K12,
    "c": P_C,
    "c12": P_C12,
    "mu": P_MU,
    "eps": P_EPS,
    "eta": P_ETA,
    "vb": P_VB,
    "vb0": P_VB0,
    "Tb": P_TB,
    "beta": P_BETA,
}


@njit(**JIT)
def eta_prime(eta: float) -> float:
    """The paper's cubic fit eta'(eta) on [1, 1.3], [1.3, 2.7], [2.7, 10].

    Returns NaN outside [1, 10]: the fit is not extrapolated (System rejects such eta).
    """
    if eta < ETA_MIN or eta > ETA_MAX or not math.isfinite(eta):
        return math.nan
    if eta <= 1.3:
        return -13.607 + eta * (30.893 + eta * (-22.01 + eta * 5.878))
    if eta <= 2.7:
        return -2.41 + eta * (3.985 + eta * (-0.3581 + eta * 0.0493))
    return -1.684 + eta * (3.121 + eta * (-0.00483 + eta * 0.000196))
