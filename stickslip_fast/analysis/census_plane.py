"""The census over a plane of two parameters: tracks across neighbouring cells, and maps.

:func:`stickslip_fast.analysis.census.census` with two parameters runs every
start at every cell (i, j) of the grid ``values[0] x values[1]`` and groups
each cell's runs into attractors exactly as a one-parameter census groups a
value's (:func:`~stickslip_fast.analysis.census_classify.group_census`). Here
the attractors of neighbouring cells (left-right and up-down) are joined into
tracks, and the per-cell maps are read off the result: number of attractors,
basin fraction of steady sliding, dominant period (docs/census.md, "A census
over a plane").
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..base.status import status_names
from ..model.system import System
from .census_classify import (
    DEFAULT_TRACK_THRESHOLD,
    KINDS,
    Attractor,
    _assemble,
    _hausdorff,
    _match_class,
    group_census,
)

__all__ = ["CensusPlaneResult", "PlaneTrack", "classify_plane", "plane_track_columns"]

#: :meth:`CensusPlaneResult.dominant_period` where the largest basin is not a periodic orbit.
PERIOD_SLIDING, PERIOD_UNRESOLVED, PERIOD_NONE, PERIOD_STALLED = 0, -1, -2, -3


@dataclass
class PlaneTrack:
    """An attractor followed over neighbouring cells of a plane.

    ``n_cells`` is the number of cells where it exists; ``extent`` is
    (i_min, i_max, j_min, j_max), the index range of those cells.
    """

    id: int
    kind: str
    periods: tuple[int, ...]
    n_cells: int
    extent: tuple[int, int, int, int]


def classify_plane(
    shape: tuple[int, int],
    raw: dict[str, np.ndarray],
    *,
    period_tol: float,
    identity_tol: float | None = None,
    track_threshold: float = DEFAULT_TRACK_THRESHOLD,
) -> tuple[np.ndarray, list, list]:
    """Group the runs of every cell into attractors and join them into tracks.

    Parameters
    ----------
    shape : (n1, n2)
        The grid; ``raw`` holds its cells in C order (cell ``i * n2 + j``).
    raw, period_tol, identity_tol, track_threshold
        As for :func:`~stickslip_fast.analysis.census_classify.classify_census`;
        the arrays are (n1 * n2, n_starts, ...).

    Returns
    -------
    labels : ndarray (n1, n2, n_starts) of int
    attractors : list of lists of lists of Attractor
        ``attractors[i][j]``: the attractors of cell (i, j), most starts first.
    tracks : list of PlaneTrack

    Notes
    -----
    The one-parameter matching, generalised: every pair of attractors of the
    same class in neighbouring cells (sharing an edge) within
    ``track_threshold`` of each other is a candidate; candidates are taken
    closest first (ties in cell order), and one joins two tracks unless the
    joined track would hold two attractors of one cell. On a single row (or
    column) this is exactly the one-parameter census's greedy matching, with
    the same ids. Track ids are numbered in the order their first cell comes
    in C order.
    """
    n1, n2 = shape
    groups_all, scale = group_census(raw, period_tol, identity_tol, track_threshold)
    n_c, n_s = raw["status"].shape
    if n_c != n1 * n2:
        raise ValueError(f"raw has {n_c} cells, the grid {shape} has {n1 * n2}")
    root = _join_cells(groups_all, n2, scale, track_threshold)
    offset = np.cumsum([0] + [len(g) for g in groups_all])
    track_of: list[list[int]] = []
    info: list[dict] = []
    id_of: dict[int, int] = {}
    for c, groups in enumerate(groups_all):
        ids = []
        for b, g in enumerate(groups):
            r = root(int(offset[c]) + b)
            if r not in id_of:
                id_of[r] = len(info)
                info.append({"kind": g[0], "birth": c, "death": c, "periods": [], "cells": []})
            t = info[id_of[r]]
            t["death"] = c
            t["cells"].append(c)
            if g[1] not in t["periods"]:
                t["periods"].append(g[1])
            ids.append(id_of[r])
        track_of.append(ids)
    labels, atts, _ = _assemble(groups_all, track_of, info, n_c, n_s)
    tracks = []
    for t, d in enumerate(info):
        i, j = np.divmod(np.asarray(d["cells"]), n2)
        tracks.append(
            PlaneTrack(t, KINDS[d["kind"]], tuple(d["periods"]), len(d["cells"]),
                       (int(i.min()), int(i.max()), int(j.min()), int(j.max())))
        )  # fmt: skip
    nested = [atts[i * n2 : (i + 1) * n2] for i in range(n1)]
    return labels.reshape(n1, n2, n_s), nested, tracks


def _join_cells(groups_all, n2, scale, track_threshold):
    """Union the attractors of neighbouring cells into tracks; returns ``root(node)``.

    Nodes are the groups of all cells, numbered cell by cell. Each track keeps
    the set of its cells, so no join puts two attractors of one cell together.
    """
    n_c = len(groups_all)
    offset = np.cumsum([0] + [len(g) for g in groups_all])
    edges = []
    for c in range(n_c):
        right = [c + 1] if (c + 1) % n2 else []
        for nb in right + ([c + n2] if c + n2 < n_c else []):
            for a, ga in enumerate(groups_all[c]):
                for b, gb in enumerate(groups_all[nb]):
                    if _match_class(ga[0]) != _match_class(gb[0]):
                        continue
                    d = _hausdorff(ga[2], gb[2], scale)
                    if d <= track_threshold:
                        edges.append((d, int(offset[c]) + a, int(offset[nb]) + b))
    edges.sort()
    parent = list(range(int(offset[-1])))
    cells: list[set | None] = [{c} for c in range(n_c) for _ in groups_all[c]]

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    for _d, u, v in edges:
        ru, rv = root(u), root(v)
        if ru == rv or not cells[ru].isdisjoint(cells[rv]):
            continue
        if len(cells[ru]) < len(cells[rv]):
            ru, rv = rv, ru
        parent[rv] = ru
        cells[ru] |= cells[rv]
        cells[rv] = None
    return root


def plane_track_columns(tracks: list[PlaneTrack]) -> dict[str, tuple]:
    """The track table of a plane's census file: (array, description) per column."""
    ext = np.array([t.extent for t in tracks], dtype="i4").reshape(len(tracks), 4)
    return {
        "kind": (np.array([KINDS.index(t.kind) for t in tracks], dtype="i1"), ""),
        "n_cells": (np.array([t.n_cells for t in tracks], dtype="i4"),
                    "number of cells where the track exists"),
        "value_index_min": (ext[:, 0], "smallest first-parameter index of its cells"),
        "value_index_max": (ext[:, 1], "largest first-parameter index of its cells"),
        "value_index2_min": (ext[:, 2], "smallest second-parameter index of its cells"),
        "value_index2_max": (ext[:, 3], "largest second-parameter index of its cells"),
        "periods": (np.array([",".join(map(str, t.periods)) for t in tracks], dtype=object), ""),
    }  # fmt: skip


