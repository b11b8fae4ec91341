"""The Branch record (a continued branch with its bifurcations), its HDF5 file, and joining two
halves."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

#: Version of the HDF5 layout written by :meth:`Branch.to_hdf5`.
BRANCH_SCHEMA = 2


#: Older schemas this version still reads (see :meth:`Branch.from_hdf5`).
READABLE_BRANCH_SCHEMAS = (1, 2)


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
        import h5py

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".partial")
        try:
            with h5py.File(tmp, "w") as h5:
                a = h5.attrs
                a["kind"] = "branch"
                a["schema_version"] = BRANCH_SCHEMA
                a["param"] = self.param
                a["period"] = int(self.period)
                a["status"] = self.status
                a["system"] = json.dumps(self.system.to_dict())
                h5["values"] = self.values
                h5["points"] = self.points
                h5["T"] = self.T
                h5["multipliers_real"] = self.multipliers.real
                h5["multipliers_imag"] = self.multipliers.imag
                h5["stable"] = self.stable.astype("i1")
                h5["bifurcation_kind"] = np.array(
                    [b.kind for b in self.bifurcations], dtype=h5py.string_dtype()
                )
                h5["bifurcation_value"] = np.array([b.value for b in self.bifurcations], "f8")
                h5["bifurcation_index"] = np.array([b.index for b in self.bifurcations], "i8")
                h5["bifurcation_point"] = np.array(
                    [b.point for b in self.bifurcations], "f8"
                ).reshape(len(self.bifurcations), self.points.shape[1])
                if self.stick_count is not None:
                    h5["stick_count"] = np.asarray(self.stick_count, "i8")
                    h5["stick_time"] = np.asarray(self.stick_time, "f8")
                if self.segments is not None and any(x is not None for x in self.segments):
                    _write_segments(h5, self.segments, self.points.shape[1])
            tmp.replace(path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        return path

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
        import h5py

        from ..io.base import check_kind
        from ..model.system import System

        with h5py.File(path, "r") as h5:
            check_kind(path, h5, "branch", READABLE_BRANCH_SCHEMAS)
            kinds = [k.decode() if isinstance(k, bytes) else str(k)
                     for k in h5["bifurcation_kind"][()]]  # fmt: skip
            values = h5["values"][()]
            points = h5["points"][()]
            if "bifurcation_point" in h5:
                bif_points = h5["bifurcation_point"][()]
            else:  # schema 1: the branch point before the event
                bif_points = [points[min(int(i), len(points) - 1)]
                              for i in h5["bifurcation_index"][()]]  # fmt: skip
            bifs = [
                Bifurcation(kinds[j], float(h5["bifurcation_value"][j]),
                            int(h5["bifurcation_index"][j]), np.array(bif_points[j]))
                for j in range(len(kinds))
            ]  # fmt: skip
            stick_count = h5["stick_count"][()] if "stick_count" in h5 else None
            stick_time = h5["stick_time"][()] if "stick_time" in h5 else None
            segments = _read_segments(h5) if "segment_offsets" in h5 else None
            return cls(
                system=System.from_dict(json.loads(h5.attrs["system"])),
                param=str(h5.attrs["param"]),
                period=int(h5.attrs["period"]),
                values=values,
                points=points,
                T=h5["T"][()],
                multipliers=h5["multipliers_real"][()] + 1j * h5["multipliers_imag"][()],
                stable=h5["stable"][()].astype(bool),
                bifurcations=bifs,
                status=str(h5.attrs["status"]),
                stick_count=stick_count,
                stick_time=stick_time,
                segments=segments,
            )

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


def _write_segments(h5, segments: list, n_state: int) -> None:
    """Every point's (mesh, starts) as three flat datasets: point i's segments are rows
    ``segment_offsets[i]:segment_offsets[i + 1]`` (none: no segments) of
    ``segment_mesh`` (each segment's start as a fraction of T; the last ends at 1) and
    ``segment_starts``."""
    counts = [0 if x is None else len(x[0]) - 1 for x in segments]
    h5["segment_offsets"] = np.r_[0, np.cumsum(counts)].astype("i8")
    h5["segment_mesh"] = np.concatenate([x[0][:-1] for x in segments if x is not None])
    starts = [np.asarray(x[1], "f8") for x in segments if x is not None]
    h5["segment_starts"] = np.concatenate(starts).reshape(-1, n_state)


def _read_segments(h5) -> list:
    """The ``segments`` list of :func:`_write_segments`' datasets."""
    off = h5["segment_offsets"][()]
    mesh, starts = h5["segment_mesh"][()], h5["segment_starts"][()]
    return [
        None if b == a else (np.r_[mesh[a:b], 1.0], starts[a:b].copy())
        for a, b in zip(off[:-1], off[1:])
    ]


def segments_of(branch: Branch) -> list:
    """``branch.segments``, or None at every point where it has none."""
    return list(branch.segments) if branch.segments is not None else [None] * branch.values.size
