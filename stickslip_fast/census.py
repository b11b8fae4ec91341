"""Attractor census: every attractor at every parameter value, with basin fractions.

A census runs many initial states (*starts*) at each value of one parameter,
in parallel over all (value, start) pairs, and groups the runs of each value
into attractors: periodic orbits (identified by their Poincare points up to a
cyclic shift), equilibria (steady sliding; identified by their state), stalled
motors, and runs with no period <= 64 ("unresolved": chaos, quasi-periodicity,
a long period or a transient longer than the run). The attractors of
neighbouring values are then matched into *tracks* (as Attractors.jl's global
continuation does), so one attractor keeps one id along the sweep and the
births and deaths of tracks tell bifurcations apart from the zero-state start
merely crossing a basin boundary.

The raw runs (the expensive part) stream to HDF5 and resume after a kill; the
grouping and tracking (cheap, deterministic) are recomputed from the raw runs
and stored in the same file (schema in :mod:`stickslip_fast.io`, census
section, and docs/file-format.md).

Each pair runs through :func:`stickslip_fast.sweep.compute_continuation_chunk`
(chains of length one, one per pair), the same pure function the sweeps and the
Dask backend use, so a census run of (value, start) is bit-identical to
``simulate(system.replace(param=value), y0=start, ...)`` with the same settings.
"""

from __future__ import annotations

import contextlib
import hashlib
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .io import CensusFile, CensusLayout, read_census, write_census_classification
from .poincare import STATUS_NAMES
from .settings import DEFAULT_EQUILIBRIUM_TOL, STOP_KINDS, Settings
from .simulate import MAX_PERIOD
from .system import SWEEPABLE, System

__all__ = [
    "census",
    "CensusResult",
    "Attractor",
    "Track",
    "default_box",
    "sample_starts",
    "classify_census",
    "load_census",
    "KINDS",
    "STOP_RULES",
]

#: Attractor kinds, in the order of their integer codes in the file.
KINDS = ("orbit", "equilibrium", "stalled", "unresolved")
K_ORBIT, K_EQUILIBRIUM, K_STALLED, K_UNRESOLVED = range(4)
#: Stop rules (as :func:`simulate`): "fixed" integrates every run to t_end;
#: "converged" ends a run once its points repeat or it has come to rest.
STOP_RULES = STOP_KINDS
#: Default identity tolerance relative to the period tolerance (see :func:`census`).
IDENTITY_FACTOR = 100.0
#: Default track-matching threshold, as a fraction of the census' spread per variable.
DEFAULT_TRACK_THRESHOLD = 0.1
#: Default Poincare points kept per run: enough to detect every period <= 64.
DEFAULT_CENSUS_POINTS = 2 * MAX_PERIOD
_BACKENDS = ("local", "dask")
_ST_OK = STATUS_NAMES.index("ok")
_ST_EQ = STATUS_NAMES.index("equilibrium")
_ST_STALLED = STATUS_NAMES.index("stalled")


