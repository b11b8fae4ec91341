"""Pseudo-arclength continuation of periodic orbits (fixed points of the Poincare map).

:func:`continue_orbit` follows a fixed point z(s) of P^p(., lambda) in (z, lambda), where
lambda is one :class:`System` field, through folds onto the unstable side. At every point it
records the Floquet multipliers (the variational Jacobian of :mod:`stickslip_fast.orbits`)
and detects and locates folds (lambda turns back; a multiplier through +1),
period-doublings (a real multiplier through -1) and Neimark-Sacker points (a complex pair
through the unit circle). The method and its limits: docs/orbits.md.

The continuation core (:func:`pseudo_arclength`) works on any smooth map given as a
callable, so it is tested on maps whose bifurcations are known in closed form.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .messages import plain
from .model import dense_jacobian
from .orbits import (
    EQUILIBRIUM_SPEED,
    SECTION_INDEX,
    Equilibrium,
    Orbit,
    _field,
    find_orbit,
    return_map,
    stick_phases,
)
from .system import SWEEPABLE

__all__ = [
    "Branch",
    "Bifurcation",
    "continue_equilibrium",
    "continue_orbit",
    "join_branches",
    "period_doubling_start",
    "pseudo_arclength",
    "switch_branch",
    "BRANCH_SCHEMA",
    "SHARP_END_STAGES",
]

#: Version of the HDF5 layout written by :meth:`Branch.to_hdf5`.
BRANCH_SCHEMA = 2
#: Older schemas this version still reads (see :meth:`Branch.from_hdf5`).
READABLE_BRANCH_SCHEMAS = (1, 2)

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

#: A branch ends with status "precision-limit" where its last this many steps together
#: advance less than the ``ds_min`` given (possible only in the tighter stages).
STALL_WINDOW = 10

# evaluate(x) -> (ok, G (m,), DG (m, m + 1), A (m, m)): residual, its Jacobian in (z, lambda),
# and the map's Jacobian in z (whose eigenvalues are the multipliers)
Evaluator = Callable[[np.ndarray], tuple[bool, np.ndarray, np.ndarray, np.ndarray]]


@dataclass
class Bifurcation:
    """A located bifurcation or branch end.

    ``kind``: "fold", "period-doubling", "neimark-sacker", "section-grazing" (the
    return map is discontinuous there: the period in time jumps because a crossing of
    dx1 = 0 appears or vanishes; the branch of P^p ends) or "stick-phase" (the number of
    stick phases per period changes: one appears or vanishes, see
    :func:`~stickslip_fast.orbits.stick_phases`; the point is the first one past the
    change) on orbit branches; "fold" or
    "hopf" (a complex pair of the Jacobian's eigenvalues crosses the imaginary axis) on
    equilibrium branches. ``value``: the parameter;
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
                "section-grazing": "G", "hopf": "H", "stick-phase": "S"}[self.kind]  # fmt: skip


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
        the integration's precision).
    stick_count : ndarray of int, shape (k,), optional
        Stick phases per period at each point (all disks together; -1 where not
        computed). None for equilibria.
    stick_time : ndarray, shape (k,), optional
        Total time per period spent sticking (NaN where not computed).
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

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the branch to HDF5 (schema: docs/orbits.md, "Branch files").

        Datasets ``values`` (point), ``points`` (point, state), ``T`` (point),
        ``multipliers_real`` / ``multipliers_imag`` (point, multiplier), ``stable``
        (point), ``stick_count`` / ``stick_time`` (point; orbit branches),
        ``bifurcation_kind`` / ``bifurcation_value`` / ``bifurcation_index``
        (bifurcation), ``bifurcation_point`` (bifurcation, state); attributes
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

        from .system import System

        with h5py.File(path, "r") as h5:
            kind = h5.attrs.get("kind")
            if kind != "branch":
                raise ValueError(f"{path}: not a branch file (kind = {kind!r})")
            version = int(h5.attrs.get("schema_version", -1))
            if version not in READABLE_BRANCH_SCHEMAS:
                raise ValueError(
                    f"{path}: branch schema_version {version}; this version reads "
                    f"{', '.join(map(str, READABLE_BRANCH_SCHEMAS))}"
                )
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
            )

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
    )


# ------------------------------------------------------------------ the core
def _tangent(DG: np.ndarray, prev: np.ndarray) -> np.ndarray:
    """Unit null vector of DG (m x (m+1)), oriented along ``prev``."""
    m = DG.shape[0]
    A = np.vstack([DG, prev[None, :]])
    rhs = np.zeros(m + 1)
    rhs[-1] = 1.0
    t = np.linalg.solve(A, rhs)
    return t / np.linalg.norm(t)


#: What :func:`_correct` returns in place of (G, DG, A) when it stopped at the residual's
#: round-off floor: converged as far as the arithmetic allows, but not to ``tol``.
NOISE_FLOOR = "noise-floor"


