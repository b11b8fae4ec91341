"""The starts of a census: the default box of initial states and the seeded sampler.

See docs/census.md ("The starts") for the physical reasoning behind the box.
"""

from __future__ import annotations

import numpy as np

from ..base.messages import plain
from ..model.system import System

__all__ = ["default_box", "sample_starts"]


def default_box(
    system: System, param: str | tuple[str, str] | None = None, values=None
) -> np.ndarray:
    """The default box of initial states, one (low, high) row per state variable.

    Physical reasoning (docs/census.md): with the belt sliding under a disk at
    rest, the friction force is mu (one unit of kinetic friction) and torque
    zero, so the steady-sliding state is x_s = mu / (1 - k12^2),
    phi_s = -k12 x_s. Sticking can hold the spring up to the static friction,
    eta times the kinetic one, so positions within D = max(eta - 1, 1) mu of
    the sliding state can stick; the box is x_i in [x_s - D, x_s + D], phi_i in
    [phi_s - D, phi_s + D], and speeds dx_i, dphi_i in [-D, D] (the speed of a
    unit-frequency swing of amplitude D). The DC motor's belt speed v_b is in
    [0, v_b0]. When ``param`` is swept, the box is the union of the boxes of
    every value (of every cell of a plane), so one set of starts serves the
    whole sweep.

    Parameters
    ----------
    system : System
    param : str or (str, str), optional
        The swept field, or the two fields of a census over a plane.
    values : array_like, or a pair of them, optional
        Its values (one array per field).

    Returns
    -------
    ndarray, shape (n_state, 2)
    """
    systems = [system]
    if param is not None and values is not None:
        if isinstance(param, str):
            systems = [system.replace(**{param: float(v)}) for v in np.unique(values)]
        else:  # two parameters: every cell of the grid
            systems = [
                system.replace(**{param[0]: float(a), param[1]: float(b)})
                for a in np.unique(values[0])
                for b in np.unique(values[1])
            ]
    lows = []
    highs = []
    for s in systems:
        xs = s.mu / (1.0 - s.k12**2)
        ps = -s.k12 * xs
        d = max(s.eta - 1.0, 1.0) * s.mu
        lo = []
        hi = []
        for _ in range(s.n_oscillators):
            lo += [xs - d, -d, ps - d, -d]
            hi += [xs + d, d, ps + d, d]
        if s.is_dc_motor:
            lo.append(0.0)
            hi.append(s.vb0)
        lows.append(lo)
        highs.append(hi)
    return np.stack([np.min(lows, axis=0), np.max(highs, axis=0)], axis=-1)


def sample_starts(
    system: System, n_starts: int, box, seed: int = 0, include_zero: bool = True
) -> np.ndarray:
    """Seeded uniform starts in ``box`` (n_state x 2), the zero state first if asked.

    ``numpy.random.default_rng(seed).random((n, n_state))`` scaled into the box
    (NumPy's PCG64 stream, stable across NumPy versions); with ``include_zero``
    start 0 is the paper's initial condition (the zero state, v_b(0) = 0) and
    ``n_starts - 1`` starts are random. The same seed gives the same starts.
    """
    box = np.asarray(box, dtype=float)
    n_random = n_starts - 1 if include_zero else n_starts
    rng = np.random.default_rng(seed)
    u = rng.random((n_random, system.n_state))
    random = box[:, 0] + u * (box[:, 1] - box[:, 0])
    if include_zero:
        return np.concatenate([system.initial_state(None)[None, :], random], axis=0)
    return random


def _check_starts(system: System, n_starts, box, starts, seed, include_zero, param, values):
    """The starts (explicit, or sampled in the box) and the box (None for explicit starts)."""
    if starts is not None:
        if box is not None:
            raise ValueError("give box or starts, not both")
        arr = np.asarray(starts, dtype=float)
        if arr.ndim != 2 or arr.shape[1] != system.n_state or arr.shape[0] < 1:
            raise ValueError(
                f"starts must have shape (n_starts, {system.n_state}) "
                f"({', '.join(system.state_names)}), got {arr.shape}"
            )
        if not np.all(np.isfinite(arr)):
            raise ValueError("starts must be finite (found NaN or inf)")
        return arr.copy(), None
    if isinstance(n_starts, bool) or not isinstance(n_starts, (int, np.integer)) or n_starts < 1:
        raise ValueError(f"n_starts must be an integer >= 1, got {n_starts!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0, got {plain(seed)}")
    if box is None:
        box_arr = default_box(system, param, values)
    else:
        box_arr = np.asarray(box, dtype=float)
        if box_arr.shape != (system.n_state, 2):
            raise ValueError(
                f"box must have shape ({system.n_state}, 2): one (low, high) pair per state "
                f"variable ({', '.join(system.state_names)}), got {box_arr.shape}"
            )
        if not np.all(np.isfinite(box_arr)) or np.any(box_arr[:, 0] > box_arr[:, 1]):
            raise ValueError("box must be finite with low <= high in every row")
    return sample_starts(system, int(n_starts), box_arr, int(seed), bool(include_zero)), box_arr
