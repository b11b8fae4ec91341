"""Argument checks and parameter derivatives shared by the one-parameter walks
(periodic orbits, equilibria, and the curves that start from them)."""

from __future__ import annotations

import dataclasses
import math

from ..base.messages import plain
from ..model.system import SWEEPABLE

#: Tighter settings :func:`continue_orbit` goes on with, in turn, where the corrector fails
#: at ``ds_min`` (``sharp_ends=True``): (tol, rtol, atol, ds_min). The sharp ends of
#: Fig. 6's period-1 branch are folds narrower than the defaults resolve (docs/limits.md):
#: at eta = 3.3236646195 the branch turns within ~1.5e-9 in arclength (below ds_min = 1e-8)
#: and its parameter moves ~1e-8 there, the residual's tol 1e-10 over dP/deta ~ 0.01; at
#: eta = 1.8430158079 the turn is ~2e-11 in eta and the map's integration noise at
#: rtol 1e-11 (~5e-14) matters too.
SHARP_END_STAGES: tuple[tuple[float, float, float, float], ...] = (
    (1e-13, 1e-11, 1e-13, 1e-14),
    (1e-14, 1e-13, 1e-15, 1e-16),
)


#: The smallest corrector tolerance ``continue_orbit(shooting="auto")`` gives multiple
#: shooting: its residual, the segments' continuity, carries their integration error,
#: 2e-14 to 1.1e-13 at rtol 1e-13 on Fig. 6's lower P1 fold (the tightest sharp-end
#: stage's tol 1e-14 ended that branch "step-too-small" at multiplier 8.6e5).
MS_TOL_FLOOR = 1e-12


#: The first step (``ds``) of :func:`continue_orbit` from an orbit that
#: :func:`~stickslip_fast.switch_branch` found at a branch point (``Orbit.origin``), and the
#: largest one advised there. That orbit lies about its offset (1e-4 on the anti-phase
#: branch) from the branch point, where the crossing branch turns sharply: on the
#: anti-phase branch's upper point its tangent turns by 80 degrees within 1e-3 of
#: arclength (its component in eta from 0.15 to 0.998). A first step of 0.01 (the default
#: elsewhere) landed back on the anti-phase branch on an AMD EPYC VM (multiplier 0.66 at
#: eta = 1.5756), though not on a Xeon; 1e-3, 3e-4 and 1e-4 followed the crossing branch on
#: both (tests/test_branch_points.py).
BRANCH_POINT_DS = 1e-3

#: ``continue_orbit``'s first step elsewhere.
DEFAULT_DS = 0.01


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


def _walk_defaults(orbit, param: str, ds, direction) -> tuple[float, float]:
    """(ds, direction) with the defaults filled in: :data:`DEFAULT_DS` and +1, or for an
    orbit :func:`~stickslip_fast.switch_branch` found (``orbit.origin``) in ``param``,
    away from the bifurcation, from a branch point with :data:`BRANCH_POINT_DS`."""
    origin = orbit.origin if orbit.origin_param == param else None
    if ds is None:
        ds = BRANCH_POINT_DS if origin is not None and origin.kind == "branch-point" else DEFAULT_DS
    if direction is None:
        direction = 1.0
        if origin is not None and getattr(orbit.system, param) < origin.value:
            direction = -1.0
    return ds, direction