def _round_off_floor(DG: np.ndarray, x: np.ndarray) -> float:
    """eps ||DG|| ||x|| (max norms): the residual that rounding errors of x's size can cause.

    The evaluation noise of a strongly unstable orbit's return map scales with its
    Jacobian: past the upper fold of Fig. 6's period-1 branch (multiplier 1e2 to 4e3), G
    at x and at x moved by ~1e-14 relative differ from the linear prediction by up to
    0.09-0.35 times this (rtol 1e-11 and 1e-13; docs/orbits.md, "Cost").
    """
    return float(np.finfo(float).eps * np.max(np.abs(DG).sum(axis=1)) * np.max(np.abs(x)))


def _correct(evaluate: Evaluator, x_pred, normal, anchor, tol, max_iter):
    """Newton on [G(x); normal . (x - anchor)] = 0 from x_pred.

    Converged when max |G| <= tol and |normal . (x - anchor)| <= tol. Fails early
    (docs/orbits.md, "Cost") where more iterations would only resample the
    evaluation's noise:

    - at the round-off floor: the Newton update is below ``tol`` and max |G|,
      above ``tol``, is below :func:`_round_off_floor` and did not halve in this
      iteration (returned with :data:`NOISE_FLOOR` in place of the data);
    - stalled: in Newton's local regime (update below sqrt(tol)), two iterations
      in a row did not halve the smallest residual so far.

    Neither accepts a point the plain test would reject.

    Returns
    -------
    (converged, x, (G, DG, A) or None or NOISE_FLOOR, iterations)
    """
    x = x_pred.copy()
    best, stalled = math.inf, 0
    for it in range(max_iter + 1):
        ok, G, DG, A = evaluate(x)
        if not ok:
            return False, x, None, it
        res = float(np.max(np.abs(G)))
        h = float(normal @ (x - anchor))
        if res <= tol and abs(h) <= tol:
            return True, x, (G, DG, A), it
        # Newton near a root gains digits quadratically: a residual that does not halve
        # is noise (the integration's or the rounding's), not progress
        if res < 0.5 * best:
            best, stalled = res, 0
        else:
            stalled += 1
        J = np.vstack([DG, normal[None, :]])
        try:
            dx = np.linalg.solve(J, -np.r_[G, h])
        except np.linalg.LinAlgError:
            return False, x, None, it
        step = float(np.max(np.abs(dx)))
        if stalled and step <= tol and abs(h) <= tol and res <= _round_off_floor(DG, x):
            return False, x, NOISE_FLOOR, it
        if stalled >= 2 and step <= math.sqrt(tol):
            return False, x, None, it
        if it == max_iter:
            break
        x = x + dx
        if not np.all(np.isfinite(x)):
            return False, x, None, it
    return False, x, None, max_iter


def _tests(A: np.ndarray, t: np.ndarray) -> dict[str, float]:
    """Test functions whose sign changes mark the bifurcations of a map's fixed points."""
    mu = np.linalg.eigvals(A)
    cplx = mu[np.abs(mu.imag) > 1e-12 * np.maximum(1.0, np.abs(mu))]
    ns = math.nan  # |mu| - 1 of the complex pair nearest the unit circle
    if cplx.size:
        ns = float((np.abs(cplx) - 1.0)[np.argmin(np.abs(np.abs(cplx) - 1.0))])
    return {
        "fold": float(t[-1]),  # d lambda / ds
        "period-doubling": float(np.linalg.det(A + np.eye(A.shape[0]))),  # prod (mu + 1)
        "neimark-sacker": ns,
    }


def _equilibrium_tests(J: np.ndarray, t: np.ndarray) -> dict[str, float]:
    """Test functions of an ODE's equilibria: the fold (d lambda / ds), and the Hopf
    point (the largest real part among complex eigenvalues of the Jacobian J: it
    changes sign when the rightmost complex pair crosses the imaginary axis)."""
    ev = np.linalg.eigvals(J)
    cplx = ev[np.abs(ev.imag) > 1e-12 * np.maximum(1.0, np.abs(ev))]
    return {
        "fold": float(t[-1]),
        "hopf": float(cplx.real.max()) if cplx.size else math.nan,
    }


def _eigs_by_real_part(J):
    ev = np.linalg.eigvals(J).astype(complex)
    return ev[np.argsort(-ev.real, kind="stable")]