# ------------------------------------------------------------------ the starts
def default_box(system: System, param: str | None = None, values=None) -> np.ndarray:
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
    every value, so one set of starts serves the whole sweep.

    Parameters
    ----------
    system : System
    param : str, optional
        The swept field.
    values : array_like, optional
        Its values.

    Returns
    -------
    ndarray, shape (n_state, 2)
    """
    systems = [system]
    if param is not None and values is not None:
        systems = [system.replace(**{param: float(v)}) for v in np.unique(values)]
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


# ------------------------------------------------------------------ the result
@dataclass
class Attractor:
    """One attractor found at one parameter value.

    Attributes
    ----------
    id : int
        Its track (the same id at every value along a continuous branch).
    kind : str
        "orbit", "equilibrium", "stalled" or "unresolved" (no period <= 64).
    period : int
        Period in Poincare points (0 for equilibria, stalls and unresolved).
    fraction : float
        Share of all starts of this value that reach it.
    count : int
        Number of starts that reach it.
    points : ndarray, (period, n_state)
        The orbit's Poincare points rotated to begin at the smallest x1; the
        state for an equilibrium or stall (one row); the last stored points of
        the first run for "unresolved".
    first_start : int
        Lowest start index that reaches it (its points come from that run).
    """

    id: int
    kind: str
    period: int
    fraction: float
    count: int
    points: np.ndarray
    first_start: int


@dataclass
class Track:
    """An attractor followed over neighbouring values.

    ``birth`` and ``death`` are value indices of its first and last value;
    ``born`` / ``dies`` say whether that happens inside the range (a birth at
    index 0 or a death at the last index is only the edge of the sweep).
    """

    id: int
    kind: str
    birth: int
    death: int
    born: bool
    dies: bool
    periods: tuple[int, ...]


@dataclass
class CensusResult:
    """Result of :func:`census`.

    Attributes
    ----------
    param : str
    values : ndarray, (n_values,)
    starts : ndarray, (n_starts, n_state)
    labels : ndarray of int, (n_values, n_starts)
        The track id of the attractor each run reached; -1 where the run
        failed (see ``status``) or gave no Poincare crossing.
    status : ndarray of str, (n_values, n_starts)
        Every run's status (as :func:`simulate`; "missing" if not computed).
    period : ndarray of int, (n_values, n_starts)
    attractors : list of list of Attractor
        Per value, its attractors (most starts first).
    tracks : list of Track
    births, deaths : list of (track id, value)
        Tracks that start or end inside the range.
    failed_fraction : ndarray, (n_values,)
        Share of starts labelled -1 (the fractions of a value sum to 1 with it).
    """

    param: str
    values: np.ndarray
    starts: np.ndarray
    labels: np.ndarray
    status_code: np.ndarray
    period: np.ndarray
    attractors: list
    tracks: list
    state_names: list
    system: System
    settings: dict
    path: Path | None = None
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def status(self) -> np.ndarray:
        names = np.array(STATUS_NAMES + ("missing",), dtype=object)
        codes = self.status_code
        return names[np.where(codes < 0, len(STATUS_NAMES), codes)]

    @property
    def births(self) -> list[tuple[int, float]]:
        return [(t.id, float(self.values[t.birth])) for t in self.tracks if t.born]

    @property
    def deaths(self) -> list[tuple[int, float]]:
        return [(t.id, float(self.values[t.death])) for t in self.tracks if t.dies]

    @property
    def failed_fraction(self) -> np.ndarray:
        return np.mean(self.labels < 0, axis=1)

    def fractions(self) -> np.ndarray:
        """Basin fractions as a (n_values, n_tracks) array (0 where a track is absent)."""
        out = np.zeros((len(self.values), len(self.tracks)))
        for i, atts in enumerate(self.attractors):
            for a in atts:
                out[i, a.id] = a.fraction
        return out

    def attractor_of(self, value_index: int, start: int) -> Attractor | None:
        """The attractor that start ``start`` reached at value ``value_index``."""
        lab = int(self.labels[value_index, start])
        for a in self.attractors[value_index]:
            if a.id == lab:
                return a
        return None

    def __repr__(self) -> str:
        n_att = sum(len(a) for a in self.attractors)
        return (
            f"CensusResult(param={self.param!r}, values={len(self.values)}, "
            f"starts={len(self.starts)}, attractors={n_att}, tracks={len(self.tracks)})"
        )


# ---------------------------------------------------------- grouping and tracks
def _canonical_orbit(points: np.ndarray, count: int, period: int) -> np.ndarray:
    """The last ``period`` points, rotated to begin at the smallest x1."""
    last = points[count - period : count]
    k = int(np.argmin(last[:, 0]))
    return np.roll(last, -k, axis=0)


def _same_cycle(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    """Equal up to a cyclic shift, max norm, within tol (1 + largest |coordinate|)."""
    if a.shape != b.shape:
        return False
    thr = tol * (1.0 + max(np.max(np.abs(a)), np.max(np.abs(b))))
    for s in range(len(a)):
        if np.max(np.abs(a - np.roll(b, -s, axis=0))) <= thr:
            return True
    return False


def _hausdorff(a: np.ndarray, b: np.ndarray, scale: np.ndarray) -> float:
    """Hausdorff distance of two point sets, max norm after dividing by ``scale``."""
    d = np.max(np.abs(a[:, None, :] - b[None, :, :]) / scale, axis=-1)
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


def _match_class(kind: int) -> int:
    """Kinds that may continue each other along a track (orbits and unresolved may)."""
    return 0 if kind in (K_ORBIT, K_UNRESOLVED) else kind


def classify_census(
    values: np.ndarray,
    raw: dict[str, np.ndarray],
    *,
    period_tol: float,
    identity_tol: float | None = None,
    track_threshold: float = DEFAULT_TRACK_THRESHOLD,
) -> tuple[np.ndarray, list, list]:
    """Group the runs of every value into attractors and match them into tracks.

    Parameters
    ----------
    values : ndarray, (n_values,)
    raw : dict
        ``points`` (V, S, K, n_state), ``count``, ``period``, ``status``
        (V, S) and ``final_state`` (V, S, n_state), as stored by :func:`census`.
    period_tol : float
        The runs' period tolerance.
    identity_tol : float, optional
        Two runs reach the same orbit when they have the same period and their
        points agree up to a cyclic shift within ``identity_tol`` (max norm,
        relative to 1 + the largest |coordinate|, as the period detection);
        equilibria and stalls when their final states agree so. Default
        ``100 * period_tol`` (1e-3 at the default rtol 1e-9: period_tol is
        1e4 rtol).
    track_threshold : float
        Largest distance for two attractors at neighbouring values to be one
        track: the Hausdorff distance of their point sets (max norm), each
        state variable divided by its spread over all attractors of the census
        (at least the identity tolerance, so that a census with a single
        equilibrium does not divide by zero). Also groups the "unresolved"
        runs of one value.

    Returns
    -------
    labels : ndarray (V, S) of int
    attractors : list of list of Attractor
    tracks : list of Track
    """
    if identity_tol is None:
        identity_tol = IDENTITY_FACTOR * period_tol
    points = raw["points"]
    count = raw["count"]
    period = raw["period"]
    status = raw["status"]
    final = raw["final_state"]
    n_v, n_s = status.shape
    n_state = final.shape[-1]

    # 1. per value: group runs (in start order; each joins the first equal group)
    groups_all = []  # per value: list of [kind, period, canonical points, members]
    for i in range(n_v):
        groups: list[list] = []
        for j in range(n_s):
            st = int(status[i, j])
            if st == _ST_OK and period[i, j] > 0:
                kind, p = K_ORBIT, int(period[i, j])
                pts = _canonical_orbit(points[i, j], int(count[i, j]), p)
            elif st == _ST_OK and count[i, j] > 0:
                kind, p = K_UNRESOLVED, 0
                pts = points[i, j, : int(count[i, j])]
            elif st in (_ST_EQ, _ST_STALLED) and np.all(np.isfinite(final[i, j])):
                kind, p = (K_EQUILIBRIUM if st == _ST_EQ else K_STALLED), 0
                pts = final[i, j][None, :]
            else:
                continue  # failed, no crossings, or not computed: label -1
            if not np.all(np.isfinite(pts)):
                continue  # (cannot happen for a computed run; never group NaN)
            for g in groups:
                if g[0] != kind or g[1] != p:
                    continue
                if kind == K_UNRESOLVED:
                    continue  # grouped below, once the census scale is known
                if _same_cycle(g[2], pts, identity_tol):
                    g[3].append(j)
                    break
            else:
                groups.append([kind, p, pts, [j]])
        groups_all.append(groups)

    # the spread of every state variable over all attractors (tracking distances)
    allpts = [g[2] for groups in groups_all for g in groups]
    if allpts:
        stack = np.concatenate(allpts, axis=0)
        spread = np.nanmax(stack, axis=0) - np.nanmin(stack, axis=0)
        # differences below the identity tolerance never count (e.g. a census whose
        # only attractor is one equilibrium has no spread at all)
        floor = identity_tol * (1.0 + float(np.nanmax(np.abs(stack))))
        scale = np.maximum(spread, floor)
    else:
        scale = np.ones(n_state)

    # unresolved runs of one value: one attractor per cluster of nearby point clouds
    for groups in groups_all:
        merged: list[list] = []
        for g in groups:
            if g[0] == K_UNRESOLVED:
                for m in merged:
                    if m[0] == K_UNRESOLVED and _hausdorff(m[2], g[2], scale) <= track_threshold:
                        m[3].extend(g[3])
                        break
                else:
                    merged.append(g)
            else:
                merged.append(g)
        groups[:] = merged
        # most starts first; ties by first start
        groups.sort(key=lambda g: (-len(g[3]), min(g[3])))

    # 2. tracks: greedy closest matching between neighbouring values
    track_of: list[list[int]] = []
    tracks_info: list[dict] = []
    for i, groups in enumerate(groups_all):
        ids = [-1] * len(groups)
        if i > 0:
            prev = groups_all[i - 1]
            cand = []
            for a, ga in enumerate(prev):
                for b, gb in enumerate(groups):
                    if _match_class(ga[0]) != _match_class(gb[0]):
                        continue
                    d = _hausdorff(ga[2], gb[2], scale)
                    if d <= track_threshold:
                        cand.append((d, a, b))
            cand.sort()
            used_a: set[int] = set()
            for _d, a, b in cand:
                if a in used_a or ids[b] >= 0:
                    continue
                used_a.add(a)
                ids[b] = track_of[i - 1][a]
        for b, g in enumerate(groups):
            if ids[b] < 0:
                ids[b] = len(tracks_info)
                tracks_info.append({"kind": g[0], "birth": i, "death": i, "periods": []})
            info = tracks_info[ids[b]]
            info["death"] = i
            if g[1] not in info["periods"]:
                info["periods"].append(g[1])
        track_of.append(ids)

    labels = np.full((n_v, n_s), -1, dtype=np.int32)
    attractors = []
    for i, groups in enumerate(groups_all):
        atts = []
        for b, g in enumerate(groups):
            tid = track_of[i][b]
            labels[i, g[3]] = tid
            atts.append(
                Attractor(
                    id=tid,
                    kind=KINDS[g[0]],
                    period=g[1],
                    fraction=len(g[3]) / n_s,
                    count=len(g[3]),
                    points=np.array(g[2]),
                    first_start=min(g[3]),
                )  # fmt: skip
            )
        attractors.append(atts)
    tracks = [
        Track(
            id=t,
            kind=KINDS[info["kind"]],
            birth=info["birth"],
            death=info["death"],
            born=info["birth"] > 0,
            dies=info["death"] < n_v - 1,
            periods=tuple(info["periods"]),
        )  # fmt: skip
        for t, info in enumerate(tracks_info)
    ]
    return labels, attractors, tracks


# ------------------------------------------------------------------ the driver
@dataclass
class _Unit:
    """A unit of work in the contract of the sweep runners: length-1 chains."""

    kind: str
    values: np.ndarray  # (C, 1, 1)
    targets: list  # flat pair indices, one per chain
    y_starts: np.ndarray  # (C, n_state)
    axis: int = 0


def _units(
    values: np.ndarray, starts: np.ndarray, done: np.ndarray, chunk: int, nthreads: int
) -> Iterator[_Unit]:
    n_s = len(starts)
    todo = np.flatnonzero(~done.reshape(-1))
    for a in range(0, todo.size, chunk):
        flat = todo[a : a + chunk]
        # interleave over the threads, whose share of a prange is contiguous: each
        # thread gets pairs from the whole unit (costs vary smoothly with the value)
        flat = np.concatenate([flat[t::nthreads] for t in range(nthreads)])
        vi, si = np.divmod(flat, n_s)
        yield _Unit(
            "continuation", values[vi][:, None, None], [int(f) for f in flat],
            np.ascontiguousarray(starts[si]),
        )  # fmt: skip


def _values_digest(a: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(a, dtype="<f8").tobytes()).hexdigest()


def _check_starts(system: System, n_starts, box, starts, seed, include_zero, param, values):
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
        raise ValueError(f"seed must be an integer >= 0, got {seed!r}")
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


def census(
    system: System,
    param: str,
    values,
    *,
    t_end: float,
    t_transient: float = 0.0,
    n_starts: int = 64,
    box=None,
    starts=None,
    seed: int = 0,
    include_zero: bool = True,
    stop: str = "fixed",
    out: str | Path | None = None,
    threads: int | None = None,
    backend: str = "local",
    scheduler: str | None = None,
    n_workers: int | None = None,
    progress: bool | None = None,
    chunk_size: int | None = None,
    method: str = "rodas5p",
    rtol: float | None = None,
    atol: float | None = None,
    h: float | None = None,
    max_points: int = DEFAULT_CENSUS_POINTS,
    max_steps: int | None = None,
    equilibrium_tol: float = DEFAULT_EQUILIBRIUM_TOL,
    period_tol: float | None = None,
    dwell: float | None = None,
    identity_tol: float | None = None,
    track_threshold: float = DEFAULT_TRACK_THRESHOLD,
    title: str = "",
    notes: str = "",
) -> CensusResult:
    """Every attractor at every value of ``param``, with its basin fraction.

    Runs every start at every value (in parallel over the (value, start)
    pairs), groups the runs of each value into attractors, and matches the
    attractors of neighbouring values into tracks.

    Parameters
    ----------
    system : System
        Base parameters; ``param`` is overwritten per value.
    param : str
        The swept field (``"eta"``, ``"k12"``, ...).
    values : array_like
        Its values, in the order tracks follow (sorted is what you want).
    t_end, t_transient : float
        Each run lasts ``t_end``; points are kept after ``t_transient``.
    n_starts : int
        Number of starts, the zero state included when ``include_zero``.
    box : array_like (n_state, 2), optional
        (low, high) per state variable for the seeded uniform sampler; default
        :func:`default_box` (docs/census.md gives the physical reasoning).
    starts : array_like (n_starts, n_state), optional
        Explicit starts instead of the sampler (not together with ``box``).
    seed : int
        Seed of the sampler.
    include_zero : bool
        Make start 0 the zero state (the paper's initial condition).
    stop : {"fixed", "converged"}
        Stop rule of every run, as for :func:`simulate`: "fixed" integrates to
        ``t_end``; "converged" ends a run once its Poincare points repeat or it
        has come to rest (``t_end`` is the cap), and stores each run's
        ``t_converged``.
    out : path, optional
        HDF5 file to stream into (docs/file-format.md, census file); running
        the same census on it again resumes, a different one is refused.
    threads, chunk_size, backend, scheduler, n_workers, progress
        As for :func:`sweep`; ``chunk_size`` counts (value, start) pairs per
        unit of work (default 32 per thread; 64 with ``backend="dask"``, each
        unit split over the workers). Results do not depend on them.
    method, rtol, atol, h, max_points, max_steps, equilibrium_tol, period_tol, dwell
        As for :func:`sweep`; ``max_points`` defaults to 128 (enough to
        detect any period <= 64); ``dwell`` only with ``stop="converged"``.
    identity_tol, track_threshold : float
        See :func:`classify_census`; they do not change the runs, so a finished
        file can be re-classified with other values (:func:`load_census`).
    title, notes : str
        Stored in the file.

    Returns
    -------
    CensusResult

    Raises
    ------
    ValueError
        For bad input, naming the argument.
    """
    from . import __version__
    from .chunks import run_local
    from .sweep import _numba_threads

    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    if not isinstance(param, str) or param not in SWEEPABLE:
        raise ValueError(f"param must be one of {list(SWEEPABLE)}, got {param!r}")
    vals = np.asarray(values, dtype=float)
    if vals.ndim != 1 or vals.size == 0 or not np.all(np.isfinite(vals)):
        raise ValueError("values must be a non-empty 1-D array of finite numbers")
    for v in np.unique(vals):
        try:
            system.replace(**{param: float(v)})
        except ValueError as exc:
            raise ValueError(f"value {v!r} of param {param!r} is invalid: {exc}") from None
    if stop not in STOP_RULES:
        raise ValueError(f"stop must be one of {STOP_RULES}, got {stop!r}")
    if backend not in _BACKENDS:
        raise ValueError(f"backend must be one of {_BACKENDS}, got {backend!r}")
    if backend == "local" and (scheduler is not None or n_workers is not None):
        raise ValueError("scheduler and n_workers are only used with backend='dask'")
    if track_threshold is None or not np.isfinite(track_threshold) or track_threshold <= 0:
        raise ValueError(f"track_threshold must be a number > 0, got {track_threshold!r}")
    if identity_tol is not None and (not np.isfinite(identity_tol) or identity_tol <= 0):
        raise ValueError(f"identity_tol must be a number > 0, got {identity_tol!r}")
    start_arr, box_arr = _check_starts(
        system, n_starts, box, starts, seed, include_zero, param, vals
    )
    settings = Settings.resolve(
        method=method, t_end=t_end, t_transient=t_transient, rtol=rtol, atol=atol, h=h,
        max_points=max_points, max_steps=max_steps, equilibrium_tol=equilibrium_tol,
        period_tol=period_tol, stop=stop, dwell=dwell,
    )  # fmt: skip
    base = system.to_dict()
    base[param] = None
    config = {
        "kind": "census",
        "system": base,
        "param": param,
        "n_values": int(vals.size),
        "values_sha256": _values_digest(vals),
        "n_starts": len(start_arr),
        "starts_sha256": _values_digest(start_arr),
        "stop": stop,
        "settings": settings.to_dict(),
    }
    layout = CensusLayout(
        param, vals, start_arr, settings.max_points, system.state_names, stop == "converged"
    )
    y0 = system.initial_state(None)
    n_v, n_s = len(vals), len(start_arr)
    runner = run_local
    if backend == "dask":
        from .backends import dask_runner

        runner = dask_runner(scheduler, n_workers)

    with contextlib.ExitStack() as stack:
        nthreads = stack.enter_context(_numba_threads(threads))
        if chunk_size is None:
            # the Dask runner splits each unit over its workers and waits for the whole
            # unit before the next: units of 64 pairs keep a small cluster busy
            chunk_size = 32 * nthreads if backend == "local" else 64
        elif isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1:
            raise ValueError(f"chunk_size must be an integer >= 1, got {chunk_size!r}")
        if out is not None:
            file = stack.enter_context(
                CensusFile.open(
                    out, config, layout, title=title, notes=notes, package_version=__version__
                )
            )
            done = file.done_mask()
            mem = None
        else:
            file = None
            done = np.zeros((n_v, n_s), dtype=bool)
            mem = CensusFile.empty_arrays(layout)
        n_todo = int(done.size - done.sum())
        show = sys.stderr.isatty() if progress is None else bool(progress)
        bar = None
        if show and n_todo:
            from tqdm.auto import tqdm

            bar = stack.enter_context(
                tqdm(total=done.size, initial=done.size - n_todo, unit="run",
                     desc=f"census {param}", dynamic_ncols=True, smoothing=0.1)
            )  # fmt: skip
        units = _units(vals, start_arr, done, chunk_size, nthreads)
        results = stack.enter_context(
            contextlib.closing(runner(units, system, (param,), y0, settings))
        )
        for unit, res in results:
            flat = np.asarray(unit.targets)
            order = np.argsort(flat, kind="stable")
            data = {k: v[:, 0][order] for k, v in res.items()}
            flat = flat[order]
            if file is not None:
                file.write_pairs(flat, data)
            else:
                vi, si = np.divmod(flat, n_s)
                for k, v in data.items():
                    mem[k][vi, si] = v
                mem["done"][vi, si] = 1
            if bar is not None:
                bar.update(len(flat))

    if out is not None:
        return load_census(
            out, identity_tol=identity_tol, track_threshold=track_threshold, _write=True
        )
    labels, attractors, tracks = classify_census(
        vals, mem, period_tol=settings.period_tol, identity_tol=identity_tol,
        track_threshold=track_threshold,
    )  # fmt: skip
    return CensusResult(
        param=param, values=vals, starts=start_arr, labels=labels, status_code=mem["status"],
        period=mem["period"], attractors=attractors, tracks=tracks,
        state_names=system.state_names, system=system, settings=settings.to_dict(),
        raw=mem,
    )  # fmt: skip


def load_census(
    path: str | Path,
    *,
    identity_tol: float | None = None,
    track_threshold: float | None = None,
    _write: bool = False,
) -> CensusResult:
    """Open a census file as a :class:`CensusResult` (classified from its runs).

    Runs not computed yet (an unfinished file) are labelled -1 with status
    "missing". ``identity_tol`` and ``track_threshold`` (see
    :func:`classify_census`) default to those the file was classified with,
    else to the defaults. With ``_write`` (what :func:`census` does when it
    finishes) the labels, attractors and tracks are also stored in the file.
    """
    data = read_census(path)
    if identity_tol is None and not _write:
        identity_tol = data["attrs"].get("identity_tol")
    if track_threshold is None:
        track_threshold = data["attrs"].get("track_threshold", DEFAULT_TRACK_THRESHOLD)
    data["status"] = np.where(data["done"] == 1, data["status"], -1).astype(data["status"].dtype)
    cfg = data["config"]
    sysd = {k: v for k, v in cfg["system"].items() if v is not None}
    param = cfg["param"]
    vals = data["values"]
    sysd[param] = float(vals[0])
    system = System.from_dict(sysd)
    settings = cfg["settings"]
    labels, attractors, tracks = classify_census(
        vals, data, period_tol=settings["period_tol"], identity_tol=identity_tol,
        track_threshold=track_threshold,
    )  # fmt: skip
    tol = IDENTITY_FACTOR * settings["period_tol"] if identity_tol is None else identity_tol
    if _write and bool(np.all(data["done"])):
        write_census_classification(
            path, labels, attractors, tracks, KINDS,
            {"identity_tol": tol, "track_threshold": track_threshold},
        )  # fmt: skip
    return CensusResult(
        param=param, values=vals, starts=data["starts"], labels=labels,
        status_code=data["status"], period=data["period"], attractors=attractors,
        tracks=tracks, state_names=data["state_names"], system=system, settings=settings,
        path=Path(path), raw=data,
    )  # fmt: skip
