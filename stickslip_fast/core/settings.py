"""Integration settings: one typed, validated, frozen record shared by simulate and sweep.

:class:`Settings` is what the kernels are run with, and :meth:`Settings.to_dict`
is the one mapping written into the configuration hash of a result file, its
HDF5 attributes and the keys of Dask tasks.

Adding a setting is one line in :class:`Settings`: a field with its default and
its check, e.g. ``stop: str = _field("t_end", _choice(("t_end", "converged")),
new=True)``. A field marked ``new=True`` is left out of :meth:`~Settings.to_dict`
while it has its default, so files written before the field existed keep their
configuration hash and still resume.
"""

from __future__ import annotations

import dataclasses
import math
import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..base.messages import plain
from ..model.system import System, slowest_belt_speed, smallest_eps
from .poincare import MAX_PERIOD
from .trajectory import METHODS, RunSettings, run_settings

__all__ = [
    "Settings",
    "DEFAULT_RTOL",
    "DEFAULT_ATOL",
    "DEFAULT_EQUILIBRIUM_TOL",
    "DEFAULT_MAX_STEPS",
    "DEFAULT_DWELL",
    "STOP_KINDS",
    "MAX_RTOL",
    "PERIOD_TOL_MAX",
    "period_tolerance",
    "ATOL_EPS_RATIO",
    "DEFAULT_ATOL_PER_EPS",
    "default_atol",
    "PRESET_BELT_SPEED",
    "EQUILIBRIUM_TOL_PER_BELT_SPEED",
    "default_equilibrium_tol",
    "default_dwell",
    "system_defaults",
    "CoarseToleranceWarning",
    "warn_if_coarse_atol",
    "check_real",
    "check_integer",
    "check_memory",
    "memory_limit",
]

#: Default tolerances. Over the seven SciPy reference trajectories (presets,
#: both drives, N = 1 and 2, 400-3000 time units with their transients) the
#: Poincare points agree with Radau rtol=1e-10 to 1.8e-7 at worst
#: (tests/test_scipy_crosscheck.py); rtol=1e-8 would give up to 2e-4 there.
DEFAULT_RTOL = 1e-9
DEFAULT_ATOL = 1e-11
#: Largest accepted rtol. Above it the step control no longer resolves the
#: stick-slip transitions (with rtol = 1 the P1 orbit at eta = 2 is called an
#: equilibrium).
MAX_RTOL = 1e-2
#: Period tolerance relative to rtol (see :func:`period_tolerance`).
PERIOD_TOL_FACTOR = 1e4
#: Largest default period tolerance, reached at rtol = 1e-8. Uncapped, 1e4 rtol is 1 at
#: rtol = 1e-4, and every pair of points then "repeats": any run with enough crossings
#: read as period 1. Over the classification corpus (benchmarks/loose_labels.py) the
#: cap leaves at most 3 of 400 labels false at any rtol in 1e-7 ... 1e-3; with 1e4 rtol
#: 21-43 of the literature set's 100 were false at rtol 1e-7 and 1e-6.
PERIOD_TOL_MAX = 1e-4
#: Disk speed (over the recording window) below which a run is at rest:
#: ten times the friction law's smoothing width eps = 1e-5 of the presets.
DEFAULT_EQUILIBRIUM_TOL = 1e-4
DEFAULT_MAX_STEPS = 20_000_000
#: Stop rules: run to t_end ("fixed"), or end once converged ("converged").
STOP_KINDS = ("fixed", "converged")
#: How long the disks must have been at rest at the end of a run for it to be
#: an equilibrium (the whole recording window if that is shorter), and with
#: converged stopping how long they must stay at rest before the run ends: about
#: 15 periods of the slowest free oscillation, 2 pi sqrt(m).
DEFAULT_DWELL = 200.0


def period_tolerance(rtol: float) -> float:
    """Tolerance for repeated Poincare points: 1e4 rtol within [1e-9, 1e-4] (relative).

    Points are accurate to roughly 100 rtol; the extra factor absorbs the last
    bit of transient decay of orbits whose Floquet multipliers are close to 1.
    The cap (:data:`PERIOD_TOL_MAX`, from rtol = 1e-8 up) keeps the test from
    calling a slow transient, a higher period or an aperiodic motion period 1 at
    loose tolerances; there a period may go undetected (period 0) instead.
    """
    return min(max(PERIOD_TOL_FACTOR * rtol, 1e-9), PERIOD_TOL_MAX)