def pseudo_arclength(
    evaluate: Evaluator,
    x0: np.ndarray,
    direction: float,
    bounds: tuple[float, float],
    *,
    ds: float,
    ds_min: float,
    ds_max: float,
    max_points: int,
    tol: float,
    locate_tol: float = 1e-9,
    max_corrector: int = 6,
    jump: Callable[[np.ndarray, np.ndarray], bool] | None = None,
    tests: Callable[[np.ndarray, np.ndarray], dict[str, float]] = _tests,
    spectrum: Callable[[np.ndarray], np.ndarray] | None = None,
    refine: Sequence[tuple[Evaluator, float, float]] = (),
):
    """Follow G(x) = 0, x = (z, lambda), by pseudo-arclength continuation.

    Parameters
    ----------
    evaluate : callable
        x -> (ok, G, DG, A): the residual, its Jacobian (m x (m + 1)) and the
        map's Jacobian in z (m x m; its eigenvalues are the multipliers).
    x0 : ndarray, shape (m + 1,)
        A solution (G(x0) ~ 0).
    direction : float
        +1 to start towards increasing lambda, -1 towards decreasing.
    bounds : (float, float)
        The branch ends on the first of them it reaches: a step that would
        leave [lo, hi] is corrected with lambda fixed at the bound instead.
    ds, ds_min, ds_max : float
        First, smallest and largest arclength step. The step grows by 1.5
        after a corrector that needed <= 3 iterations, halves after a failure.
    max_points : int
    tol : float
        Corrector tolerance on max |G|.
    locate_tol : float
        Bifurcations are located (Illinois secant on the test function along
        the chord between two branch points) until lambda moves less than this.
    max_corrector : int
        Most corrector iterations per step.
    jump : callable, optional
        (x_old, x_new) -> True when x_new is not on the same smooth branch
        (for orbits: the period in time jumped). Such a step, like a failed
        corrector or one that moved more than ds / 2 from the predictor, is
        rejected and ds halved. When ds falls below ds_min and the last
        rejection was a jump, the branch ends with status "nonsmooth" within
        ds_min of the discontinuity; otherwise with "step-too-small".
    tests : callable
        (A, tangent) -> {kind: value}: test functions whose sign changes mark
        bifurcations (default: those of a map's fixed points, fold /
        period-doubling / Neimark-Sacker; equilibria use fold / Hopf).
    spectrum : callable, optional
        A -> the eigenvalues recorded per point (default: by modulus, largest first).
    refine : sequence of (evaluate, tol, ds_min)
        Tighter settings to go on with, in turn, where the corrector fails at
        ``ds_min`` (not where the steps jump off the branch): the last point is
        corrected again with the next stage's evaluator and ``tol`` (or, if
        that fails, one of the few before it: :func:`_restart`; the points after
        it are dropped), and the continuation resumes from it with
        ``ds = ds_min`` and the stage's smaller ``ds_min``. The branch ends when
        no stage is left (or no recent point can be corrected with it). For sharp folds whose turn is
        narrower than ``ds_min`` or whose parameter extent is below ``tol`` over
        the residual's sensitivity to lambda (docs/limits.md).

    Returns
    -------
    xs, mults, bifs, status
        The points (k, m + 1), their multipliers (k, m), the located
        bifurcations (kind, lambda, index, x) and the reason the branch ended:
        "bounds", "max-points", "step-too-small" (the corrector failed),
        "nonsmooth" (steps kept jumping off the branch) or "precision-limit"
        (with ``refine``: the last :data:`STALL_WINDOW` steps together advanced
        less than ``ds_min``; or the last corrector stopped at the residual's
        round-off floor, :func:`_correct`, with no stage left).
    """
    ok, G, DG, A = evaluate(x0)
    if not ok:
        raise ValueError("the start could not be evaluated")
    m = G.size
    guess = np.zeros(m + 1)
    guess[-1] = 1.0 if direction >= 0 else -1.0
    t = _tangent(DG, guess)
    xs = [x0.copy()]
    spectrum = spectrum or _sorted_eigs
    test_fn = tests
    mults = [spectrum(A)]
    tests = [test_fn(A, t)]
    bifs: list[tuple[str, float, int, np.ndarray]] = []
    lo, hi = bounds
    status = "max-points"
    stages = list(refine)
    ds_min_given = ds_min
    while len(xs) < max_points:
        x = xs[-1]
        accepted = False
        jumped = False
        floored = False  # the last rejection: a corrector at the round-off floor
        on_bound = False
        while ds >= ds_min:
            x_pred = x + ds * t
            if not lo <= x_pred[-1] <= hi:
                # the step leaves the interval: end on its bound (lambda fixed there)
                edge = x_pred.copy()
                edge[-1] = hi if x_pred[-1] > hi else lo
                e_lam = np.zeros_like(x)
                e_lam[-1] = 1.0
                okc, x_new, data, its = _correct(evaluate, edge, e_lam, edge, tol, max_corrector)
                if okc and not (jump is not None and jump(x, x_new)):
                    on_bound = True
                    accepted = True
                    break
                floored = data is NOISE_FLOOR
                ds *= 0.5
                continue
            okc, x_new, data, its = _correct(evaluate, x_pred, t, x_pred, tol, max_corrector)
            jumped = False
            floored = data is NOISE_FLOOR
            if okc:
                jumped = bool(jump is not None and jump(x, x_new))
                # a corrector that went far from the predictor has left the branch
                if not jumped and np.linalg.norm(x_new - x_pred) <= 0.5 * ds:
                    accepted = True
                    break
            ds *= 0.5
        if not accepted:
            restart = None
            while not jumped and stages and restart is None:
                # a sharp end: correct a recent point again with tighter settings, go on
                evaluate, tol, ds_min_next = stages.pop(0)
                restart = _restart(evaluate, xs, tol, max_corrector)
                if restart is not None:
                    ds, ds_min = ds_min, min(ds_min, ds_min_next)
            if restart is None:
                status = "nonsmooth" if jumped else "step-too-small"
                if floored:  # the residual's noise, not the step, stopped the corrector
                    status = "precision-limit"
                break
            j, x_re, (_, DG, A) = restart
            t = _tangent(DG, xs[j] - xs[j - 1] if j > 0 else t)
            del xs[j + 1 :], mults[j + 1 :], tests[j + 1 :]
            xs[j] = x_re
            mults[j] = spectrum(A)
            tests[j] = test_fn(A, t)
            bifs = [b for b in bifs if b[2] < j]
            continue
        G, DG, A = data
        t_new = _tangent(DG, t)
        te = test_fn(A, t_new)
        k = len(xs) - 1
        for kind, prev in tests[-1].items():
            cur = te[kind]
            if math.isfinite(prev) and math.isfinite(cur) and prev * cur < 0:
                loc = _locate(evaluate, x, x_new, kind, prev, cur, t, tol, locate_tol, test_fn)
                if loc is not None:
                    bifs.append((kind, float(loc[-1]), k, loc))
        xs.append(x_new)
        mults.append(spectrum(A))
        tests.append(te)
        t = t_new
        if on_bound:
            status = "bounds"
            break
        if len(xs) > STALL_WINDOW:
            # only the tighter stages take steps below ds_min: a crawl there means that
            # Newton's reach has shrunk to the integration's precision (docs/limits.md)
            last = np.asarray(xs[-STALL_WINDOW - 1 :])
            if np.linalg.norm(np.diff(last, axis=0), axis=1).sum() < ds_min_given:
                status = "precision-limit"
                break
        if its <= 3:
            ds = min(ds * 1.5, ds_max)
    return np.array(xs), np.array(mults), bifs, status


