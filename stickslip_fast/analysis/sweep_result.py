"""What a sweep returns: :class:`SweepResult`, and :func:`load_sweep` to reopen a file."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..base.status import status_names
from ..core.poincare import ORBIT_STATUSES, STATUS_NAMES
from ..core.settings import Settings
from ..io import PER_VALUE_FIELDS, read_dataset, read_sweep
from ..model.system import System

__all__ = ["SweepResult", "load_sweep", "warn_no_orbit"]


_DATA_FIELDS = ("points", "t_points", "final_state", "done", *PER_VALUE_FIELDS)


@dataclass
class SweepResult:
    """Result of :func:`sweep`.

    Arrays have the value axes first: ``(n,)`` for a 1-D sweep, ``(n1, n2)``
    for a 2-D one, with a leading branch axis of 2 ("up", "down") for mode
    "continuation-both". When the sweep wrote a file, the arrays are read from
    it on first access.

    Attributes
    ----------
    param : str or tuple of str
    values : ndarray or tuple of ndarray
        The swept values (one array per axis).
    points : ndarray, (..., max_points, n_state)
        Poincare points in time order, NaN-padded; NaN where there is no orbit.
    t_points : ndarray, (..., max_points)
    count, period, n_steps, n_rejected, n_crossings : ndarray of int
    status : ndarray of str
        As in :class:`SimulationResult`.
    final_state : ndarray, (..., n_state)
    t_converged : ndarray of float
        With ``stop="converged"`` only: when each run was found converged (NaN
        where it reached t_end first).
    state_names : list of str
    settings : Settings
    path : Path or None
        The HDF5 file, if any.
    """

    param: str | tuple[str, str]
    values: np.ndarray | tuple[np.ndarray, np.ndarray]
    mode: str
    state_names: list[str]
    system: System
    settings: Settings
    path: Path | None = None
    _data: dict = field(default_factory=dict, repr=False)

    def _get(self, name: str) -> np.ndarray:
        if name not in self._data:
            if self.path is None:
                raise AttributeError(name)
            try:
                self._data[name] = read_dataset(self.path, name)
            except KeyError as exc:
                raise AttributeError(exc.args[0]) from None
        return self._data[name]

    # the per-value arrays (``points``, ``count``, ... ``status_code``) are properties added
    # below the class from _LAZY_FIELDS: read from memory or, lazily, from the file

    @property
    def status(self) -> np.ndarray:
        return status_names(self.status_code)

    @property
    def shape(self) -> tuple[int, ...]:
        return self.count.shape

    def column(self, name: str) -> np.ndarray:
        """One state variable of every point, shape (..., max_points)."""
        return self.points[..., self.state_names.index(name)]

    def summary(self) -> dict[str, int]:
        """How many values ended with each status."""
        st = self.status.ravel()
        return {s: int(np.sum(st == s)) for s in STATUS_NAMES if np.any(st == s)}

    def __repr__(self) -> str:
        return f"SweepResult(param={self.param!r}, shape={self.shape}, mode={self.mode!r}, status={self.summary()})"


def warn_no_orbit(result: SweepResult, names, axes, branches) -> None:
    status = result.status
    bad = ~np.isin(status, ORBIT_STATUSES)
    if not np.any(bad):
        return
    counts = {s: int(np.sum(status == s)) for s in np.unique(status[bad])}
    detail = ", ".join(f"{n} {s}" for s, n in sorted(counts.items()))
    example = ""
    if len(axes) == 1 and not branches:
        vals = axes[0][bad][:5]
        example = f" (e.g. {names[0]} = {', '.join(f'{v:g}' for v in vals)})"
    hint = ""
    if "unsettled" in counts:
        hint = (
            " 'unsettled' runs were at rest for less than `dwell` even `dwell` past"
            " t_end, too late to tell (their rest restarted, e.g. a DC belt still"
            " drifting): run longer, or use stop='converged'."
        )
    warnings.warn(
        f"{int(bad.sum())} of {status.size} values gave no orbit: {detail}{example}. "
        f"Their points are NaN; see result.status.{hint}",
        UserWarning,
        stacklevel=3,
    )


def load_sweep(path: str | Path) -> SweepResult:
    """Open a sweep file written by :func:`sweep` as a :class:`SweepResult`."""
    data = read_sweep(path)
    cfg = data["config"]
    sysd = {k: v for k, v in cfg["system"].items() if v is not None}
    system = System.from_dict(sysd)
    names = tuple(cfg["param"])
    return SweepResult(
        param=names[0] if len(names) == 1 else names,
        values=data["axes"][0] if len(names) == 1 else data["axes"],
        mode=cfg["mode"],
        state_names=data["state_names"],
        system=system,
        settings=Settings.from_dict(cfg["settings"]),
        path=Path(path),
        _data={**{k: data[k] for k in _DATA_FIELDS}, **data["analyses"]},
    )


#: Attribute -> dataset of the per-value arrays a SweepResult reads lazily.
_LAZY_FIELDS = {
    name: name
    for name in (
        "points t_points final_state count period n_steps n_rejected n_crossings sync_error "
        "lyapunov lyapunov_fit t_converged"
    ).split()
} | {"status_code": "status"}
for _attr, _name in _LAZY_FIELDS.items():
    setattr(SweepResult, _attr, property(lambda self, _n=_name: self._get(_n)))
del _attr, _name
