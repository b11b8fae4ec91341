"""A sweep's arguments checked into a :class:`_Plan`: what to compute, and so what the
result file's configuration (and its hash) holds.

:func:`~stickslip_fast.analysis.sweep.sweep` builds the plan first, before it touches a
file or a backend, so that bad arguments fail early and name themselves."""

from __future__ import annotations

import hashlib
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..base.messages import plain
from ..core.settings import Settings, check_memory, warn_if_coarse_atol
from ..io import ANALYSES, PER_VALUE_FIELDS, SweepLayout
from ..model.system import (
    SWEEPABLE,
    System,
    smallest_eps,
    warn_if_synchronous,
)
from .simulate import WORKSPACE_VECTORS

MODES = ("restart", "continuation", "continuation-both")
BACKENDS = ("local", "dask", "cuda")


# ----------------------------------------------------------------- validation
def _normalise_params(
    system: System, param, values
) -> tuple[tuple[str, ...], tuple[np.ndarray, ...]]:
    if isinstance(param, str):
        names = (param,)
        axes_in = (values,)
    elif (
        isinstance(param, (tuple, list))
        and len(param) == 2
        and all(isinstance(p, str) for p in param)
    ):
        names = tuple(param)
        if not isinstance(values, (tuple, list)) or len(values) != 2:
            raise ValueError("a 2-D sweep needs values as a tuple of two arrays, one per parameter")
        axes_in = tuple(values)
        if names[0] == names[1]:
            raise ValueError(f"the two swept parameters must differ, got {names}")
    else:
        raise ValueError(f"param must be a field name or a tuple of two, got {param!r}")
    return names, tuple(_check_axis(system, n, v) for n, v in zip(names, axes_in))


def _check_axis(system: System, name: str, vals: Any) -> np.ndarray:
    """The values of one swept field as a float array, checked vectorised.

    Every per-field rule of :class:`System` is an interval (m > 0, eta in
    [1, 10], mu >= 0, ...), so checking the smallest and the largest value
    checks them all: 1e7 values take ~0.5 s, not ~5 min of one System() per value.
    """
    if name not in SWEEPABLE:
        raise ValueError(
            f"param {name!r} cannot be swept; choose one of {list(SWEEPABLE)} "
            "(n_oscillators and drive change the state layout)"
        )
    if isinstance(vals, (list, tuple)) and any(isinstance(v, (bool, np.bool_)) for v in vals):
        raise ValueError(f"values for {name!r} must be numbers, got a boolean in {plain(vals)}")
    arr = np.asarray(vals)
    if arr.dtype.kind not in "iuf":  # strings, booleans, objects: not silently converted
        raise ValueError(f"values for {name!r} must be numbers, got an array of {arr.dtype}")
    arr = arr.astype(float)
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"values for {name!r} must be a non-empty 1-D array")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"values for {name!r} must be finite")
    for v in (float(arr.min()), float(arr.max())):
        try:
            system.replace(**{name: v})
        except ValueError as exc:
            raise ValueError(
                f"value {plain(v)} of swept param {name!r} is invalid: {exc}"
            ) from None
    return arr


def _normalise_analyses(analyses) -> tuple[str, ...]:
    if isinstance(analyses, str):
        analyses = (analyses,)
    try:
        items = tuple(analyses)
    except TypeError:
        raise ValueError(f"analyses must be a sequence of names, got {analyses!r}") from None
    unknown = [a for a in items if a not in ANALYSES]
    if unknown:
        raise ValueError(f"unknown analyses {unknown}; choose from {sorted(ANALYSES)}")
    return tuple(a for a in ANALYSES if a in items)  # canonical order, no duplicates


def _warn_order(name: str, values: np.ndarray, mode: str) -> None:
    """Continuation follows the values in array order: say so when that order is odd."""
    step = np.diff(values)
    if mode == "continuation-both" and not np.all(step > 0):
        what = "has duplicates" if np.any(step == 0) else "is not increasing"
    elif mode == "continuation" and not (np.all(step > 0) or np.all(step < 0)):
        what = "has duplicates" if np.any(step == 0) else "is not monotonic"
    else:
        return
    warnings.warn(
        f"values for {name!r} {what}; mode {mode!r} follows them in the given order "
        + ("(the 'up' branch is array order, 'down' its reverse)" if mode != "continuation" else "")
        + ", so each value starts from the previous one in that order. Sort them "
        "(np.unique) for a branch that follows the parameter.",
        UserWarning,
        stacklevel=4,
    )