@dataclass
class CensusPlaneResult:
    """Result of :func:`census` over two parameters.

    Attributes
    ----------
    params : (str, str)
    values : (ndarray (n1,), ndarray (n2,))
        Cell (i, j) is (``values[0][i]``, ``values[1][j]``).
    starts : ndarray, (n_starts, n_state)
    labels : ndarray of int, (n1, n2, n_starts)
        The track id of the attractor each run reached (-1: failed or no crossing).
    status : ndarray of str, (n1, n2, n_starts)
    period : ndarray of int, (n1, n2, n_starts)
    attractors : list of lists of lists of Attractor
        ``attractors[i][j]``: the attractors of cell (i, j), most starts first.
    tracks : list of PlaneTrack
    raw : dict
        The runs, (n1, n2, n_starts, ...).
    """

    params: tuple[str, str]
    values: tuple[np.ndarray, np.ndarray]
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

    @classmethod
    def from_runs(
        cls, names, axes, starts, labels, attractors, tracks, runs, system, settings, path=None
    ) -> CensusPlaneResult:
        """Assemble from the classification and the runs in (n_cells, n_starts) order."""
        shape = (len(axes[0]), len(axes[1]))
        raw = {k: v.reshape(shape + v.shape[1:]) for k, v in runs.items()}
        return cls(
            params=tuple(names), values=tuple(axes), starts=starts, labels=labels,
            status_code=raw["status"], period=raw["period"], attractors=attractors,
            tracks=tracks, state_names=system.state_names, system=system, settings=settings,
            path=path, raw=raw,
        )  # fmt: skip

    @property
    def shape(self) -> tuple[int, int]:
        return (len(self.values[0]), len(self.values[1]))

    @property
    def status(self) -> np.ndarray:
        return status_names(self.status_code)

    @property
    def failed_fraction(self) -> np.ndarray:
        """(n1, n2): share of starts labelled -1."""
        return np.mean(self.labels < 0, axis=2)

    def _per_cell(self, fn, dtype) -> np.ndarray:
        out = np.empty(self.shape, dtype=dtype)
        for i, row in enumerate(self.attractors):
            for j, atts in enumerate(row):
                out[i, j] = fn(atts)
        return out

    def fractions(self) -> np.ndarray:
        """Basin fractions, (n1, n2, n_tracks) (0 where a track is absent)."""
        out = np.zeros(self.shape + (len(self.tracks),))
        for i, row in enumerate(self.attractors):
            for j, atts in enumerate(row):
                for a in atts:
                    out[i, j, a.id] = a.fraction
        return out

    def n_attractors(self, min_fraction: float = 0.0, stalls_as_one: bool = False) -> np.ndarray:
        """(n1, n2): attractors per cell whose basin fraction is at least ``min_fraction``.

        With ``stalls_as_one`` the stalled states of a cell count as one (a
        stalled DC motor holds the disks wherever stiction does: a continuum of
        states, each start its own, rather than isolated attractors).
        """

        def count(atts: list[Attractor]) -> int:
            big = [a for a in atts if a.fraction >= min_fraction]
            stalls = sum(a.kind == "stalled" for a in big)
            return len(big) - (stalls - 1 if stalls_as_one and stalls > 1 else 0)

        return self._per_cell(count, int)

    def sliding_fraction(self) -> np.ndarray:
        """(n1, n2): share of the starts that end in steady sliding (an equilibrium)."""
        return self._per_cell(
            lambda atts: sum(a.fraction for a in atts if a.kind == "equilibrium"), float
        )

    def dominant_period(self) -> np.ndarray:
        """(n1, n2): the period of the attractor with the largest basin in each cell.

        A periodic orbit gives its period (>= 1); steady sliding
        :data:`PERIOD_SLIDING` (0); "unresolved" :data:`PERIOD_UNRESOLVED` (-1);
        a cell where every run failed :data:`PERIOD_NONE` (-2); a stalled motor
        :data:`PERIOD_STALLED` (-3; its stalled states together, as one basin).
        Ties go to the attractor reached by the lowest start.
        """

        def dominant(atts: list[Attractor]) -> int:
            if not atts:
                return PERIOD_NONE
            stalled = sum(a.fraction for a in atts if a.kind == "stalled")
            a = atts[0]  # most starts first, ties by first start
            if stalled > a.fraction:
                return PERIOD_STALLED
            if a.kind == "orbit":
                return a.period
            codes = {"unresolved": PERIOD_UNRESOLVED, "stalled": PERIOD_STALLED}
            return codes.get(a.kind, PERIOD_SLIDING)

        return self._per_cell(dominant, int)

    def attractor_of(self, i: int, j: int, start: int) -> Attractor | None:
        """The attractor that start ``start`` reached at cell (i, j)."""
        lab = int(self.labels[i, j, start])
        return next((a for a in self.attractors[i][j] if a.id == lab), None)

    def __repr__(self) -> str:
        n_att = sum(len(a) for row in self.attractors for a in row)
        return (
            f"CensusPlaneResult(params={self.params!r}, shape={self.shape}, "
            f"starts={len(self.starts)}, attractors={n_att}, tracks={len(self.tracks)})"
        )
