"""Argument checks and parameter derivatives shared by the one-parameter walks
(periodic orbits, equilibria, and the curves that start from them)."""

from __future__ import annotations

import dataclasses
import math

from ..base.messages import plain
from ..model.system import SWEEPABLE


def _difference(value_at, lam: float, h: float, centre):
    """d value / d lambda: central, or one-sided at the edge of the parameter's valid
    range (value_at raises ValueError outside it, or returns None on failure)."""

    def at(v):
        try:
            return value_at(v)
        except ValueError:
            return None

    plus, minus = at(lam + h), at(lam - h)
    if plus is not None and minus is not None:
        return (plus - minus) / (2 * h)
    if plus is not None and centre is not None:
        return (plus - centre) / h
    if minus is not None and centre is not None:
        return (centre - minus) / h
    return None


def _check_args(system, what, param, bounds, ds, ds_min, ds_max, tol, max_points):
    """The continuation arguments, checked; returns (start value, lo, hi)."""
    if param not in SWEEPABLE or param == "n_oscillators":
        raise ValueError(f"param must be one of {sorted(SWEEPABLE)}, got {param!r}")
    try:
        lo, hi = (float(v) for v in bounds)
    except (TypeError, ValueError):
        raise ValueError(f"bounds must be two numbers (lo, hi), got {plain(bounds)}") from None
    lam0 = float(getattr(system, param))
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= lam0 <= hi):
        raise ValueError(f"bounds {plain(bounds)} must contain the {what}'s {param} = {lam0}")
    for name, v in (("ds", ds), ("ds_min", ds_min), ("ds_max", ds_max), ("tol", tol)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {plain(v)}")
    if not ds_min <= ds <= ds_max:
        raise ValueError(f"need ds_min <= ds <= ds_max, got {ds_min}, {ds}, {ds_max}")
    if isinstance(max_points, bool) or not isinstance(max_points, int) or max_points < 2:
        raise ValueError(f"max_points must be an integer >= 2, got {max_points!r}")
    return lam0, lo, hi


@dataclasses.dataclass(frozen=True)
class WalkSettings:
    """The settings of one walk along a branch of periodic orbits: those of
    :func:`~stickslip_fast.bifurcation.orbit_branch.continue_orbit` of the same names, checked
    there once. A walk's later stages (the sharp ends, multiple shooting after single)
    run on copies with some fields changed (:func:`dataclasses.replace`)."""

    ds: float
    ds_min: float
    ds_max: float
    max_points: int
    tol: float
    rtol: float
    atol: float
    fd_step: float
    stick_events: bool
    sharp_ends: bool