def _restart(
    evaluate: Evaluator, xs: list[np.ndarray], tol: float, max_corrector: int, back: int = 6
) -> tuple[int, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]] | None:
    """A recent branch point corrected again (with ``evaluate`` and ``tol``), or None.

    Tries the last ``back`` points, newest first, each on the hyperplane through it
    normal to the chord from its predecessor, then with lambda fixed; a result is
    kept if it lies closer to the old point than half that chord (the same branch).
    A point computed to a looser tolerance near a sharp fold can lie past the fold
    (its lambda off by ~tol / |dG/dlambda|), where neither has a solution: the
    search then goes back along the branch. Returns (index, point, (G, DG, A)).
    """
    e_lam = np.zeros_like(xs[-1])
    e_lam[-1] = 1.0
    for j in range(len(xs) - 1, max(len(xs) - 1 - back, -1), -1):
        chord = xs[j] - xs[j - 1] if j > 0 else e_lam
        reach = 0.5 * float(np.linalg.norm(chord)) if j > 0 else math.inf
        for normal in (chord / np.linalg.norm(chord), e_lam):
            okc, x, data, _ = _correct(evaluate, xs[j], normal, xs[j], tol, max_corrector)
            if okc and np.linalg.norm(x - xs[j]) <= reach:
                return j, x, data
    return None


def _sorted_eigs(A):
    ev = np.linalg.eigvals(A).astype(complex)
    return ev[np.argsort(-np.abs(ev), kind="stable")]


def _locate(evaluate, xa, xb, kind, fa, fb, t_a, tol, locate_tol, test_fn=_tests):
    """Illinois secant in sigma in [0, 1] on the chord xa -> xb, correcting each point."""
    chord = xb - xa
    normal = chord / np.linalg.norm(chord)
    a, b = 0.0, 1.0
    side = 0
    x_best = None
    lam_prev = math.inf
    for _ in range(60):
        sig = (a * fb - b * fa) / (fb - fa)
        if not a < sig < b:
            sig = 0.5 * (a + b)
        anchor = xa + sig * chord
        okc, x, data, _ = _correct(evaluate, anchor, normal, anchor, tol, 8)
        if not okc:
            return x_best
        _, DG, A = data
        f = test_fn(A, _tangent(DG, t_a))[kind]
        x_best = x
        if abs(x[-1] - lam_prev) <= locate_tol or f == 0.0 or b - a < 1e-14:
            return x
        lam_prev = x[-1]
        if f * fa > 0:
            a, fa = sig, f
            if side == -1:
                fb *= 0.5
            side = -1
        else:
            b, fb = sig, f
            if side == 1:
                fa *= 0.5
            side = 1
    return x_best


# ------------------------------------------------------------------ orbits
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