#: Largest atol / eps that resolves the creep of a sticking disk. Over the classification
#: corpus at the default rtol (benchmarks/eps_atol.py) atol = 1e-4 eps gave the settled
#: labels for all 200 asymmetric cases at eps = 1e-5, 1e-7, 1e-8 and 1e-9 (3 false at
#: eps = 1e-3); 1e-3 eps left 23 (eps = 1e-5) to 78 (eps = 1e-8) of them false or
#: undetected. At rtol 1e-6 / 1e-3 (benchmarks/loose_labels.py) 1e-2 eps gave 4-26
#: false, 1e-1 eps 4-80.
ATOL_EPS_RATIO = 1e-4
#: The default atol per unit of eps, where eps is below the presets' 1e-5
#: (:func:`default_atol`): the presets' ratio, DEFAULT_ATOL / 1e-5.
DEFAULT_ATOL_PER_EPS = 1e-6


def default_atol(eps: float) -> float:
    """The default atol of a run whose smallest eps is ``eps``.

    :data:`DEFAULT_ATOL` (1e-11, which is 1e-6 eps at the presets' eps = 1e-5), and
    :data:`DEFAULT_ATOL_PER_EPS` ``eps`` for a smaller eps: a sticking disk creeps at
    slip speeds of the order of eps, so a fixed atol would not resolve the creep of a
    sharper friction law (at eps = 1e-8, atol = 1e-11 left 78 of the corpus's 200
    labels false or undetected; benchmarks/eps_atol.py).
    """
    return min(DEFAULT_ATOL, DEFAULT_ATOL_PER_EPS * eps)


#: The constant belt speed of the main parameter sets (v_b = v_b0 = 0.0112), at which
#: :data:`DEFAULT_EQUILIBRIUM_TOL` and :data:`DEFAULT_DWELL` were set.
PRESET_BELT_SPEED = 0.0112
#: The default equilibrium_tol per unit of a belt speed below 0.01
#: (:func:`default_equilibrium_tol`).
EQUILIBRIUM_TOL_PER_BELT_SPEED = 1e-2


def default_equilibrium_tol(belt_speed: float | None) -> float:
    """The default ``equilibrium_tol`` for a belt at ``belt_speed``.

    :data:`DEFAULT_EQUILIBRIUM_TOL` (1e-4), and 1e-2 ``|belt_speed|`` where that is
    smaller. A disk that sticks rides with the belt, so below a belt speed of 1e-2 the
    fixed 1e-4 took a stick phase for rest: at v_b = 1e-4 Fig. 6's stick-slip orbits
    read as "equilibrium" (benchmarks/belt_speed.py). ``None`` (no belt speed, or 0):
    the fixed default.
    """
    if not belt_speed:
        return DEFAULT_EQUILIBRIUM_TOL
    return min(DEFAULT_EQUILIBRIUM_TOL, EQUILIBRIUM_TOL_PER_BELT_SPEED * abs(belt_speed))


def default_dwell(belt_speed: float | None) -> float:
    """The default ``dwell`` for a belt at ``belt_speed``.

    :data:`DEFAULT_DWELL` (200) at the presets' belt speed and above, and longer in
    proportion to 1 / ``|belt_speed|`` below it: a stick phase lasts about the spring's
    travel over the belt speed (some 6 time units at v_b = 0.0112, some 700 at 1e-4),
    and an orbit needs a crossing within the last ``dwell``. ``None``: the fixed
    default.
    """
    if not belt_speed:
        return DEFAULT_DWELL
    return max(DEFAULT_DWELL, DEFAULT_DWELL * PRESET_BELT_SPEED / abs(belt_speed))


def system_defaults(
    system: System, names=(), axes=(), *, atol: float | None = None,
    equilibrium_tol: float | None = None, dwell: float | None = None,
) -> tuple[float, float, float]:  # fmt: skip
    """``(atol, equilibrium_tol, dwell)`` for a run of ``system`` over the swept ``names``
    / ``axes``: each given value kept, each ``None`` set to its default for the smallest
    eps and the slowest belt speed the run meets (:func:`default_atol`,
    :func:`default_equilibrium_tol`, :func:`default_dwell`)."""
    speed = slowest_belt_speed(system, names, axes)
    return (
        default_atol(smallest_eps(system, names, axes)) if atol is None else atol,
        default_equilibrium_tol(speed) if equilibrium_tol is None else equilibrium_tol,
        default_dwell(speed) if dwell is None else dwell,
    )


