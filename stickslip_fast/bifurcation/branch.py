"""The Branch record (a continued branch with its bifurcations) and joining two halves; its
HDF5 file is :mod:`stickslip_fast.io.branchfile`."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

# the file's versions, defined with its schema in io/ (re-exported for older imports)
from ..io.branchfile import BRANCH_SCHEMA, READABLE_BRANCH_SCHEMAS  # noqa: F401


@dataclass
class Bifurcation:
    """A located bifurcation or branch end.

    ``kind``: "fold", "period-doubling", "neimark-sacker", "section-grazing" (the
    return map is discontinuous there: the period in time jumps because a crossing of
    dx1 = 0 appears or vanishes; the branch of P^p ends) or "stick-phase" (the number of
    stick phases per period changes: one appears or vanishes, see
    :func:`~stickslip_fast.bifurcation.stickphases.stick_phases`; the point is the first one past the
    change) or "symmetry-breaking" (in-phase orbits of disks on one motor: a multiplier
    across the disks passes +1) on orbit branches; "fold" or
    "hopf" (a complex pair of the Jacobian's eigenvalues crosses the imaginary axis) on
    equilibrium branches; "branch-point" on both (another branch of solutions crosses
    this one: det [DG; tᵀ] changes sign, a multiplier passes +1 (an eigenvalue 0) with
    no fold; for orbits: a pitchfork of a symmetric orbit, or the period-doubling
    point seen from the doubled branch). ``value``: the parameter;
    ``index``: the branch point just before it (for "section-grazing": the last point,
    within ``ds_min`` in arclength of the event); ``point``: the state there.
    """

    kind: str
    value: float
    index: int
    point: np.ndarray

    @property
    def label(self) -> str:
        return {"fold": "F", "period-doubling": "PD", "neimark-sacker": "NS",
                "section-grazing": "G", "hopf": "H", "stick-phase": "S",
                "symmetry-breaking": "SB", "branch-point": "BP"}[self.kind]  # fmt: skip


@dataclass
class Branch:
    """A branch of periodic orbits (:func:`continue_orbit`) or of equilibria
    (:func:`continue_equilibrium`, ``period = 0``).

    Attributes
    ----------
    system : System
        The system of the start (its ``param`` field is the start's value).
    param : str
        The continued :class:`System` field.
    period : int
        Crossings per period; 0 for a branch of equilibria.
    values : ndarray, shape (k,)
        The parameter at each point.
    points : ndarray, shape (k, n_state)
        The orbit's state on the section (dx1 = 0) at each point; the crossing
        continued from the start orbit's ``points[0]``. For equilibria: the
        equilibrium state.
    T : ndarray, shape (k,)
        Period in time (NaN for equilibria).
    multipliers : ndarray of complex, shape (k, n_state - 1)
        Floquet multipliers, largest modulus first. For equilibria, shape
        (k, n_state): the Jacobian's eigenvalues, largest real part first.
    stable : ndarray of bool, shape (k,)
        All multipliers inside the unit circle; for equilibria, all eigenvalues
        with a negative real part.
    bifurcations : list of Bifurcation
    status : str
        Why the branch ended: "bounds" (the last point lies on one of them),
        "max-points", "step-too-small" (the corrector failed at ds_min),
        "nonsmooth" (a section grazing, recorded in ``bifurcations``) or
        "precision-limit" (past a sharp end, in the tighter stages of
        ``sharp_ends``: the steps crawl because Newton's reach has shrunk to
        the integration's precision) or "degenerate" (orbits: at each of the
        last 10 points the shooting Jacobian had a second null direction
        within its noise, as where a nearly undamped disk makes a family of
        orbits at one parameter value; which way the branch goes is noise there).
    stick_count : ndarray of int, shape (k,), optional
        Stick phases per period at each point (all disks together; -1 where not
        computed). None for equilibria.
    stick_time : ndarray, shape (k,), optional
        Total time per period spent sticking (NaN where not computed).
    segments : list, optional
        Multiple shooting only: at each point, ``(mesh, starts)`` as in
        :attr:`Orbit.segments` (the mesh as fractions of T, and the segments' start
        states), or None at a point found by single shooting. A point whose
        multiplier is far beyond 1/eps can be integrated again only from these, not
        from its section point alone (:meth:`orbit_at`). Written to the branch file and
        read back.
    """

    system: Any
    param: str
    period: int
    values: np.ndarray
    points: np.ndarray
    T: np.ndarray
    multipliers: np.ndarray
    stable: np.ndarray
    bifurcations: list[Bifurcation] = field(default_factory=list)
    status: str = ""
    stick_count: np.ndarray | None = None
    stick_time: np.ndarray | None = None
    segments: list | None = field(default=None, repr=False)

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the branch to HDF5 (schema: docs/orbits.md, "Branch files").

        Datasets ``values`` (point), ``points`` (point, state), ``T`` (point),
        ``multipliers_real`` / ``multipliers_imag`` (point, multiplier), ``stable``
        (point), ``stick_count`` / ``stick_time`` (point; orbit branches),
        ``bifurcation_kind`` / ``bifurcation_value`` / ``bifurcation_index``
        (bifurcation), ``bifurcation_point`` (bifurcation, state); where the branch has
        :attr:`segments`, ``segment_offsets`` (point + 1), ``segment_mesh`` (segment)
        and ``segment_starts`` (segment, state); attributes
        ``kind = "branch"``, ``schema_version``, ``param``, ``period``, ``status``
        and ``system`` (JSON). Readable with
        ``xarray.open_dataset(path, engine="h5netcdf", phony_dims="sort")``.
        """
        from ..io.branchfile import write_branch

        bifs = self.bifurcations
        return write_branch(path, {
            "param": self.param, "period": int(self.period), "status": self.status,
            "system": json.dumps(self.system.to_dict()), "values": self.values,
            "points": self.points, "T": self.T, "multipliers": self.multipliers,
            "stable": self.stable, "bifurcation_kind": [b.kind for b in bifs],
            "bifurcation_value": [b.value for b in bifs],
            "bifurcation_index": [b.index for b in bifs],
            "bifurcation_point": [b.point for b in bifs], "stick_count": self.stick_count,
            "stick_time": self.stick_time, "segments": self.segments,
        })  # fmt: skip

    @classmethod
    def from_hdf5(cls, path: str | Path) -> Branch:
        """Read a branch file written by :meth:`to_hdf5`.

        Schema 1 files (before 2026-11-23) stored no bifurcation points: their
        ``Bifurcation.point`` is the branch point just before the event, good to
        ~ds only (continue again before :func:`switch_branch`).

        Raises
        ------
        ValueError
            If the file is not a branch file of a known schema (naming what is wrong).
        """
        from ..io.branchfile import read_branch
        from ..model.system import System

        d = read_branch(path)
        bifs = [
            Bifurcation(k, float(v), int(i), np.array(p))
            for k, v, i, p in zip(d["bifurcation_kind"], d["bifurcation_value"],
                                  d["bifurcation_index"], d["bifurcation_point"])
        ]  # fmt: skip
        return cls(
            system=System.from_dict(json.loads(d["system"])), param=str(d["param"]),
            period=int(d["period"]), values=d["values"], points=d["points"], T=d["T"],
            multipliers=d["multipliers"], stable=d["stable"], bifurcations=bifs,
            status=str(d["status"]), stick_count=d["stick_count"],
            stick_time=d["stick_time"], segments=d["segments"],
        )  # fmt: skip

    def orbit_at(self, i: int, *, tol: float = 1e-10, max_iter: int = 30,
                 rtol: float = 1e-11, atol: float = 1e-13) -> Any:  # fmt: skip
        """The orbit at point ``i``, corrected again: an :class:`Orbit` to plot, simulate
        from, or continue in another parameter.

        A point found by multiple shooting is corrected on its own segments
        (:attr:`segments`), the only start from which an orbit far past a multiplier of
        ~1e16 can be integrated again; a point found by single shooting by
        :func:`find_orbit` from its section point.

        Parameters
        ----------
        i : int
            The point (negative counts from the end).
        tol, max_iter, rtol, atol : float, int
            Those of :func:`find_orbit` (the defaults are :func:`continue_orbit`'s).

        Returns
        -------
        Orbit
            Check ``converged``. Its ``segments`` are set for a multiple-shooting point.

        Raises
        ------
        ValueError
            For a branch of equilibria or an index out of range.
        """
        from .multishoot_orbit import find_orbit_multiple
        from .orbits import DEFAULT_T_MAX, find_orbit
        from .returnmap import _TANGENT_ATOL

        if self.period == 0:
            raise ValueError("orbit_at needs a branch of periodic orbits, not of equilibria")
        k = self.values.size
        if not -k <= int(i) < k:
            raise ValueError(f"i must index one of the {k} points, got {i}")
        i = int(i) % k
        system = self.system.replace(**{self.param: float(self.values[i])})
        known = self.segments[i] if self.segments is not None else None
        kw = dict(tol=tol, max_iter=max_iter, rtol=rtol, atol=atol)
        if known is None:
            return find_orbit(system, self.points[i], self.period, **kw)
        return find_orbit_multiple(system, self.points[i], self.period, segments=0,
                                   t_max=DEFAULT_T_MAX, tangent_atol=_TANGENT_ATOL,
                                   T=float(self.T[i]), known=known, **kw)  # fmt: skip

    def summary(self) -> str:
        """A few lines: range, stability, bifurcations and why the branch ended."""
        v = self.values
        lines = [
            f"branch:    {'equilibria' if self.period == 0 else f'period {self.period}'} in "
            f"{self.param}, {v.size} points, "
            f"{self.param} in [{v.min():.10g}, {v.max():.10g}], ended: {self.status}",
            f"stability: {int(self.stable.sum())} stable, {int((~self.stable).sum())} unstable "
            "points",
        ]
        if v.size and self.period == 0:
            lead = self.multipliers.real.max(axis=1)
            lines.append(f"leading eigenvalue real part: {lead.min():.4g} .. {lead.max():.4g}")
        elif v.size:
            lead = np.abs(self.multipliers).max(axis=1)
            lines.append(f"|leading multiplier|: {lead.min():.4g} .. {lead.max():.4g}")
        if self.bifurcations:
            lines.append("bifurcations:")
            lines += [f"  {b.label:<3} {b.kind:<16} {self.param} = {b.value:.10g}"
                      for b in self.bifurcations]  # fmt: skip
        else:
            lines.append("bifurcations: none detected")
        return "\n".join(lines)


def join_branches(lower: Branch, upper: Branch) -> Branch:
    """One branch from two continued from the same start in opposite directions.

    ``lower`` (run with ``direction=-1``) is reversed and put before ``upper``
    (``direction=+1``), so the values run from the lower end to the upper end
    through the start, which appears once. Bifurcation indices are renumbered
    (each still names the point just before the event in the new order); the
    status reads "lower end: ...; upper end: ...".

    Raises
    ------
    ValueError
        If the two were not continued from one start (system, parameter, period, point).
    """
    same = (
        lower.system == upper.system
        and lower.param == upper.param
        and lower.period == upper.period
        and lower.values[0] == upper.values[0]
        and np.array_equal(lower.points[0], upper.points[0])
    )
    if not same:
        raise ValueError(
            "join_branches needs two branches continued from one start (the same system, "
            "parameter, period and start point)"
        )
    n_low = lower.values.size
    rev = slice(n_low - 1, 0, -1)  # lower's points except its start, in increasing order

    def cat(a, b):
        return np.concatenate([a[rev], b])

    bifs = [Bifurcation(b.kind, b.value, max(n_low - 2 - b.index, 0), b.point)
            for b in reversed(lower.bifurcations)]  # fmt: skip
    bifs += [Bifurcation(b.kind, b.value, n_low - 1 + b.index, b.point)
             for b in upper.bifurcations]  # fmt: skip
    return Branch(
        system=lower.system,
        param=lower.param,
        period=lower.period,
        values=cat(lower.values, upper.values),
        points=cat(lower.points, upper.points),
        T=cat(lower.T, upper.T),
        multipliers=cat(lower.multipliers, upper.multipliers),
        stable=cat(lower.stable, upper.stable),
        bifurcations=bifs,
        status=f"lower end: {lower.status}; upper end: {upper.status}",
        stick_count=(
            cat(lower.stick_count, upper.stick_count)
            if lower.stick_count is not None and upper.stick_count is not None
            else None
        ),  # fmt: skip
        stick_time=(
            cat(lower.stick_time, upper.stick_time)
            if lower.stick_time is not None and upper.stick_time is not None
            else None
        ),  # fmt: skip
        segments=(
            segments_of(lower)[rev] + segments_of(upper)
            if lower.segments is not None or upper.segments is not None
            else None
        ),  # fmt: skip
    )


def segments_of(branch: Branch) -> list:
    """``branch.segments``, or None at every point where it has none."""
    return list(branch.segments) if branch.segments is not None else [None] * branch.values.size
