"""The turn shared by the normal forms whose null vectors turn along a curve (the borders'
refresh of fold, NS and Hopf curves: tests/test_foldcurve.py, test_nscurve.py,
test_eqcurve.py)."""

from __future__ import annotations

import numpy as np


def quarter_turn(th: float) -> tuple[float, float]:
    """(phi, dphi/dth): a smooth quarter turn, phi = 0 at th = 0 up to pi/2 at th = 1.5,
    where it stays."""
    t = min(max(th / 1.5, 0.0), 1.0)
    phi = 0.5 * np.pi * (3 * t * t - 2 * t**3)
    dphi = np.pi * 2 * t * (1 - t) if 0.0 < t < 1.0 else 0.0
    return phi, dphi


def plane_turn(th: float) -> tuple[np.ndarray, np.ndarray]:
    """(Q, dQ/dth): the 4 x 4 rotation that turns the (1, 2) plane into the (3, 4) plane by
    :func:`quarter_turn` of th."""
    phi, dphi = quarter_turn(th)
    c, s, eye2 = np.cos(phi), np.sin(phi), np.eye(2)
    Q = np.block([[c * eye2, -s * eye2], [s * eye2, c * eye2]])
    dQ = np.block([[-s * eye2, -c * eye2], [c * eye2, -s * eye2]]) * dphi
    return Q, dQ
