"""Census classification: attractors from runs, identity up to a cyclic shift, tracks over values.

Used by :func:`stickslip_fast.analysis.census.census` and :func:`~stickslip_fast.analysis.census.load_census`;
see docs/census.md for the rules.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..base.status import status_names
from ..core.poincare import MAX_PERIOD, STATUS_NAMES
from ..core.settings import STOP_KINDS
from ..model.system import System

__all__ = ["Attractor", "Track", "CensusResult", "classify_census", "group_census", "KINDS"]

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
_BACKENDS = ("local", "dask", "cuda")
_ST_OK = STATUS_NAMES.index("ok")
_ST_EQ = STATUS_NAMES.index("equilibrium")
_ST_STALLED = STATUS_NAMES.index("stalled")


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
        return status_names(self.status_code)

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
        1e4 rtol, at most 1e-4).
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
    groups_all, scale = group_census(raw, period_tol, identity_tol, track_threshold)
    n_v, n_s = raw["status"].shape
    # 2. tracks: greedy closest matching between neighbouring values
    track_of, tracks_info = _match_tracks(groups_all, scale, track_threshold)
    return _assemble(groups_all, track_of, tracks_info, n_v, n_s)


def group_census(
    raw: dict[str, np.ndarray],
    period_tol: float,
    identity_tol: float | None,
    track_threshold: float,
) -> tuple[list[list[list]], np.ndarray]:
    """The runs of every value (or cell) grouped into attractors, and the tracking scale.

    Step 1 of :func:`classify_census` (the same arguments); a census over a
    plane groups its cells (C order) the same way. Returns, per value, its
    groups ``[kind, period, canonical points, member starts]`` (most starts
    first), and the per-variable spread that scales tracking distances.
    """
    if identity_tol is None:
        identity_tol = IDENTITY_FACTOR * period_tol
    points = raw["points"]
    count = raw["count"]
    period = raw["period"]
    status = raw["status"]
    final = raw["final_state"]
    # per value: group runs (in start order; each joins the first equal group)
    groups_all = [  # per value: list of [kind, period, canonical points, members]
        _group_runs(points[i], count[i], period[i], status[i], final[i], identity_tol)
        for i in range(status.shape[0])
    ]
    scale = _census_scale(groups_all, identity_tol, final.shape[-1])
    for groups in groups_all:
        _merge_unresolved(groups, scale, track_threshold)
    return groups_all, scale


def _group_runs(points, count, period, status, final, identity_tol) -> list[list]:
    """The runs of one value grouped (in start order; each joins the first equal group)."""
    groups: list[list] = []
    for j in range(status.shape[0]):
        st = int(status[j])
        if st == _ST_OK and period[j] > 0:
            kind, p = K_ORBIT, int(period[j])
            pts = _canonical_orbit(points[j], int(count[j]), p)
        elif st == _ST_OK and count[j] > 0:
            kind, p = K_UNRESOLVED, 0
            pts = points[j, : int(count[j])]
        elif st in (_ST_EQ, _ST_STALLED) and np.all(np.isfinite(final[j])):
            kind, p = (K_EQUILIBRIUM if st == _ST_EQ else K_STALLED), 0
            pts = final[j][None, :]
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
    return groups


def _census_scale(groups_all, identity_tol, n_state) -> np.ndarray:
    """The spread of every state variable over all attractors (tracking distances)."""
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
    return scale


def _merge_unresolved(groups, scale, track_threshold) -> None:
    """Unresolved runs of one value: one attractor per cluster of nearby point clouds.

    Then sorts the value's groups: most starts first, ties by first start (in place).
    """
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


def _match_tracks(groups_all, scale, track_threshold) -> tuple[list[list[int]], list[dict]]:
    """Tracks by greedy closest matching between neighbouring values: ids and track info."""
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
    return track_of, tracks_info


def _assemble(groups_all, track_of, tracks_info, n_v, n_s) -> tuple[np.ndarray, list, list]:
    """Labels, attractors per value and tracks from the groups and their track ids."""
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