def _orbit_evaluator(
    system0,
    param: str,
    p: int,
    rtol: float,
    atol: float,
    fd_step: float,
    periods: dict[bytes, float] | None = None,
):
    """The residual G(z, lambda) = P^p(z) - z of an orbit branch, and its helpers.

    Returns ``(evaluate, full, system_at, periods)``: ``evaluate(x)`` for
    :func:`pseudo_arclength` (x = section coordinates and lambda; the map's
    Jacobian in z and its derivative in lambda from the variational equations
    and the parameter sensitivity, integrated together), ``full(x)`` the state
    on the section, ``system_at(lam)`` and
    ``periods`` (the return time of every evaluated x, keyed by its bytes; pass
    a dict to share it between evaluators of different tolerances).
    """
    n = system0.n_state
    mask = np.arange(n) != SECTION_INDEX
    kw = dict(rtol=rtol, atol=atol)

    def full(x):
        z = np.zeros(n)
        z[mask] = x[:-1]
        return z

    def system_at(lam):
        return dataclasses.replace(system0, **{param: float(lam)})

    cache: dict[bytes, Any] = {}
    if periods is None:
        periods = {}

    def evaluate(x):
        key = x.tobytes()
        if key in cache:
            return cache[key]
        lam = float(x[-1])
        try:
            s = system_at(lam)
        except ValueError:  # outside the parameter's valid range
            return False, None, None, None
        z = full(x)
        # [D_z P^p, dP^p/dlambda] in one integration: the tangents and the parameter
        # sensitivity together (a central difference of the map would take two more)
        st, pts, times, jac_full = return_map(s, z, p, param=param, param_step=fd_step, **kw)
        if st != "ok":
            return False, None, None, None
        jac = jac_full[:, :-1]
        G = pts[-1][mask] - x[:-1]
        DG = jac_full.copy()
        DG[:, :-1] -= np.eye(n - 1)
        out = (True, G, DG, jac)
        periods[key] = float(times[-1])
        cache.clear()
        cache[key] = out
        return out

    return evaluate, full, system_at, periods