def _values_digest(axes: tuple[np.ndarray, ...]) -> list[str]:
    return [
        hashlib.sha256(np.ascontiguousarray(a, dtype="<f8").tobytes()).hexdigest() for a in axes
    ]


@dataclass(frozen=True)
class _Plan:
    """Everything that determines a sweep's results, validated."""

    system: System
    names: tuple[str, ...]
    axes: tuple[np.ndarray, ...]
    mode: str
    settings: Settings
    y0: np.ndarray
    analyses: tuple[str, ...]
    backend: str = "local"

    @property
    def layout(self) -> SweepLayout:
        branches = self.mode == "continuation-both"
        return SweepLayout(
            self.names, self.axes, branches, self.settings.max_points, self.system.state_names,
            self.analyses, converged=self.settings.stop == "converged",
        )  # fmt: skip

    def config(self) -> dict[str, Any]:
        """The configuration stored in (and hashed into) the result file."""
        base = self.system.to_dict()
        for name in self.names:
            base[name] = None  # the base value of a swept field does not affect results
        config = {
            "system": base,
            "param": list(self.names),
            "n_values": [len(a) for a in self.axes],
            "values_sha256": _values_digest(self.axes),
            "mode": self.mode,
            "settings": self.settings.to_dict(),
            "y0": self.y0.tolist(),
        }
        if self.analyses:  # absent when empty, so files made before analyses existed resume
            config["analyses"] = list(self.analyses)
        if self.backend == "cuda":  # GPU points differ from the CPU's at ~1e-9: never mixed
            config["backend"] = "cuda"
        return config


def _checked_params(
    system: System, param, values
) -> tuple[tuple[str, ...], tuple[np.ndarray, ...]]:
    """The swept fields' names and checked values (first: the default atol needs them)."""
    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    return _normalise_params(system, param, values)


def _plan(system, names, axes, mode, y0, analyses, settings: Settings) -> _Plan:
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    if mode != "restart":
        _warn_order(names[0], axes[0], mode)
    if y0 is None:
        warn_if_synchronous(system, "the default start y0 (rest)", stacklevel=3)
    warn_if_coarse_atol(smallest_eps(system, names, axes), settings.atol, stacklevel=3)
    if settings.max_points == 0:
        warnings.warn(
            "max_points = 0: no Poincare points are kept, so no period is detected "
            "(period 0 for every value); only status and final state are recorded",
            UserWarning,
            stacklevel=4,
        )
    return _Plan(
        system, names, axes, mode, settings, system.initial_state(y0), _normalise_analyses(analyses)
    )


def _check_backend(backend: str, scheduler, n_workers) -> None:
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if backend != "dask" and (scheduler is not None or n_workers is not None):
        raise ValueError("scheduler and n_workers are only used with backend='dask'")


def _check_chunk_size(chunk_size) -> None:
    if chunk_size is not None and (
        isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1
    ):
        raise ValueError(f"chunk_size must be an integer >= 1, got {plain(chunk_size)}")


def _check_sweep_memory(plan: _Plan, in_memory: bool, chunk_size: int, threads: int) -> None:
    """Refuse, before allocating, a sweep whose result arrays cannot fit in memory."""
    n_state, kp = plan.system.n_state, plan.settings.max_points
    per_value = 8 * (n_state * (kp + 1) + kp + len(PER_VALUE_FIELDS) + 1)
    if in_memory:
        n_values = int(np.prod(plan.layout.grid_shape))
        what = "the in-memory results (give out= to stream them to a file)"
    else:  # a continuation unit holds a segment of chunk_size values of every chain
        n_chains = int(np.prod(plan.layout.grid_shape)) // len(plan.axes[0])
        n_values = chunk_size * (1 if plan.mode == "restart" else n_chains)
        what = f"one unit of {n_values} values (lower chunk_size)"
    check_memory(
        n_values * per_value + threads * 8 * n_state * WORKSPACE_VECTORS,
        f"{what} with n_oscillators = {plan.system.n_oscillators} and max_points = {kp}",
    )