class CoarseToleranceWarning(UserWarning):
    """atol is not small against the friction law's eps.

    A sticking disk creeps at slip speeds of the order of eps, and the error control
    weighs a speed against ``atol + rtol |speed|``: with atol near eps the steps there are
    free to get the creep wrong, and a run can come to rest, stop crossing or change
    its period where a tighter run does not.
    """


def warn_if_coarse_atol(eps: float, atol: float, stacklevel: int) -> None:
    """Warn (:class:`CoarseToleranceWarning`) if ``atol`` > :data:`ATOL_EPS_RATIO` ``eps``.

    ``eps``: the smallest eps the call integrates with (a swept eps included).
    """
    if atol > ATOL_EPS_RATIO * eps:
        warnings.warn(
            f"atol = {atol:g} is not small against the friction law's eps = {eps:g} "
            f"(atol > {ATOL_EPS_RATIO:g} eps): the creep of a sticking disk, of the order "
            "of eps, is not resolved, and a run can come to rest, stop crossing or change "
            "its period where a tighter one does not; use atol <= "
            f"{ATOL_EPS_RATIO * eps:g} (the default here is {default_atol(eps):g})",
            CoarseToleranceWarning,
            stacklevel=stacklevel + 1,
        )


# ------------------------------------------------------------------ checks
def check_real(
    name: str,
    value: Any,
    *,
    minimum: float = 0.0,
    allow_equal: bool = False,
    maximum: float = math.inf,
) -> float:
    """``value`` as a finite float in (minimum, maximum] (or [minimum, ...] with allow_equal).

    Strings and booleans are rejected, not converted: ``t_end = "300"`` is an
    error naming ``t_end``.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(
        value, (int, float, np.integer, np.floating)
    ):
        raise ValueError(f"{name} must be a real number, got {plain(value)}")
    value = float(value)
    low_ok = value >= minimum if allow_equal else value > minimum
    if not math.isfinite(value) or not low_ok:
        raise ValueError(
            f"{name} must be finite and {'>=' if allow_equal else '>'} {minimum:g}, got {plain(value)}"
        )
    if value > maximum:
        raise ValueError(f"{name} must be <= {maximum:g}, got {plain(value)}")
    return value


def check_integer(name: str, value: Any, minimum: int) -> int:
    """``value`` as an int >= minimum; an integral float (2.0, 1e6) is accepted, 2.7 is not."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(
        value, (int, float, np.integer, np.floating)
    ):
        raise ValueError(f"{name} must be an integer >= {minimum}, got {plain(value)}")
    if isinstance(value, (float, np.floating)) and not float(value).is_integer():
        raise ValueError(f"{name} must be an integer >= {minimum}, got {plain(value)} (not cut)")
    if int(value) < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {plain(value)}")
    return int(value)


def memory_limit() -> int:
    """Bytes of physical memory of this machine (the bound of :func:`check_memory`)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):  # pragma: no cover - not POSIX
        return 2**62


def check_memory(nbytes: float, what: str) -> None:
    """Refuse work whose arrays would not fit in this machine's memory, before allocating.

    Parameters
    ----------
    nbytes : float
        Estimated bytes the work allocates.
    what : str
        What needs them, naming the arguments that set the size (for the message).
    """
    limit = memory_limit()
    if nbytes > limit:
        raise ValueError(
            f"{what} would need about {nbytes / 2**30:.1f} GiB, more than this machine's "
            f"{limit / 2**30:.1f} GiB of memory"
        )


def _positive(allow_zero: bool = False, maximum: float = math.inf) -> Callable[[str, Any], float]:
    def check(name: str, value: Any) -> float:
        return check_real(name, value, allow_equal=allow_zero, maximum=maximum)

    return check


def _integer(minimum: int) -> Callable[[str, Any], int]:
    def check(name: str, value: Any) -> int:
        return check_integer(name, value, minimum)

    return check


def _choice(options: tuple[str, ...]) -> Callable[[str, Any], str]:
    def check(name: str, value: Any) -> str:
        if not isinstance(value, str) or value not in options:
            raise ValueError(f"{name} must be one of {options}, got {plain(value)}")
        return value

    return check


def _field(default: Any, check: Callable[[str, Any], Any], *, new: bool = False) -> Any:
    """A settings field: its default, its check and whether it post-dates schema 1 files."""
    return dataclasses.field(default=default, metadata={"check": check, "new": new})


_REQUIRED = dataclasses.MISSING


def _exact(value: Any) -> tuple:
    """A key that tells apart what ``==`` does not: the type, and a float's bits."""
    if isinstance(value, float):
        return (type(value), float(value).hex())
    hash(value)  # TypeError for an unhashable value
    return (type(value), value)