def continue_orbit(
    orbit: Orbit,
    param: str,
    bounds: tuple[float, float],
    *,
    ds: float = 0.01,
    ds_min: float = 1e-8,
    ds_max: float = 0.05,
    max_points: int = 200,
    direction: float = 1.0,
    tol: float = 1e-10,
    rtol: float = 1e-11,
    atol: float = 1e-13,
    fd_step: float = 1e-7,
    stick_events: bool = True,
    sharp_ends: bool = True,
) -> Branch:
    """Continue a periodic orbit in one parameter (pseudo-arclength).

    Parameters
    ----------
    orbit : Orbit
        A converged orbit from :func:`find_orbit`.
    param : str
        A :class:`System` field (one of ``SWEEPABLE``), e.g. "eta".
    bounds : (float, float)
        The parameter interval; it must contain the orbit's value.
    ds, ds_min, ds_max : float
        First, smallest and largest step in arclength (section coordinates and
        the parameter together).
    max_points : int
        Most branch points.
    direction : float
        +1: start towards increasing ``param``; -1: decreasing.
    tol : float
        Corrector tolerance on ``max |P^p(z) - z|``.
    rtol, atol : float
        Integration tolerances of the return map.
    fd_step : float
        Relative step of the central difference of the vector field and its
        Jacobian in the parameter, which drives the parameter sensitivity that
        gives dP/dlambda (one-sided at the edge of the parameter's valid range;
        see :func:`~stickslip_fast.orbits.return_map`).
    stick_events : bool
        Record the stick phases of every point (``Branch.stick_count``,
        ``stick_time``; :func:`~stickslip_fast.orbits.stick_phases`) and locate
        every change of their number between two points (bisection on the
        branch to 1e-8 in the parameter) as a "stick-phase" bifurcation.
    sharp_ends : bool
        Where the corrector fails at ``ds_min``, go on with the tighter
        settings of :data:`SHARP_END_STAGES` in turn (corrector tolerance,
        integration tolerances, smallest step; each only where tighter than the
        ones given), from the last point corrected again with them. This passes
        folds narrower than the defaults resolve, e.g. both ends of Fig. 6's
        period-1 branch (docs/limits.md). The branch keeps the tighter settings
        from there on; ``T`` and the points are those of the stage that
        computed them.

    Returns
    -------
    Branch

    Raises
    ------
    ValueError
        For an unconverged orbit, an unknown ``param``, bounds that do not
        contain the start, or non-positive step sizes (naming the argument).
    """
    if not isinstance(orbit, Orbit) or not orbit.converged:
        raise ValueError("orbit must be a converged Orbit from find_orbit")
    lam0, lo, hi = _check_args(orbit.system, "orbit", param, bounds, ds, ds_min, ds_max, tol,
                               max_points)  # fmt: skip
    system0 = orbit.system
    p = orbit.period
    evaluate, full, system_at, periods = _orbit_evaluator(system0, param, p, rtol, atol, fd_step)
    kw = dict(rtol=rtol, atol=atol)
    mask = np.arange(system0.n_state) != SECTION_INDEX

    def jump(x_old, x_new):
        t_old = periods.get(x_old.tobytes(), math.nan)
        t_new = periods.get(x_new.tobytes(), math.nan)
        if not abs(t_new - t_old) <= 0.05 * t_old:
            return True
        # a rest point is a fixed point of the map too (near a stable focus): not the branch
        f = _field(system_at(x_new[-1]), full(x_new))
        return bool(np.max(np.abs(f)) < EQUILIBRIUM_SPEED)

    refine = []
    if sharp_ends:
        cur = (tol, rtol, atol, ds_min)
        for stage in SHARP_END_STAGES:
            nxt = tuple(min(a, b) for a, b in zip(cur, stage))
            if nxt != cur:
                ev, _, _, _ = _orbit_evaluator(system0, param, p, nxt[1], nxt[2], fd_step,
                                               periods)  # fmt: skip
                refine.append((ev, nxt[0], nxt[3]))
                cur = nxt
    x0 = np.r_[orbit.points[0][mask], lam0]
    evaluate(x0)
    xs, mults, bifs, status = pseudo_arclength(
        evaluate, x0, direction, (lo, hi), ds=ds, ds_min=ds_min, ds_max=ds_max,
        max_points=max_points, tol=tol, jump=jump, refine=refine,
    )  # fmt: skip
    if status == "nonsmooth":
        # the fixed point of P^p ends: its return time jumps (a crossing of the section
        # appears or vanishes: the orbit grazes dx1 = 0), within ds_min of the last point
        bifs.append(("section-grazing", float(xs[-1][-1]), len(xs) - 1, xs[-1].copy()))
    points = np.array([full(x) for x in xs])
    T = np.empty(len(xs))
    for i, x in enumerate(xs):
        T[i] = periods.get(x.tobytes(), math.nan)
        if not math.isfinite(T[i]):
            _, _, times, _ = return_map(system_at(x[-1]), full(x), p, tangents=False, **kw)
            T[i] = times[-1]
    stick_count = stick_time = None
    if stick_events:
        stick_count = np.full(len(xs), -1, dtype=np.int64)
        stick_time = np.full(len(xs), np.nan)

        def geometry(x, T_x):
            d = stick_phases(system_at(x[-1]), full(x), T_x)
            return d.size, float(d.sum())

        for i, x in enumerate(xs):
            if math.isfinite(T[i]):
                try:
                    stick_count[i], stick_time[i] = geometry(x, T[i])
                except ValueError:  # the orbit could not be sampled: left as not computed
                    pass
        for i in range(len(xs) - 1):
            a, b = stick_count[i], stick_count[i + 1]
            if a >= 0 and b >= 0 and a != b:
                loc = _locate_change(
                    evaluate, xs[i], xs[i + 1], a,
                    lambda x: geometry(x, periods.get(x.tobytes(), math.nan))[0],
                    tol, 1e-8,
                )  # fmt: skip
                bifs.append(("stick-phase", float(loc[-1]), i, loc))
        bifs.sort(key=lambda b: (b[2], b[1] if direction >= 0 else -b[1]))
    return Branch(
        system=system0,
        param=param,
        period=p,
        values=xs[:, -1].copy(),
        points=points,
        T=T,
        multipliers=mults,
        stable=np.all(np.abs(mults) < 1.0, axis=1),
        bifurcations=[Bifurcation(k, v, i, full(x)) for k, v, i, x in bifs],
        status=status,
        stick_count=stick_count,
        stick_time=stick_time,
    )


def _locate_change(evaluate, xa, xb, count_a, count_at, tol, locate_tol):
    """Bisection on the chord xa -> xb (each trial corrected onto the branch) for where
    the integer ``count_at(x)`` stops being ``count_a``; returns the first point past it
    (xb if no trial converges), within ``locate_tol`` in the parameter."""
    chord = xb - xa
    normal = chord / np.linalg.norm(chord)
    a, b = 0.0, 1.0
    x_past = xb
    for _ in range(60):
        if abs(chord[-1]) * (b - a) <= locate_tol:
            break
        sig = 0.5 * (a + b)
        anchor = xa + sig * chord
        okc, x, _, _ = _correct(evaluate, anchor, normal, anchor, tol, 8)
        if not okc:
            break
        try:
            same = count_at(x) == count_a
        except ValueError:  # the orbit could not be sampled there
            break
        if same:
            a = sig
        else:
            b = sig
            x_past = x
    return x_past


# ------------------------------------------------------------ branch switching
#: Offsets along the -1 eigenvector tried by :func:`switch_branch`, largest first: the
#: doubled orbit's amplitude grows like sqrt(|lambda - lambda_PD|), and in the stiff
#: friction layer the quadratic regime can be very narrow.
SWITCH_DELTAS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7)


