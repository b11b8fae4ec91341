"""Measures of basins of attraction on label arrays and label functions (pure NumPy).

Every function here works on a 2-D array of integer labels (one attractor id per
cell of a grid; negative ids are failed or unlabelled cells) or on a vectorised
label function ``f(points) -> labels``; none of them knows about the stick-slip
model, so they are tested on maps with known basins (tests/test_basins.py).

References
----------
Daza, Wagemakers, Georgeot, Guery-Odelin, Sanjuan, "Basin entropy: a new tool to
analyze uncertainty in dynamical systems", Sci. Rep. 6, 31416 (2016).
Daza, Wagemakers, Sanjuan, "Ascertaining when a basin is Wada: the merging
method", Sci. Rep. 8, 9954 (2018) (the merging method, and the simpler grid test of
their Sec. 2).
Grebogi, McDonald, Ott, Yorke, "Final state sensitivity: an obstruction to
predictability", Phys. Lett. A 99, 415 (1983) (the uncertainty exponent).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = [
    "basin_fractions",
    "basin_entropy",
    "boundary_basin_entropy",
    "uncertain_fraction",
    "uncertainty_exponent",
    "uncertainty_exponent_fn",
    "boundary_cells",
    "boundary_pairs",
    "wada_grid_test",
    "wada_merge_test",
    "UncertaintyFit",
    "WadaTest",
    "WadaMergeTest",
]


def _labels2d(labels) -> np.ndarray:
    arr = np.asarray(labels)
    if arr.ndim != 2 or arr.size == 0:
        raise ValueError(f"labels must be a non-empty 2-D array, got shape {arr.shape}")
    if not np.issubdtype(arr.dtype, np.integer):
        raise ValueError(f"labels must be integers (attractor ids), got dtype {arr.dtype}")
    return arr


# ------------------------------------------------------------------ fractions
def basin_fractions(labels, *, include_failed: bool = True) -> dict[int, tuple[float, float]]:
    """Share of cells per label with its binomial standard error.

    Parameters
    ----------
    labels : array_like of int
        Any shape; negative labels are failed runs.
    include_failed : bool
        Count failed cells (label < 0, reported under key -1) in the total.

    Returns
    -------
    dict
        ``{id: (fraction, standard_error)}``, ids ascending; the standard error
        is sqrt(f (1 - f) / n), n the number of cells counted. Cells of a grid
        are not independent samples, so this is the error of a random start
        drawn from the box, which the grid estimates.
    """
    lab = np.asarray(labels).ravel()
    if lab.size == 0:
        raise ValueError("labels must not be empty")
    lab = np.where(lab < 0, -1, lab)
    if not include_failed:
        lab = lab[lab >= 0]
    n = lab.size
    out: dict[int, tuple[float, float]] = {}
    if n == 0:
        return out
    ids, counts = np.unique(lab, return_counts=True)
    for i, c in zip(ids, counts):
        f = c / n
        out[int(i)] = (float(f), float(np.sqrt(f * (1.0 - f) / n)))
    return out


# ------------------------------------------------------------------ entropies
def _box_entropies(labels: np.ndarray, box: int) -> tuple[np.ndarray, np.ndarray]:
    """Shannon entropy (natural log) and number of distinct labels of every box."""
    if isinstance(box, bool) or not isinstance(box, (int, np.integer)) or box < 1:
        raise ValueError(f"box must be an integer >= 1, got {box!r}")
    n1, n2 = labels.shape
    b1, b2 = n1 // box, n2 // box
    if b1 == 0 or b2 == 0:
        raise ValueError(f"box ({box}) is larger than the grid {labels.shape}")
    cut = labels[: b1 * box, : b2 * box].reshape(b1, box, b2, box).transpose(0, 2, 1, 3)
    cut = cut.reshape(b1 * b2, box * box)
    ent = np.zeros(len(cut))
    nlab = np.zeros(len(cut), dtype=int)
    for lab in np.unique(cut):
        p = np.mean(cut == lab, axis=1)
        nz = p > 0
        ent[nz] -= p[nz] * np.log(p[nz])
        nlab += nz
    return ent, nlab


def basin_entropy(labels, box: int = 5) -> tuple[float, float]:
    """Basin entropy S_b and boundary basin entropy S_bb (Daza et al. 2016).

    The grid is cut into non-overlapping boxes of ``box`` x ``box`` cells (a
    remainder at the high edges is dropped); each box has the Shannon entropy
    S_i = -sum_j p_ij ln p_ij of its labels (failed cells, label < 0, count as
    one more label). S_b is the mean of S_i over all boxes, S_bb the mean over
    the boxes holding more than one label (the boundary boxes).

    Returns
    -------
    (S_b, S_bb) : tuple of float
        S_bb is 0 when no box holds two labels. S_bb > ln 2 proves a fractal
        boundary (Daza et al.'s log-2 criterion; the converse does not hold).
    """
    lab = _labels2d(labels)
    lab = np.where(lab < 0, -1, lab)
    ent, nlab = _box_entropies(lab, box)
    bnd = nlab > 1
    return float(ent.mean()), float(ent[bnd].mean()) if bnd.any() else 0.0


def boundary_basin_entropy(labels, box: int = 5) -> float:
    """Boundary basin entropy S_bb alone (see :func:`basin_entropy`)."""
    return basin_entropy(labels, box)[1]


# ------------------------------------------------------- uncertainty exponent
@dataclass
class UncertaintyFit:
    """A fit f(eps) ~ eps^alpha of the uncertain fraction.

    Attributes
    ----------
    alpha : float
        Uncertainty exponent (NaN if fewer than two eps have f > 0).
    alpha_stderr : float
        Standard error of the slope of the least-squares fit in log-log.
    eps, f : ndarray
        The distances and uncertain fractions that were fitted.
    dimension : float
        Box-counting dimension of the boundary, D - alpha (D = the plane's 2,
        or the dimension of the label function's domain).
    """

    alpha: float
    alpha_stderr: float
    eps: np.ndarray
    f: np.ndarray
    dimension: float


def _fit(eps: np.ndarray, f: np.ndarray, dim: int) -> UncertaintyFit:
    ok = (f > 0) & np.isfinite(f)
    if ok.sum() < 2:
        return UncertaintyFit(np.nan, np.nan, eps, f, np.nan)
    x, y = np.log(eps[ok]), np.log(f[ok])
    A = np.stack([x, np.ones_like(x)], axis=1)
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    se = np.nan
    if ok.sum() > 2:
        resid = y - A @ coef
        s2 = resid @ resid / (ok.sum() - 2)
        se = float(np.sqrt(s2 / np.sum((x - x.mean()) ** 2)))
    alpha = float(coef[0])
    return UncertaintyFit(alpha, se, eps, f, dim - alpha)


def uncertain_fraction(labels, k: int) -> float:
    """Share of cell pairs k cells apart (along either axis) with different labels.

    Pairs with a failed cell (label < 0) are left out; an axis shorter than
    k + 1 cells contributes no pairs.
    """
    lab = _labels2d(labels)
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ValueError(f"k must be an integer >= 1, got {k!r}")
    n_diff = 0
    n_all = 0
    for axis in (0, 1):
        if k >= lab.shape[axis]:
            continue
        a = lab[k:, :] if axis == 0 else lab[:, k:]
        b = lab[:-k, :] if axis == 0 else lab[:, :-k]
        ok = (a >= 0) & (b >= 0)
        n_all += int(ok.sum())
        n_diff += int(np.sum((a != b) & ok))
    return n_diff / n_all if n_all else np.nan


def uncertainty_exponent(labels, ks=None, spacing: float = 1.0) -> UncertaintyFit:
    """Uncertainty exponent of a basin map from pairs of cells at k-cell distances.

    f(eps) is :func:`uncertain_fraction` at eps = k * spacing; alpha is the
    least-squares slope of ln f against ln eps, and the boundary's dimension is
    2 - alpha. Default ks: 1, 2, 4, ... up to an eighth of the smaller side
    (distances of a few cells up to where the pairs still sample the boundary
    locally).
    """
    lab = _labels2d(labels)
    if ks is None:
        top = max(2, min(lab.shape) // 8)
        ks = [1 << j for j in range(int(np.log2(top)) + 1)]
    ks = np.asarray(ks, dtype=int)
    if ks.ndim != 1 or ks.size < 2 or np.any(ks < 1) or np.any(ks >= max(lab.shape)):
        raise ValueError(f"ks must hold >= 2 distances in [1, {max(lab.shape) - 1}], got {ks}")
    f = np.array([uncertain_fraction(lab, int(k)) for k in ks])
    return _fit(ks * float(spacing), f, 2)


def uncertainty_exponent_fn(
    label_fn: Callable[[np.ndarray], np.ndarray],
    bounds,
    eps,
    n: int = 2000,
    seed: int = 0,
) -> UncertaintyFit:
    """Uncertainty exponent of a label function, from random pairs at distances eps.

    For each eps, ``n`` starts x are drawn uniformly in ``bounds`` (shrunk by
    eps at the high side) with a random axis k each; the pair (x, x + eps e_k)
    is uncertain when ``label_fn`` gives its two points different labels.

    Parameters
    ----------
    label_fn : callable
        ``label_fn(points)`` with points of shape (m, D) returns m integer labels.
    bounds : array_like, (D, 2)
        (low, high) per coordinate.
    eps : array_like
        Decreasing or increasing distances (> 0).
    n : int
        Pairs per distance.
    seed : int
        Seed of ``numpy.random.default_rng``.
    """
    b = np.asarray(bounds, dtype=float)
    if b.ndim != 2 or b.shape[1] != 2 or np.any(b[:, 1] <= b[:, 0]):
        raise ValueError(f"bounds must be (D, 2) with low < high, got {b.tolist()}")
    eps = np.asarray(eps, dtype=float)
    if eps.ndim != 1 or eps.size < 2 or np.any(eps <= 0):
        raise ValueError("eps must hold >= 2 distances > 0")
    rng = np.random.default_rng(seed)
    d = len(b)
    f = np.empty(eps.size)
    for i, e in enumerate(eps):
        x = b[:, 0] + rng.random((n, d)) * (b[:, 1] - b[:, 0] - e)
        axis = rng.integers(0, d, n)
        y = x.copy()
        y[np.arange(n), axis] += e
        la = np.asarray(label_fn(x))
        lb = np.asarray(label_fn(y))
        f[i] = np.mean(la != lb)
    return _fit(eps, f, d)


# ------------------------------------------------------------------ boundary
def boundary_cells(labels) -> np.ndarray:
    """Boolean mask of cells with a differently labelled cell among their 8 neighbours."""
    lab = _labels2d(labels)
    pad = np.pad(lab, 1, mode="edge")
    n1, n2 = lab.shape
    out = np.zeros(lab.shape, dtype=bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            out |= pad[1 + di : 1 + di + n1, 1 + dj : 1 + dj + n2] != lab
    return out


def boundary_pairs(labels) -> np.ndarray:
    """Neighbouring cells (along an axis) with different labels, both >= 0.

    Returns
    -------
    ndarray of int, (m, 4)
        Rows (i, j, i2, j2): cell (i, j) and its neighbour (i2, j2) = (i + 1, j)
        or (i, j + 1), in row-major order of (i, j), the axis-0 neighbour first.
    """
    lab = _labels2d(labels)
    rows = []
    for di, dj in ((1, 0), (0, 1)):
        a = lab[: lab.shape[0] - di, : lab.shape[1] - dj]
        b = lab[di:, dj:]
        i, j = np.nonzero((a != b) & (a >= 0) & (b >= 0))
        rows.append(np.stack([i, j, i + di, j + dj, np.full_like(i, di)], axis=1))
    allr = np.concatenate(rows)
    order = np.lexsort((1 - allr[:, 4], allr[:, 1], allr[:, 0]))
    return allr[order, :4].astype(np.int64)


# ------------------------------------------------------------------ Wada
@dataclass
class WadaTest:
    """Result of the grid Wada test.

    Attributes
    ----------
    n_basins : int
        Number of basins (labels >= 0) on the map.
    radii : ndarray
        r = 1, 2, ...: half-widths of the square neighbourhoods tried.
    fraction : ndarray
        Share of boundary cells whose (2r+1) x (2r+1) neighbourhood holds every
        basin, per r.
    is_wada : bool
        n_basins >= 3 and ``fraction`` reaches ``threshold`` at some r <= r_wada.
    r_wada : int
        The largest r the verdict took.
    """

    n_basins: int
    radii: np.ndarray
    fraction: np.ndarray
    is_wada: bool
    r_wada: int = 3


def _box_sum(a: np.ndarray, r: int) -> np.ndarray:
    """Sum of ``a`` over the (2r+1)^2 square around each cell (clipped at the edges)."""
    c = np.pad(a.astype(np.int64), ((1, 0), (1, 0))).cumsum(0).cumsum(1)
    n1, n2 = a.shape
    i0 = np.clip(np.arange(n1) - r, 0, n1)
    i1 = np.clip(np.arange(n1) + r + 1, 0, n1)
    j0 = np.clip(np.arange(n2) - r, 0, n2)
    j1 = np.clip(np.arange(n2) + r + 1, 0, n2)
    return c[i1][:, j1] - c[i0][:, j1] - c[i1][:, j0] + c[i0][:, j0]


def wada_grid_test(labels, r_max: int = 5, threshold: float = 0.99, r_wada: int = 3) -> WadaTest:
    """Grid test for the Wada property: do boundary cells see every basin nearby?

    A boundary cell (:func:`boundary_cells`, failed cells excluded) passes at
    radius r when its (2r+1) x (2r+1) neighbourhood holds a cell of every basin.
    In a Wada map every boundary point is on the boundary of all basins, so the
    share of passing cells goes to 1 at small r as the grid is refined; where
    two basins share a smooth boundary away from a third, cells fail up to the
    distance to the third basin.

    Parameters
    ----------
    labels : array_like of int, 2-D
    r_max : int
        Largest radius tried.
    threshold : float
        Share of boundary cells that must pass for ``is_wada``.
    r_wada : int
        The largest r the verdict accepts. Repeating bands 0, 1, 2, 0, ... w cells wide
        are not Wada, yet every boundary cell sees all three basins at r = w, so a
        verdict at r <= 5 called bands of 3 and 4 cells Wada (until 2026-12-02); at
        r <= 3 they fall short (97.4 % and 0 % pass at r = 3), while Newton's basins for
        z^3 = 1 pass at r = 3 on 150^2, 300^2 and 600^2 grids (99.4-99.8 %). Bands of
        2 cells pass (at r = 3), as they pass the merging test: at the grid's resolution
        they cannot be told from a Wada map.
    """
    lab = _labels2d(labels)
    ids = [int(i) for i in np.unique(lab) if i >= 0]
    radii = np.arange(1, int(r_max) + 1)
    bnd = boundary_cells(lab) & (lab >= 0)
    if len(ids) < 2 or not bnd.any():
        return WadaTest(len(ids), radii, np.zeros(radii.size), False, int(r_wada))
    frac = np.empty(radii.size)
    for k, r in enumerate(radii):
        seen = np.zeros(lab.shape, dtype=int)
        for i in ids:
            seen += _box_sum(lab == i, int(r)) > 0
        frac[k] = np.mean(seen[bnd] == len(ids))
    near = frac[radii <= int(r_wada)]
    ok = len(ids) >= 3 and bool(np.any(near >= threshold))
    return WadaTest(len(ids), radii, frac, ok, int(r_wada))


@dataclass
class WadaMergeTest:
    """Result of the merging Wada test.

    Attributes
    ----------
    n_basins : int
        Number of basins (labels >= 0) on the map.
    radii : ndarray
        r = 1, 2, ...: half-widths of the squares by which a boundary is fattened.
    uncovered : ndarray
        Per r, the largest share, over every pair of basins (i, j), of the cells of
        the boundary of basin i merged against the rest that lie farther than r
        cells (Chebyshev) from the boundary of basin j merged against the rest (and
        the same with i and j swapped). 0: the merged boundaries coincide to r. NaN
        where the map has fewer than two basins (no boundary).
    is_wada : bool
        n_basins >= 3 and ``uncovered`` falls to ``1 - threshold`` at some r <= r_wada.
    r_wada : int
        The largest r the verdict took.
    """

    n_basins: int
    radii: np.ndarray
    uncovered: np.ndarray
    is_wada: bool
    r_wada: int = 2


def _merged_boundary(lab: np.ndarray, basin: int) -> np.ndarray:
    """Cells of the two-colour map (``basin`` against all other basins) with a cell of
    the other colour among their 8 neighbours; failed cells (< 0) take no side."""
    side = np.where(lab < 0, -1, lab == basin).astype(np.int8)  # signed, whatever lab is
    pad = np.pad(side, 1, constant_values=-1)
    n1, n2 = lab.shape
    out = np.zeros(lab.shape, dtype=bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            other = pad[1 + di : 1 + di + n1, 1 + dj : 1 + dj + n2]
            out |= (other >= 0) & (other != side)
    return out & (side >= 0)


def wada_merge_test(
    labels, r_max: int = 5, threshold: float = 0.99, r_wada: int = 2
) -> WadaMergeTest:
    """The merging method for the Wada property (Daza, Wagemakers and Sanjuan 2018).

    Merge all basins but one into a single colour; the boundary of that two-colour map
    is the boundary of the one basin. In a Wada map all basins have the same boundary,
    so the merged maps' boundaries coincide; on a grid, each one fattened by r cells
    covers the others at small r. Where two basins share a stretch of boundary away
    from a third, the third's merged boundary misses that stretch up to the distance
    to the third basin. Unlike :func:`wada_grid_test`, which asks whether every basin
    lies near each boundary cell, this compares whole boundaries pairwise, so a basin
    that only touches the others at isolated points fails it.

    Parameters
    ----------
    labels : array_like of int, 2-D
        Attractor id per cell; negative ids (failed runs) belong to no basin.
    r_max : int
        Largest fattening tried.
    threshold : float
        ``is_wada`` when at most ``1 - threshold`` of any merged boundary is uncovered
        at some r <= ``r_wada``.
    r_wada : int
        The largest r the verdict accepts: a merged boundary is two cells thick (the
        cells on both sides), so boundaries that coincide in the plane lie within two
        cells of each other on the grid. A larger r covers a share of a coarse map that
        says little (the engine's η = 9.0 map, not Wada, left 1.4 % uncovered at r = 5
        on 40 x 40 cells, 11 % at r = 2).

    Returns
    -------
    WadaMergeTest

    Notes
    -----
    Daza et al. also refine the grid: a Wada map needs the same small r at every
    resolution, while for a map that is not Wada the r needed grows with the
    resolution (the distance to the third basin is fixed in the plane). That check is
    the caller's, with maps of two resolutions.
    """
    lab = _labels2d(labels)
    ids = [int(i) for i in np.unique(lab) if i >= 0]
    radii = np.arange(1, int(r_max) + 1)
    uncovered = np.full(radii.size, np.nan)
    bounds = [_merged_boundary(lab, i) for i in ids]
    if len(ids) < 2 or not all(b.any() for b in bounds):
        return WadaMergeTest(len(ids), radii, uncovered, False, int(r_wada))
    for k, r in enumerate(radii):
        fat = [_box_sum(b, int(r)) > 0 for b in bounds]
        worst = 0.0
        for i in range(len(ids)):
            for j in range(len(ids)):
                if i != j:
                    worst = max(worst, float(np.mean(~fat[j][bounds[i]])))
        uncovered[k] = worst
    near = uncovered[radii <= int(r_wada)]
    ok = len(ids) >= 3 and bool(np.any(near <= 1.0 - threshold))
    return WadaMergeTest(len(ids), radii, uncovered, ok, int(r_wada))
