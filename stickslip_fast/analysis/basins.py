"""Basins of attraction on a plane of initial states (issue 29; docs/basins.md).

:func:`basins` runs one start per cell of a grid over a plane of the state space
(two state coordinates, or two direction vectors through a base state) and
labels every cell with the attractor it reaches. It *is* a census at one
parameter value whose starts are the cells (row-major, cell (i, j) is start
``i * len(g2) + j``): the runs go through :func:`stickslip_fast.analysis.census.census`,
so they stream to HDF5, resume after a kill, refuse a different configuration
and are bit-identical across thread counts, chunk sizes and backends (local,
Dask, CUDA), and the attractor ids are exactly those of a census at that value
over the same starts. The basins' own results (the label grid, the attractor
table with standard errors, the measures, the refined boundary and the saddle
check) are stored in the file's ``/basins`` group (:mod:`stickslip_fast.io.basins`).

The measures are pure NumPy functions of the label grid
(:mod:`stickslip_fast.analysis.basins_measures`); the boundary refinement and the
saddle ("edge tracking") check are in :mod:`stickslip_fast.analysis.basins_boundary`
and :mod:`stickslip_fast.bifurcation.basin_saddles`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ..model.system import System
from . import basins_measures as bm
from .census_classify import (
    DEFAULT_CENSUS_POINTS,
    DEFAULT_TRACK_THRESHOLD,
    IDENTITY_FACTOR,
    KINDS,
    Attractor,
    CensusResult,
    _hausdorff,
    _same_cycle,
)

__all__ = [
    "basins", "load_basins", "BasinsResult", "BasinTests", "plane_starts", "DEFAULT_ENTROPY_BOX",
]  # fmt: skip

#: Default side (in cells) of the boxes of the basin entropy (Daza et al. use 5).
DEFAULT_ENTROPY_BOX = 5
#: Label of a start that reached an attractor not on the map (boundary refinement).
LABEL_OTHER = -3


# ------------------------------------------------------------------ the plane
def _axes(system: System, plane: Any) -> tuple[np.ndarray, list[str]]:
    """(2, n_state) direction vectors and the two axis names of ``plane``."""
    names = system.state_names
    n = system.n_state
    if not isinstance(plane, (tuple, list)) or len(plane) != 2:
        raise ValueError(
            f"plane must be two state names ({', '.join(names)}) or two direction "
            f"vectors of length {n}, got {plane!r}"
        )
    if all(isinstance(p, str) for p in plane):
        bad = [p for p in plane if p not in names]
        if bad:
            raise ValueError(f"plane names {bad} are not state variables ({', '.join(names)})")
        if plane[0] == plane[1]:
            raise ValueError(f"plane must name two different state variables, got {plane!r}")
        dirs = np.zeros((2, n))
        dirs[0, names.index(plane[0])] = 1.0
        dirs[1, names.index(plane[1])] = 1.0
        return dirs, [str(plane[0]), str(plane[1])]
    try:
        dirs = np.asarray(plane, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"plane must be two state names or two vectors, got {plane!r}") from None
    if dirs.shape != (2, n) or not np.all(np.isfinite(dirs)):
        raise ValueError(f"plane direction vectors must have shape (2, {n}), got {dirs.shape}")
    if np.linalg.matrix_rank(dirs) < 2:
        raise ValueError("plane direction vectors must be linearly independent")
    return dirs, ["u", "v"]


def _grid_axis(g: Any, name: str) -> np.ndarray:
    arr = np.asarray(g, dtype=float)
    if arr.ndim != 1 or arr.size < 2 or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be a 1-D array of >= 2 finite numbers")
    if np.any(np.diff(arr) <= 0):
        raise ValueError(f"{name} must be strictly increasing")
    return arr


def plane_starts(
    system: System, g1: Any, g2: Any, plane: Any = ("x1", "phi1"), base: Any = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """The starts of a basin map: ``base + g1[i] * d1 + g2[j] * d2``, row-major.

    Parameters
    ----------
    system : System
    g1, g2 : array_like
        Increasing coordinates along the two axes.
    plane : (str, str) or (array_like, array_like)
        Two state names (``system.state_names``: x1, dx1, phi1, dphi1, x2, ...,
        vb), whose values are g1 and g2, or two direction vectors d1, d2.
    base : array_like, optional
        The state whose other coordinates the plane keeps (default zeros; for
        named axes, its values on those axes are replaced, not added to).

    Returns
    -------
    starts : ndarray (len(g1) * len(g2), n_state)
    base : ndarray (n_state,)
    directions : ndarray (2, n_state)
    axis_names : list of str
    """
    dirs, axis_names = _axes(system, plane)
    a1, a2 = _grid_axis(g1, "g1"), _grid_axis(g2, "g2")
    b = system.initial_state(None) if base is None else system.initial_state(base)
    b = np.array(b, dtype=float)
    if axis_names != ["u", "v"]:  # named axes: the grid values replace the base's
        b[dirs.argmax(axis=1)] = 0.0
    u, v = np.meshgrid(a1, a2, indexing="ij")
    starts = b + u.reshape(-1, 1) * dirs[0] + v.reshape(-1, 1) * dirs[1]
    return starts, b, dirs, axis_names


# ------------------------------------------------------------------ the result
class BasinTests(NamedTuple):
    """The tests of a map that give arrays as well as its scalar measures."""

    uncertainty: bm.UncertaintyFit
    wada: bm.WadaTest
    wada_merge: bm.WadaMergeTest


@dataclass
class BasinsResult:
    """Result of :func:`basins`: a label per cell of a plane of starts.

    Attributes
    ----------
    system : System
    g1, g2 : ndarray
        Grid coordinates along the two axes.
    axis_names : list of str
        The two state names, or ["u", "v"] for direction vectors.
    base : ndarray (n_state,)
    directions : ndarray (2, n_state)
    labels : ndarray of int (len(g1), len(g2))
        Attractor id per cell (the census's ids); -1 where a run failed.
    attractors : list of Attractor
        As in a census (``id``, ``kind``, ``period``, ``fraction``, ``count``,
        ``points``, ``first_start``), most cells first.
    census : CensusResult
        The underlying one-value census (runs, statuses, settings).
    entropy_box : int
        Box side (cells) of the stored basin entropies.
    path : Path or None
    boundary : Boundary or None
        The refined boundary (:func:`stickslip_fast.analysis.basins_boundary.refine_boundary`).
    edge : EdgeCheck or None
        The saddle check (:func:`stickslip_fast.bifurcation.basin_saddles.edge_check`).
    manifold : StableManifold or None
        A saddle orbit's stable manifold in the plane
        (:func:`stickslip_fast.bifurcation.stable_manifold.stable_manifold`).
    """

    system: System
    g1: np.ndarray
    g2: np.ndarray
    axis_names: list
    base: np.ndarray
    directions: np.ndarray
    labels: np.ndarray
    attractors: list
    census: CensusResult
    entropy_box: int = DEFAULT_ENTROPY_BOX
    path: Path | None = None
    boundary: Any = None
    edge: Any = None
    manifold: Any = None
    identity_tol: float | None = field(default=None, repr=False)

    @property
    def shape(self) -> tuple[int, int]:
        return self.labels.shape

    @property
    def starts(self) -> np.ndarray:
        """The cells' initial states, (len(g1) * len(g2), n_state), row-major."""
        return self.census.starts

    def state_at(self, uv: Any) -> np.ndarray:
        """Full states of plane points ``uv`` (m, 2): base + u d1 + v d2."""
        uv = np.atleast_2d(np.asarray(uv, dtype=float))
        return self.base + uv[:, :1] * self.directions[0] + uv[:, 1:2] * self.directions[1]

    def attractor(self, id: int) -> Attractor:
        for a in self.attractors:
            if a.id == id:
                return a
        raise KeyError(f"no attractor with id {id} on this map")

    def fractions(self, stderr: bool = False) -> dict:
        """``{id: fraction}`` of the cells (``{id: (fraction, stderr)}`` with ``stderr``).

        Failed cells are under id -1 when there are any.
        """
        out = bm.basin_fractions(self.labels)
        return out if stderr else {k: v[0] for k, v in out.items()}

    def basin_entropy(self, box: int | None = None) -> float:
        """Basin entropy S_b (Daza et al. 2016) with boxes of ``box`` cells."""
        return bm.basin_entropy(self.labels, box or self.entropy_box)[0]

    def boundary_basin_entropy(self, box: int | None = None) -> float:
        """Boundary basin entropy S_bb (mean over the boxes holding > 1 label)."""
        return bm.basin_entropy(self.labels, box or self.entropy_box)[1]

    def uncertainty_exponent(self, ks: Any = None) -> bm.UncertaintyFit:
        """Uncertainty exponent from cell pairs k cells apart (eps in units of g1's step)."""
        return bm.uncertainty_exponent(self.labels, ks, spacing=float(np.mean(np.diff(self.g1))))

    def wada(self, r_max: int = 5) -> bm.WadaTest:
        """Grid Wada test (meaningful with three or more basins)."""
        return bm.wada_grid_test(self.labels, r_max=r_max)

    def wada_merge(self, r_max: int = 5) -> bm.WadaMergeTest:
        """Merging Wada test (Daza et al. 2018; meaningful with three or more basins)."""
        return bm.wada_merge_test(self.labels, r_max=r_max)

    def tests(self) -> BasinTests:
        """The uncertainty exponent and both Wada tests with their default arguments."""
        return BasinTests(self.uncertainty_exponent(), self.wada(), self.wada_merge())

    def measures(self, tests: BasinTests | None = None) -> dict[str, Any]:
        """Every scalar measure, as stored in the file's /basins attributes.

        ``tests``: those of :meth:`tests`, where the caller has them already (the Wada
        tests take about a second each on a 1000 x 1000 map).
        """
        ue, w, wm = self.tests() if tests is None else tests
        sb, sbb = bm.basin_entropy(self.labels, self.entropy_box)
        return {
            "entropy_box": int(self.entropy_box),
            "basin_entropy": sb,
            "boundary_basin_entropy": sbb,
            "boundary_box_fraction": float(np.mean(bm._box_entropies(
                np.where(self.labels < 0, -1, self.labels), self.entropy_box)[1] > 1)),
            "uncertainty_exponent": ue.alpha,
            "uncertainty_exponent_stderr": ue.alpha_stderr,
            "boundary_dimension": ue.dimension,
            "n_basins": w.n_basins,
            "wada": int(w.is_wada),
            "wada_merge": int(wm.is_wada),
            "failed_fraction": float(np.mean(self.labels < 0)),
        }  # fmt: skip

    def label_states(self, states: Any, **kw: Any) -> np.ndarray:
        """Run ``states`` (m, n_state) with the map's settings; label them with its ids.

        Runs are in memory (one census at the map's value, ``threads`` etc. as
        for :func:`basins`); each run's attractor is matched to the map's by the
        census's identity rule, and one not on the map gets :data:`LABEL_OTHER`.
        """
        from .census import census

        st = np.atleast_2d(np.asarray(states, dtype=float))
        s = dict(self.census.settings)
        s["h"] = s["h"] or None
        res = census(self.system, "eta", [self.system.eta], starts=st, progress=False,
                     identity_tol=self.identity_tol, **s, **kw)  # fmt: skip
        return _match_labels(res, self.attractors, self._tol())

    def label_plane(self, uv: Any, **kw: Any) -> np.ndarray:
        """:meth:`label_states` of plane points (m, 2) (the map's label function)."""
        return self.label_states(self.state_at(uv), **kw)

    def _tol(self) -> float:
        return self.identity_tol or IDENTITY_FACTOR * self.census.settings["period_tol"]

    def __repr__(self) -> str:
        fr = ", ".join(f"{k}: {v:.3f}" for k, v in self.fractions().items())
        return (
            f"BasinsResult({self.axis_names[0]} x {self.axis_names[1]}: "
            f"{self.shape[0]} x {self.shape[1]} cells, eta={self.system.eta:g}, "
            f"fractions {{{fr}}})"
        )


def _match_labels(res: CensusResult, attractors: list, tol: float) -> np.ndarray:
    """Map a one-value census's labels onto ``attractors`` (ids of another census)."""
    out = np.full(res.labels.shape[1], -1, dtype=np.int32)
    pts = [a.points for a in attractors] or [np.zeros((1, res.starts.shape[1]))]
    stack = np.concatenate(pts)
    scale = np.maximum(np.ptp(stack, axis=0), tol * (1 + np.max(np.abs(stack))))
    for new in res.attractors[0]:
        hit = LABEL_OTHER
        for a in attractors:
            if a.kind != new.kind or a.period != new.period:
                continue
            if a.kind == "unresolved":
                ok = _hausdorff(a.points, new.points, scale) <= DEFAULT_TRACK_THRESHOLD
            else:
                ok = _same_cycle(a.points, new.points, tol)
            if ok:
                hit = a.id
                break
        out[res.labels[0] == new.id] = hit
    return out


def _result(census_res: CensusResult, meta: dict, entropy_box: int) -> BasinsResult:
    n1, n2 = len(meta["g1"]), len(meta["g2"])
    return BasinsResult(
        system=census_res.system, g1=np.asarray(meta["g1"]), g2=np.asarray(meta["g2"]),
        axis_names=list(meta["axis_names"]), base=np.asarray(meta["base"]),
        directions=np.asarray(meta["directions"]),
        labels=census_res.labels[0].reshape(n1, n2), attractors=census_res.attractors[0],
        census=census_res, entropy_box=entropy_box, path=census_res.path,
        identity_tol=meta.get("identity_tol"),
    )  # fmt: skip


def _write(out: Any, result: BasinsResult) -> None:
    from ..io.basins import write_basins

    write_basins(out, result, KINDS)


def _starts_and_meta(system: System, grid: Any, plane: Any, base: Any, entropy_box: Any):
    """Check the arguments of :func:`basins`; the starts and the configuration's grid part."""
    if not isinstance(system, System):
        raise TypeError(f"system must be a stickslip_fast.System, got {type(system).__name__}")
    if not isinstance(grid, (tuple, list)) or len(grid) != 2:
        raise ValueError("grid must be a pair (g1, g2) of 1-D arrays")
    starts, b, dirs, axis_names = plane_starts(system, grid[0], grid[1], plane, base)
    if isinstance(entropy_box, bool) or not isinstance(entropy_box, int) or entropy_box < 1:
        raise ValueError(f"entropy_box must be an integer >= 1, got {entropy_box!r}")
    meta = {
        "g1": np.asarray(grid[0], dtype=float).tolist(),
        "g2": np.asarray(grid[1], dtype=float).tolist(),
        "axis_names": axis_names, "base": b.tolist(), "directions": dirs.tolist(),
    }  # fmt: skip
    return starts, meta


# ------------------------------------------------------------------ the driver
def basins(
    system: System,
    grid: Any,
    *,
    plane: Any = ("x1", "phi1"),
    base: Any = None,
    t_end: float = 3000.0,
    t_transient: float = 0.0,
    stop: str = "converged",
    out: str | Path | None = None,
    threads: int | None = None,
    backend: str = "local",
    scheduler: str | None = None,
    n_workers: int | None = None,
    progress: bool | None = None,
    chunk_size: int | None = None,
    max_points: int = DEFAULT_CENSUS_POINTS,
    identity_tol: float | None = None,
    entropy_box: int = DEFAULT_ENTROPY_BOX,
    refine: dict | None = None,
    title: str = "",
    notes: str = "",
    **settings: Any,
) -> BasinsResult:
    """Label every cell of a grid over a plane of starts with the attractor it reaches.

    Parameters
    ----------
    system : System
        The system (its parameter values; ``eta`` is the census value).
    grid : (array_like, array_like)
        (g1, g2): increasing coordinates along the plane's two axes.
    plane : (str, str) or (array_like, array_like)
        Two state names (default ``("x1", "phi1")``) or two direction vectors
        (:func:`plane_starts`).
    base : array_like, optional
        The state whose other coordinates the plane keeps (default zeros).
    t_end, t_transient, stop
        As for :func:`census`; ``stop="converged"`` (the default): ``t_end`` is the cap.
    out : path, optional
        HDF5 file (docs/basins.md): the census datasets plus ``/basins``. The same
        map on it resumes; a different configuration is refused.
    threads, backend, scheduler, n_workers, progress, chunk_size
        As for :func:`census` (results do not depend on them; cuda files are all-GPU).
    max_points, identity_tol, **settings
        As for :func:`census` (``method``, ``rtol``, ``atol``, ``h``, ``max_steps``,
        ``equilibrium_tol``, ``period_tol``, ``dwell``).
    entropy_box : int
        Box side in cells of the stored basin entropies.
    refine : dict, optional
        Also refine the boundary by bisection: keyword arguments of
        :func:`stickslip_fast.analysis.basins_boundary.refine_boundary` (``tol``,
        ``max_segments``, ``seed``); stored in ``/basins/boundary``.
    title, notes : str

    Returns
    -------
    BasinsResult
    """
    from .basins_boundary import refine_boundary
    from .census import census

    starts, meta = _starts_and_meta(system, grid, plane, base, entropy_box)
    res = census(
        system, "eta", [system.eta], starts=starts, t_end=t_end, t_transient=t_transient,
        stop=stop, out=out, threads=threads, backend=backend, scheduler=scheduler,
        n_workers=n_workers, progress=progress, chunk_size=chunk_size, max_points=max_points,
        identity_tol=identity_tol, title=title, notes=notes,
        _config_extra={"kind": "basins", "basins": meta},
        _desc=f"basins {len(meta['g1'])}x{len(meta['g2'])}", **settings,
    )  # fmt: skip
    meta["identity_tol"] = identity_tol
    result = _result(res, meta, entropy_box)
    if out is not None:
        _write(out, result)
    if refine is not None:
        refine_boundary(result, threads=threads, progress=progress, **dict(refine))
    return result


def load_basins(path: str | Path, *, entropy_box: int | None = None) -> BasinsResult:
    """Open a basins file as a :class:`BasinsResult` (classified from its runs).

    Cells not computed yet (an unfinished file) are labelled -1. The refined
    boundary, the saddle check and the stable manifold are read back when the file has them.
    """
    from ..io.basins import read_basins_meta
    from .census import load_census

    meta, stored_box = read_basins_meta(path)
    res = load_census(path)
    result = _result(res, meta, entropy_box or stored_box or DEFAULT_ENTROPY_BOX)
    result.boundary, result.edge, result.manifold = read_extras(path)
    return result


def read_extras(path: str | Path) -> tuple[Any, Any, Any]:
    """The refined boundary, the saddle check and the stable manifold of a basins file
    (``Boundary``, ``EdgeCheck``, ``StableManifold``; each None where the file has none)."""
    from ..io.basins_extras import read_basins_extras
    from .basins_boundary import Boundary, EdgeCheck
    from .basins_manifold import StableManifold

    found = read_basins_extras(path)
    return tuple(None if d is None else cls(**d)
                 for cls, d in zip((Boundary, EdgeCheck, StableManifold), found))  # fmt: skip