def period_doubling_start(
    evaluate_double: Evaluator,
    x_pd: np.ndarray,
    v: np.ndarray,
    delta: float,
    *,
    tol: float,
    max_corrector: int = 8,
) -> tuple[bool, np.ndarray]:
    """A point of the period-doubled branch near a period-doubling point.

    At a period-doubling point x_pd = (z*, lambda*) of a fixed point of P^p, with
    D_z P^p v = -v, the branch of fixed points of P^2p that are not fixed points
    of P^p crosses the p-branch, tangent to (v, 0): along it z = z* + delta v +
    O(delta^2) and lambda - lambda* = O(delta^2). The predictor (z* + delta v,
    lambda*) is corrected by Newton on G_2p(x) = 0 within the hyperplane
    v . (z - z*) = delta (lambda free).

    Parameters
    ----------
    evaluate_double : callable
        The evaluator of P^2p (see :func:`pseudo_arclength`).
    x_pd : ndarray, shape (m + 1,)
        The period-doubling point (z*, lambda*).
    v : ndarray, shape (m,)
        An eigenvector of D_z P^p(z*) for the multiplier -1.
    delta : float
        Offset along v (v is normalised first).
    tol : float
        Corrector tolerance on max |G_2p|.
    max_corrector : int
        Most Newton iterations.

    Returns
    -------
    ok, x
        Whether the corrector converged, and the point (z, lambda). It may still
        be a fixed point of P^p (for a delta too large): check that.
    """
    v = np.asarray(v, dtype=float)
    w = np.r_[v / np.linalg.norm(v), 0.0]
    x_pred = np.asarray(x_pd, dtype=float) + delta * w
    ok, x, _, _ = _correct(evaluate_double, x_pred, w, x_pred, tol, max_corrector)
    return bool(ok), x


def switch_branch(
    branch: Branch,
    bifurcation: Bifurcation | int,
    *,
    deltas: tuple[float, ...] = SWITCH_DELTAS,
    tol: float = 1e-10,
    rtol: float = 1e-11,
    atol: float = 1e-13,
    fd_step: float = 1e-7,
) -> Orbit:
    """The period-doubled orbit born at a period-doubling point of an orbit branch.

    Parameters
    ----------
    branch : Branch
        A branch of period-p orbits (:func:`continue_orbit`).
    bifurcation : Bifurcation or int
        One of ``branch.bifurcations`` (or its index there), of kind
        "period-doubling".
    deltas : tuple of float
        Offsets along the -1 eigenvector to try, in order (:func:`period_doubling_start`).
        The first that gives a fixed point of P^2p that is not one of P^p wins.
    tol, rtol, atol, fd_step
        As for :func:`continue_orbit`.

    Returns
    -------
    Orbit
        Of period 2p, at a parameter value near the bifurcation's (``orbit.system``
        holds it), polished by :func:`find_orbit`. Continue it away from the
        bifurcation with ``continue_orbit(orbit, branch.param, bounds,
        direction=np.sign(getattr(orbit.system, branch.param) - bifurcation.value))``.
        If no offset works, the orbit is returned with ``converged = False``
        and a ``message`` saying so.

    Raises
    ------
    ValueError
        For a branch of equilibria, a bifurcation that is not a period-doubling
        of this branch, or non-positive deltas (naming the argument).
    """
    if not isinstance(branch, Branch) or branch.period < 1:
        raise ValueError("branch must be a Branch of periodic orbits (continue_orbit)")
    if isinstance(bifurcation, (int, np.integer)) and not isinstance(bifurcation, bool):
        if not 0 <= bifurcation < len(branch.bifurcations):
            raise ValueError(
                f"bifurcation index {bifurcation} out of range: the branch has "
                f"{len(branch.bifurcations)} bifurcations"
            )
        bifurcation = branch.bifurcations[int(bifurcation)]
    if not isinstance(bifurcation, Bifurcation) or bifurcation.kind != "period-doubling":
        kind = getattr(bifurcation, "kind", type(bifurcation).__name__)
        raise ValueError(f"bifurcation must be a period-doubling of the branch, got {kind!r}")
    if not deltas or not all(isinstance(d, (int, float)) and math.isfinite(d) and d > 0
                             for d in deltas):  # fmt: skip
        raise ValueError(f"deltas must be finite numbers > 0, got {deltas!r}")
    p = branch.period
    system0 = branch.system
    n = system0.n_state
    mask = np.arange(n) != SECTION_INDEX
    lam_pd = float(bifurcation.value)
    z_pd = np.asarray(bifurcation.point, dtype=float)
    s_pd = dataclasses.replace(system0, **{branch.param: lam_pd})
    st, _, _, jac = return_map(s_pd, z_pd, p, rtol=rtol, atol=atol)
    if st != "ok":
        raise ValueError(f"the return map fails at the bifurcation point: {st}")
    mu, vecs = np.linalg.eig(jac)
    k = int(np.argmin(np.abs(mu + 1.0)))
    v = np.real(vecs[:, k])
    evaluate2, full, system_at, _ = _orbit_evaluator(system0, branch.param, 2 * p, rtol, atol,
                                                     fd_step)  # fmt: skip
    x_pd = np.r_[z_pd[mask], lam_pd]
    last = None
    tried = []
    for delta in deltas:
        ok, x = period_doubling_start(evaluate2, x_pd, v, delta, tol=tol)
        tried.append(delta)
        if not ok:
            continue
        s = system_at(x[-1])
        z = full(x)
        st_p, pts_p, _, _ = return_map(s, z, p, tangents=False, rtol=rtol, atol=atol)
        # a fixed point of P^p lies on the hyperplane too: the doubled orbit's P^p image is
        # its other half, ~2 delta away
        if st_p != "ok" or np.max(np.abs(pts_p[-1][mask] - z[mask])) < 0.5 * delta * np.max(
            np.abs(v / np.linalg.norm(v))
        ):
            continue
        last = find_orbit(s, z, 2 * p, tol=tol, rtol=rtol, atol=atol)
        if last.converged:
            return last
    if last is None:
        last = find_orbit(s_pd, z_pd, 2 * p, tol=tol, rtol=rtol, atol=atol, max_iter=0)
    last.converged = False
    last.stable = False
    last.message = (
        f"no period-{2 * p} orbit found along the -1 eigenvector (offsets tried: "
        f"{', '.join(f'{d:g}' for d in tried)})"
    )
    if last.status == "converged":
        last.status = "no-progress"
    return last