#: Records built by :meth:`Settings.resolve`, by their exact arguments.
_RESOLVED: dict[tuple, Settings] = {}
_RESOLVED_MAX = 512


# ---------------------------------------------------------------- the record
@dataclass(frozen=True, kw_only=True)
class Settings:
    """Validated integration settings (see :func:`stickslip_fast.simulate` for each).

    Build one with :meth:`resolve`, which fills the defaults that depend on
    other fields (``None`` means "default"); the constructor itself takes every
    value explicitly and validates it. ``h = 0.0`` means "no fixed step".

    Attributes
    ----------
    method : str
        One of :data:`~stickslip_fast.METHODS`.
    t_end, t_transient : float
        Final time (> 0) and start of the recording window (>= 0, < t_end).
    rtol, atol : float
        Tolerances (> 0; rtol <= :data:`MAX_RTOL`).
    h : float
        Fixed step, 0.0 for the adaptive methods.
    max_points : int
        Points kept per trajectory (>= 0; 0 records none and detects no period).
    max_steps : int
        Step budget (>= 1).
    equilibrium_tol, period_tol : float
        Classification tolerances (> 0).
    stop : str
        "fixed" (run to t_end) or "converged" (end once converged; see
        :func:`stickslip_fast.simulate`).
    dwell : float
        Time at rest at the end of a run that makes it an equilibrium (the
        whole recording window if shorter); with converged stopping, the time
        at rest before the run ends.
    """

    method: str = _field("rodas5p", _choice(METHODS))
    t_end: float = _field(_REQUIRED, _positive())
    t_transient: float = _field(0.0, _positive(allow_zero=True))
    rtol: float = _field(DEFAULT_RTOL, _positive(maximum=MAX_RTOL))
    atol: float = _field(DEFAULT_ATOL, _positive())
    h: float = _field(0.0, _positive(allow_zero=True))
    max_points: int = _field(1000, _integer(0))
    max_steps: int = _field(DEFAULT_MAX_STEPS, _integer(1))
    equilibrium_tol: float = _field(DEFAULT_EQUILIBRIUM_TOL, _positive())
    period_tol: float = _field(period_tolerance(DEFAULT_RTOL), _positive())
    stop: str = _field("fixed", _choice(STOP_KINDS), new=True)
    dwell: float = _field(DEFAULT_DWELL, _positive(), new=True)

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            object.__setattr__(self, f.name, f.metadata["check"](f.name, getattr(self, f.name)))
        if self.t_transient >= self.t_end:
            raise ValueError(f"t_transient ({self.t_transient}) must be < t_end ({self.t_end})")
        if self.method == "dopri5-fixed" and self.h == 0.0:
            raise ValueError("method 'dopri5-fixed' needs a step size h")
        if self.method == "dopri5" and self.h != 0.0:
            raise ValueError("h is not used by the adaptive 'dopri5'; use 'dopri5-fixed'")
        if self.method == "auto" and self.h != 0.0:
            raise ValueError("h is not used by 'auto' (adaptive steps, switching methods)")

    @classmethod
    def resolve(
        cls,
        method: str = "rodas5p",
        t_end: float | None = None,
        t_transient: float = 0.0,
        rtol: float | None = None,
        atol: float | None = None,
        h: float | None = None,
        max_points: int = 1000,
        max_steps: int | None = None,
        equilibrium_tol: float | None = None,
        period_tol: float | None = None,
        **extra: Any,
    ) -> Settings:
        """Complete and validate settings; ``None`` takes the default.

        Defaults that depend on other fields: ``period_tol`` is
        :func:`period_tolerance` of ``rtol``; with a fixed step ``h``,
        ``max_steps`` is the number of steps to ``t_end`` plus one.
        ``extra`` are further fields (``None`` again means the default).

        The record is immutable, so the same arguments give the same record: it
        is kept (up to ``_RESOLVED_MAX`` of them) and validated once. Its key holds
        each argument's type and a float's every bit (0.0 and -0.0 apart);
        unhashable arguments are validated every time.
        """
        args = (method, t_end, t_transient, rtol, atol, h, max_points, max_steps,
                equilibrium_tol, period_tol)  # fmt: skip
        try:
            extras = tuple(sorted((k, _exact(v)) for k, v in extra.items()))
            key = (cls, tuple(map(_exact, args)), extras)
            hit = _RESOLVED.get(key)
        except TypeError:  # an unhashable argument (an array, a list)
            return cls._build(*args, **extra)
        if hit is None:
            hit = cls._build(*args, **extra)
            if len(_RESOLVED) >= _RESOLVED_MAX:
                _RESOLVED.clear()
            _RESOLVED[key] = hit
        return hit

    @classmethod
    def _build(
        cls, method: str, t_end: float | None, t_transient: float, rtol: float | None,
        atol: float | None, h: float | None, max_points: int, max_steps: int | None,
        equilibrium_tol: float | None, period_tol: float | None, **extra: Any,
    ) -> Settings:  # fmt: skip
        """:meth:`resolve` without the kept records."""
        if t_end is None:
            raise ValueError("t_end is required")
        if method not in METHODS:  # before h, so a wrong name is reported as such
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")
        rtol = DEFAULT_RTOL if rtol is None else check_real("rtol", rtol, maximum=MAX_RTOL)
        if method == "dopri5-fixed" and h is None:
            raise ValueError("method 'dopri5-fixed' needs a step size h")
        if h is not None:
            if method == "dopri5":
                raise ValueError("h is not used by the adaptive 'dopri5'; use 'dopri5-fixed'")
            if method == "auto":
                raise ValueError("h is not used by 'auto' (adaptive steps, switching methods)")
            h = check_real("h", h)
            if max_steps is None:
                max_steps = math.ceil(check_real("t_end", t_end) / h) + 1
        return cls(
            method=method,
            t_end=t_end,
            t_transient=t_transient,
            rtol=rtol,
            atol=DEFAULT_ATOL if atol is None else atol,
            h=0.0 if h is None else h,
            max_points=max_points,
            max_steps=DEFAULT_MAX_STEPS if max_steps is None else max_steps,
            equilibrium_tol=(
                DEFAULT_EQUILIBRIUM_TOL if equilibrium_tol is None else equilibrium_tol
            ),
            period_tol=period_tolerance(rtol) if period_tol is None else period_tol,
            **{k: v for k, v in extra.items() if v is not None},
        )

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> Settings:
        """Rebuild settings from :meth:`to_dict` output (e.g. a file's configuration)."""
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(f"unknown setting(s) {unknown}; known: {sorted(known)}")
        return cls(**values)

    def to_dict(self) -> dict[str, Any]:
        """The settings as plain Python values: for the config hash, file attributes, task keys.

        Fields marked new are omitted while at their default, so that a file
        written before they existed keeps its configuration hash.
        """
        return {
            f.name: getattr(self, f.name)
            for f in dataclasses.fields(self)
            if not (f.metadata["new"] and getattr(self, f.name) == f.default)
        }

    def __getitem__(self, name: str) -> Any:
        """``settings["rtol"]``: read access as for the plain dict used before."""
        if name not in self.to_dict():
            raise KeyError(name)
        return getattr(self, name)

    def replace(self, **changes: Any) -> Settings:
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def run_settings(self) -> RunSettings:
        """The :class:`~stickslip_fast.core.trajectory.RunSettings` the compiled kernels take."""
        return run_settings(
            self.t_end, self.t_transient, self.rtol, self.atol, self.h, self.max_steps,
            self.equilibrium_tol, self.period_tol, MAX_PERIOD, STOP_KINDS.index(self.stop),
            self.dwell,
        )  # fmt: skip
