"""The boundary of a basin map: bisection refinement and the saddle ("edge tracking") check.

:func:`refine_boundary` bisects the segment between neighbouring cells of
different labels, running the midpoints with the engine (all active segments of
one bisection step in one parallel batch), until the bracket is shorter than
``tol``. Its end points straddle the boundary: two starts ``tol`` apart that
reach different attractors.

:func:`stickslip_fast.bifurcation.basin_saddles.edge_check` (it needs the
orbit solver, a layer above) follows trajectories from refined boundary points. A start on
the boundary between two basins stays on it; if the boundary is the stable
manifold of a saddle orbit, the trajectory goes to that saddle and lingers near
it (for as long as its distance from the boundary, at most ``tol``, takes to
grow by the saddle's unstable multiplier) before it falls to one side. The check
finds the orbit the boundary trajectories linger at (Newton on the return map
from their most nearly recurrent Poincare point, or an orbit given, e.g. from
:func:`stickslip_fast.continue_orbit`), and measures how close they come to it,
for how many crossings, against control trajectories from cells away from the
boundary (docs/basins.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..base.terminal import show_progress
from . import basins_measures as bm

__all__ = ["Boundary", "refine_boundary", "EdgeCheck"]


@dataclass
class Boundary:
    """Refined boundary segments of a basin map (plane coordinates).

    Attributes
    ----------
    u, v : ndarray (m,)
        The refined boundary points (bracket midpoints).
    ua, ub : ndarray (m, 2)
        The final bracket: ``ua`` reaches ``label_a``, ``ub`` reaches ``label_b``.
    label_a, label_b : ndarray of int (m,)
    status : ndarray of int (m,)
        0: refined to ``tol``; 1: a midpoint reached a third outcome (another
        attractor or a failed run), the bracket stops there.
    tol : float
        Bracket length reached (plane units).
    n_pairs : int
        Differently labelled neighbour pairs on the map (the segments are a
        seeded sample of them when more than ``max_segments``).
    n_runs : int
        Engine runs the refinement took.
    seed : int
    """

    u: np.ndarray
    v: np.ndarray
    ua: np.ndarray
    ub: np.ndarray
    label_a: np.ndarray
    label_b: np.ndarray
    status: np.ndarray
    tol: float
    n_pairs: int
    n_runs: int
    seed: int


def _segments(result: Any, max_segments: int | None, seed: int) -> tuple:
    pairs = bm.boundary_pairs(result.labels)
    n_pairs = len(pairs)
    if max_segments is not None and n_pairs > max_segments:
        pick = np.sort(np.random.default_rng(seed).choice(n_pairs, max_segments, replace=False))
        pairs = pairs[pick]
    ua = np.stack([result.g1[pairs[:, 0]], result.g2[pairs[:, 1]]], axis=1)
    ub = np.stack([result.g1[pairs[:, 2]], result.g2[pairs[:, 3]]], axis=1)
    la = result.labels[pairs[:, 0], pairs[:, 1]].astype(np.int32)
    lb = result.labels[pairs[:, 2], pairs[:, 3]].astype(np.int32)
    return ua, ub, la, lb, n_pairs


def _resume(result: Any, config: dict, restart: bool) -> dict | None:
    """The checkpoint of an unfinished refinement with this ``config``, or None."""
    from ..io.basins import read_refine_progress

    saved = read_refine_progress(result.path)
    if saved is None or restart:
        return None
    for key, value in config.items():
        if saved["config"].get(key) != value:
            raise ValueError(
                f"{result.path}: an unfinished boundary refinement with {key}="
                f"{saved['config'].get(key)!r} is stored, this call asks {key}={value!r}; "
                "rerun with the stored settings to resume it, or pass restart=True to discard it"
            )
    return saved


def _bisect(result: Any, ua, ub, la, lb, status, tol: float, threads: Any) -> int:
    """One bisection step of every active bracket, in place; returns the runs it took."""
    act = np.flatnonzero((status == 0) & (np.linalg.norm(ub - ua, axis=1) > tol))
    if act.size == 0:
        return 0
    mid = 0.5 * (ua[act] + ub[act])
    lm = result.label_plane(mid, threads=threads)
    to_a, to_b = lm == la[act], lm == lb[act]
    ua[act[to_a]] = mid[to_a]
    ub[act[to_b]] = mid[to_b]
    status[act[~(to_a | to_b)]] = 1
    return int(act.size)


def refine_boundary(
    result: Any,
    *,
    tol: float | None = None,
    max_segments: int | None = 400,
    seed: int = 0,
    threads: int | None = None,
    progress: bool | None = None,
    store: bool = True,
    restart: bool = False,
) -> Boundary:
    """Refine the boundary of a basin map by bisection between differently labelled cells.

    With a file (``store`` and a result read from or written to a file), the
    brackets are saved after every bisection step, and a call with the same
    ``tol``, ``max_segments`` and ``seed`` after an interruption resumes from the
    last saved step, with a result bit-identical to an uninterrupted run.

    Parameters
    ----------
    result : BasinsResult
    tol : float, optional
        Final bracket length in plane units (default: 1/64 of g1's step).
    max_segments : int or None
        Refine a seeded sample of at most this many neighbour pairs (None: all).
    seed : int
        Seed of that sample.
    threads, progress
        As for :func:`basins` (the runs do not depend on ``threads``).
    store : bool
        Write ``/basins/boundary`` into the result's file (if it has one), and
        checkpoint the brackets there while refining.
    restart : bool
        Discard an unfinished refinement stored in the file instead of resuming
        it (without this, one stored with other settings is an error naming the
        setting).

    Returns
    -------
    Boundary
        Also set as ``result.boundary``.
    """
    tol = _check_refine_args(result, tol, max_segments)
    ua, ub, la, lb, n_pairs = _segments(result, max_segments, seed)
    status = np.zeros(len(ua), dtype=np.int8)
    length = np.max(np.linalg.norm(ub - ua, axis=1)) if len(ua) else 0.0
    n_iter = int(np.ceil(np.log2(length / tol))) if length > tol else 0
    filed = store and result.path is not None
    config = {"tol": tol, "max_segments": max_segments, "seed": int(seed), "n_segments": len(ua)}
    saved = _resume(result, config, restart) if filed else None
    done, n_runs = (saved["step"], saved["n_runs"]) if saved else (0, 0)
    if saved:
        ua, ub, status = saved["ua"], saved["ub"], saved["status"].astype(np.int8)
    n_runs = _bisect_all(result, (ua, ub, la, lb, status), tol, threads, (done, n_iter), n_runs,
                         config if filed else None, progress)  # fmt: skip
    c = 0.5 * (ua + ub)
    b = Boundary(c[:, 0], c[:, 1], ua, ub, la, lb, status, tol, n_pairs, n_runs, int(seed))
    result.boundary = b
    if filed:
        _store_boundary(result.path, b)
    return b


def _check_refine_args(result: Any, tol: float | None, max_segments: int | None) -> float:
    """The bracket length to refine to (default: 1/64 of g1's step), arguments checked."""
    step = float(np.min(np.diff(result.g1)))
    tol = step / 64.0 if tol is None else float(tol)
    if not np.isfinite(tol) or tol <= 0:
        raise ValueError(f"tol must be a number > 0, got {tol!r}")
    if max_segments is not None and (isinstance(max_segments, bool) or max_segments < 1):
        raise ValueError(f"max_segments must be an integer >= 1 or None, got {max_segments!r}")
    return tol


def _bisect_all(
    result: Any,
    brackets: tuple,
    tol: float,
    threads: Any,
    steps: tuple[int, int],
    n_runs: int,
    checkpoint: dict | None,
    progress: bool | None,
) -> int:
    """Bisection steps ``steps[0]`` to ``steps[1]`` of the brackets (ua, ub, la, lb,
    status; changed in place), until none is active; returns the runs taken in all.

    With ``checkpoint`` (the refinement's configuration), the brackets are written to the
    result's file after every step, so that an interrupted refinement resumes there."""
    ua, ub, la, lb, status = brackets
    done, n_iter = steps
    bar = None
    if show_progress(progress) and n_iter:
        from tqdm.auto import tqdm

        bar = tqdm(total=n_iter, initial=done, desc="boundary bisection", unit="step")
    for k in range(done, n_iter):
        took = _bisect(result, ua, ub, la, lb, status, tol, threads)
        if took == 0:
            break
        n_runs += took
        if checkpoint is not None:
            from ..io.basins import write_refine_progress

            write_refine_progress(result.path, checkpoint, k + 1, n_runs, ua, ub, status)
        if bar is not None:
            bar.update()
    if bar is not None:
        bar.close()
    return n_runs


def _store_boundary(path: Any, b: Boundary) -> None:
    """Write ``/basins/boundary`` (replacing one there) and drop the refinement's checkpoint."""
    from ..io.basins_extras import store_extra

    store_extra(path, "boundary", b)


# ------------------------------------------------------------------ the saddle check
@dataclass
class EdgeCheck:
    """Do boundary trajectories linger at a saddle orbit? (see :func:`edge_check`).

    Attributes
    ----------
    saddle_points : ndarray (p, n_state)
        The saddle orbit's Poincare points (NaN when none was found).
    saddle_period : int
    saddle_T : float
    saddle_multipliers : ndarray of complex
    saddle_status : str
        ``Orbit.status`` of the Newton solve ("given" for an orbit passed in).
    u, v : ndarray (m,)
        Boundary starts followed.
    min_distance : ndarray (m,)
        Closest approach of each one's Poincare points to the saddle's (max norm).
    t_min : ndarray (m,)
        Time of that closest approach.
    n_near : ndarray of int (m,)
        Crossings within ``near`` of the saddle.
    control_min_distance : ndarray (mc,)
        The same closest approach for starts at cells away from the boundary.
    control_n_near : ndarray of int (mc,)
    near : float
    split_crossing : ndarray of int (m,)
        First crossing at which the runs from the two ends of the bracket (at
        most ``tol`` apart) are more than ``split`` apart (max norm): how long
        the pair stays on the boundary (-1: never within the run).
    t_split : ndarray (m,)
        Time of that crossing (NaN: never).
    split : float
    distances : ndarray (m, K)
        Distance of every crossing of every boundary trajectory (NaN-padded).
    """

    saddle_points: np.ndarray
    saddle_period: int
    saddle_T: float
    saddle_multipliers: np.ndarray
    saddle_status: str
    u: np.ndarray
    v: np.ndarray
    min_distance: np.ndarray
    t_min: np.ndarray
    n_near: np.ndarray
    control_min_distance: np.ndarray
    control_n_near: np.ndarray
    near: float
    split_crossing: np.ndarray
    t_split: np.ndarray
    split: float
    distances: np.ndarray = field(repr=False)

    @property
    def summary(self) -> dict[str, float]:
        """Medians of the boundary and control statistics (NaN without a saddle)."""

        def med(a: np.ndarray) -> float:
            a = np.asarray(a, dtype=float)
            return float(np.median(a[np.isfinite(a)])) if np.isfinite(a).any() else np.nan

        return {
            "boundary_median_min_distance": med(self.min_distance),
            "control_median_min_distance": med(self.control_min_distance),
            "boundary_median_n_near": float(np.median(self.n_near)),
            "control_median_n_near": float(np.median(self.control_n_near)),
            "boundary_share_near": float(np.mean(self.n_near > 0)),
            "control_share_near": float(np.mean(self.control_n_near > 0)),
            "median_split_crossing": float(np.median(self.split_crossing)),
            "median_t_split": med(self.t_split),
        }