# ------------------------------------------------------------------ equilibria
def continue_equilibrium(
    equilibrium: Equilibrium,
    param: str,
    bounds: tuple[float, float],
    *,
    ds: float = 0.01,
    ds_min: float = 1e-8,
    ds_max: float = 0.05,
    max_points: int = 200,
    direction: float = 1.0,
    tol: float = 1e-12,
    fd_step: float = 1e-7,
) -> Branch:
    """Continue an equilibrium (steady sliding, the stalled motor) in one parameter.

    Pseudo-arclength continuation of f(y; lambda) = 0 with the analytic
    Jacobian in y (:func:`stickslip_fast.model.dense_jacobian`) and a central
    difference in lambda. Along the branch it records the Jacobian's
    eigenvalues and the stability, and locates (to ~1e-9 in the parameter)
    folds (lambda turns back: an eigenvalue through 0) and Hopf points (a
    complex pair crosses the imaginary axis: the rightmost complex pair's
    real part changes sign).

    Parameters
    ----------
    equilibrium : Equilibrium
        A converged equilibrium from :func:`find_equilibrium`.
    param, bounds, ds, ds_min, ds_max, max_points, direction
        As for :func:`continue_orbit` (arclength in the full state and the parameter).
    tol : float
        Corrector tolerance on ``max |f(y)|``.
    fd_step : float
        Relative step of the central difference df/dlambda (one-sided at the
        edge of the parameter's valid range, e.g. eta = 1 or 10).

    Returns
    -------
    Branch
        With ``period = 0``, ``T`` NaN, ``multipliers`` the eigenvalues
        (largest real part first), and bifurcations of kinds "fold" and "hopf".

    Raises
    ------
    ValueError
        For an unconverged equilibrium, an unknown ``param``, bounds that do
        not contain the start, or non-positive step sizes (naming the argument).
    """
    if not isinstance(equilibrium, Equilibrium) or not equilibrium.converged:
        raise ValueError("equilibrium must be a converged Equilibrium from find_equilibrium")
    system0 = equilibrium.system
    lam0, lo, hi = _check_args(system0, "equilibrium", param, bounds, ds, ds_min, ds_max, tol,
                               max_points)  # fmt: skip
    nosc, dc = system0.n_oscillators, system0.is_dc_motor

    def system_at(lam):
        return dataclasses.replace(system0, **{param: float(lam)})

    def evaluate(x):
        y, lam = x[:-1], float(x[-1])
        try:
            s = system_at(lam)
        except ValueError:  # outside the parameter's valid range
            return False, None, None, None
        G = _field(s, y)
        J = dense_jacobian(y, s.to_array(), nosc, dc)
        dlam = _difference(lambda v: _field(system_at(v), y), lam,
                           fd_step * max(1.0, abs(lam)), G)  # fmt: skip
        if dlam is None or not (
            np.all(np.isfinite(G)) and np.all(np.isfinite(J)) and np.all(np.isfinite(dlam))
        ):
            return False, None, None, None
        return True, G, np.hstack([J, dlam[:, None]]), J

    x0 = np.r_[equilibrium.state, lam0]
    xs, eigs, bifs, status = pseudo_arclength(
        evaluate, x0, direction, (lo, hi), ds=ds, ds_min=ds_min, ds_max=ds_max,
        max_points=max_points, tol=tol, tests=_equilibrium_tests, spectrum=_eigs_by_real_part,
    )  # fmt: skip
    return Branch(
        system=system0,
        param=param,
        period=0,
        values=xs[:, -1].copy(),
        points=xs[:, :-1].copy(),
        T=np.full(len(xs), np.nan),
        multipliers=eigs,
        stable=np.all(eigs.real < 0.0, axis=1),
        bifurcations=[Bifurcation(k, v, i, x[:-1].copy()) for k, v, i, x in bifs],
        status=status,
    )
