"""Basins files: a one-value census file plus a ``/basins`` group (docs/basins.md).

A basins file is a census file (root attribute ``kind = "census"``, one value of
``eta``, one start per cell, row-major: cell (i, j) is start ``i * n2 + j``), so
the census datasets, resume, configuration check and classification are the
census's; its configuration (root ``config``) also holds ``"kind": "basins"`` and
the grid, plane and base. The ``/basins`` group, written once the map is
complete (rewritten whole on a re-run, keeping ``boundary`` and ``edge``)::

    /basins                    attrs: axis_names (JSON), eta, entropy_box, and the
                               measures: basin_entropy, boundary_basin_entropy,
                               boundary_box_fraction, uncertainty_exponent(_stderr),
                               boundary_dimension, n_basins, wada, wada_merge,
                               failed_fraction; wada_verdict_radius and
                               wada_merge_verdict_radius (the largest r each
                               Wada verdict took: 3 and 2; absent before
                               2026-12-02, when the grid verdict took r <= 5)
      u (n1), v (n2)           coordinates along the two axes (attrs long_name)
      state (S)                state names
      label (u, v)       i4    attractor id per cell (-1: failed)
      base (state)       f8    the state whose other coordinates the plane keeps
      directions (direction, state)  the two axis vectors
      attractor (A)            scale; id, kind (flag_values / flag_meanings),
                               period, count, fraction, fraction_stderr (attractor)
      points (attractor, orbit_point, state)   as the census's /attractors/points
      k (K); eps (k); uncertain_fraction (k)   the uncertainty exponent's data
      radius (R); wada_fraction (radius)       the grid Wada test
      wada_merge_uncovered (radius)            the merging Wada test (absent from files
                                               finished before 2026-12-01; a re-run
                                               rewrites /basins with it)
      boundary/                (optional) refined boundary segments: segment scale;
                               u, v (the refined point), u_a, v_a, u_b, v_b (the
                               final bracket), label_a, label_b, status
                               (0 refined to tol, 1 a third outcome met); attrs tol,
                               n_pairs, n_runs, seed
      edge/                    (optional) the saddle check: see analysis.basins_boundary.EdgeCheck
      manifold/                (optional) a saddle orbit's stable manifold in the plane
                               (bifurcation.stable_manifold): manifold_point and
                               saddle_point scales; u, v (the curve points, in order
                               along each branch), branch, n (crossings of the
                               condition w.(P^n(p) - x*) = 0), target (the orbit
                               point P^n(p) lands near), residual (|w.(P^n(p) - x*)|),
                               distance (max norm |P^n(p) - x*|) per point; mu
                               (saddle_point), saddle_points (saddle_point, state);
                               attrs saddle_period, r_local, tol, ds, n_evals,
                               branch_status (JSON list: why each branch ended),
                               settings (JSON)
      manifold_scan/           (optional) the seed scan of stable_manifold(seeds="scan"):
                               seed, edge, end, axis, g1, g2 scales; uv (seed, axis),
                               n, target, residual, distance (seed); edges (edge, end,
                               axis), edge_n, edge_target, edge_status (edge); closest
                               (g1, g2); attrs r_scan, n_max, n_evals, key (the
                               canonical JSON of the scan's inputs, as a config's:
                               it is used again only for the same key)
      boundary_progress/       (only while a refinement is unfinished) the brackets
                               after the last completed bisection step: u_a, v_a,
                               u_b, v_b, status; attrs config (JSON: tol,
                               max_segments, seed, n_segments), step, n_runs. A
                               re-run with the same settings resumes from it; it is
                               deleted when ``boundary`` is written.

Every dataset has its dimensions attached, so
``xarray.open_dataset(path, group="basins", engine="h5netcdf")`` reads it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import h5py
import numpy as np

__all__ = [
    "write_basins",
    "read_basins_meta",
    "write_group",
    "read_refine_progress",
    "write_refine_progress",
]

_KEEP = ("boundary", "edge", "manifold", "manifold_scan", "boundary_progress")
_PROGRESS = "boundary_progress"


def _scale(g: h5py.Group, name: str, data: Any, long_name: str, **kw: Any) -> h5py.Dataset:
    d = g.create_dataset(name, data=data, **kw)
    d.make_scale(name)
    d.attrs["long_name"] = long_name
    return d


def _put(g: h5py.Group, name: str, data: Any, dims: tuple, desc: str, **kw: Any) -> None:
    d = g.create_dataset(name, data=data, **kw)
    for i, dim in enumerate(dims):
        d.dims[i].attach_scale(g[dim])
    d.attrs["description"] = desc


def write_group(g: h5py.Group, scales: dict, columns: dict, attrs: dict) -> None:
    """Fill group ``g``: ``scales`` {name: (data, long_name)}, ``columns`` {name:
    (data, dims, description)}, scalar ``attrs`` (None values are skipped)."""
    for name, (data, long_name) in scales.items():
        _scale(g, name, data, long_name)
    for name, (data, dims, desc) in columns.items():
        _put(g, name, data, dims, desc)
    for k, v in attrs.items():
        if v is not None:
            g.attrs[k] = v


def write_basins(path: str | Path, result: Any, kinds: tuple[str, ...]) -> None:
    """Write (or rewrite) the ``/basins`` group of a finished basins file.

    ``kinds`` are the attractor kinds in code order (the census's ``KINDS``;
    passed in, since io sits below the analysis layer that defines them).
    """
    KINDS = kinds  # noqa: N806

    tests = result.tests()  # each once: the Wada tests take ~1 s each on 1000 x 1000 cells
    m = result.measures(tests)
    fr = result.fractions(stderr=True)
    ue, w, wm = tests
    atts = result.attractors
    n = result.system.n_state
    width = max([1, *(len(a.points) for a in atts)])
    pts = np.full((len(atts), width, n), np.nan)
    for r, a in enumerate(atts):
        pts[r, : len(a.points)] = a.points
    with h5py.File(path, "r+", libver="latest") as h5:
        g = h5.require_group("basins")
        for name in list(g):
            if name not in _KEEP:
                del g[name]
        g.attrs["description"] = "Basins of attraction on a plane of starts (docs/basins.md)"
        g.attrs["axis_names"] = json.dumps(result.axis_names)
        g.attrs["eta"] = float(result.system.eta)
        for k, v in m.items():
            g.attrs[k] = v
        # the largest r each verdict took (absent from files before 2026-12-02, whose
        # grid verdict took any r of wada_fraction, and whose merging verdict r <= 2)
        g.attrs["wada_verdict_radius"] = int(w.r_wada)
        g.attrs["wada_merge_verdict_radius"] = int(wm.r_wada)
        names = np.array(result.system.state_names, dtype=object)
        _scale(g, "u", result.g1, f"{result.axis_names[0]}(0): first axis of the plane")
        _scale(g, "v", result.g2, f"{result.axis_names[1]}(0): second axis of the plane")
        _scale(g, "state", names, "state variable", dtype=h5py.string_dtype())
        _scale(g, "direction", np.arange(2, dtype="i4"), "axis of the plane")
        _scale(g, "attractor", np.arange(len(atts), dtype="i4"), "row of the attractor table")
        _scale(g, "orbit_point", np.arange(width, dtype="i4"), "point of the orbit")
        _scale(g, "k", ue.eps / max(float(np.mean(np.diff(result.g1))), 1e-300),
               "pair distance in cells")  # fmt: skip
        _scale(g, "radius", w.radii.astype("i4"), "half-width of the neighbourhood (cells)")
        _put(g, "label", result.labels.astype("i4"), ("u", "v"),
             "attractor id per cell (the census's ids); -1: failed run")  # fmt: skip
        _put(g, "base", result.base, ("state",), "state whose other coordinates the plane keeps")
        _put(g, "directions", result.directions, ("direction", "state"), "axis vectors")
        cols = {
            "id": (np.array([a.id for a in atts], dtype="i4"), "attractor id (census track)"),
            "kind": (np.array([KINDS.index(a.kind) for a in atts], dtype="i1"), "kind"),
            "period": (np.array([a.period for a in atts], dtype="i4"), "period (0: none)"),
            "count": (np.array([a.count for a in atts], dtype="i4"), "cells reaching it"),
            "fraction": (np.array([a.fraction for a in atts], dtype="f8"), "basin fraction"),
            "fraction_stderr": (np.array([fr[a.id][1] for a in atts], dtype="f8"),
                                "binomial standard error sqrt(f (1 - f) / n_cells)"),
        }  # fmt: skip
        for name, (arr, desc) in cols.items():
            _put(g, name, arr, ("attractor",), desc)
        g["kind"].attrs["flag_values"] = np.arange(len(KINDS), dtype="i1")
        g["kind"].attrs["flag_meanings"] = " ".join(KINDS)
        _put(
            g,
            "points",
            pts,
            ("attractor", "orbit_point", "state"),
            "Poincare points of each attractor (as the census's /attractors/points)",
        )
        _put(g, "eps", ue.eps, ("k",), "pair distance in plane units")
        _put(g, "uncertain_fraction", ue.f, ("k",), "share of cell pairs with different labels")
        _put(g, "wada_fraction", w.fraction, ("radius",),
             "share of boundary cells whose neighbourhood holds every basin")  # fmt: skip
        _put(g, "wada_merge_uncovered", wm.uncovered, ("radius",),
             "largest share of one basin's boundary farther than radius from another's")  # fmt: skip
        h5.flush()


def read_basins_meta(path: str | Path) -> tuple[dict, int | None]:
    """The grid, plane and base of a basins file (from its configuration), and its box."""
    with h5py.File(path, "r", libver="latest", swmr=True) as h5:
        cfg = json.loads(h5.attrs["config"])
        if cfg.get("kind") != "basins":
            raise ValueError(f"{path}: not a stickslip_fast basins file (a census file?)")
        box = int(h5["basins"].attrs["entropy_box"]) if "basins" in h5 else None
    return cfg["basins"], box


def replace_subgroup(path: str | Path, name: str) -> h5py.File:
    """Open ``path`` for writing with ``/basins/<name>`` deleted (the caller refills it)."""
    h5 = h5py.File(path, "r+", libver="latest")
    g = h5.require_group("basins")
    if name in g:
        del g[name]
    return h5


def read_refine_progress(path: str | Path) -> dict | None:
    """The checkpoint of an unfinished boundary refinement, or None.

    Returns a dict with ``config`` (dict), ``step`` and ``n_runs`` (int), and the
    arrays ``ua``, ``ub`` (m, 2) and ``status`` (m,).
    """
    with h5py.File(path, "r", libver="latest", swmr=True) as h5:
        g = h5.get(f"basins/{_PROGRESS}")
        if g is None:
            return None
        return {
            "config": json.loads(g.attrs["config"]),
            "step": int(g.attrs["step"]),
            "n_runs": int(g.attrs["n_runs"]),
            "ua": np.stack([g["u_a"][...], g["v_a"][...]], axis=1),
            "ub": np.stack([g["u_b"][...], g["v_b"][...]], axis=1),
            "status": g["status"][...],
        }


def write_refine_progress(
    path: str | Path, config: dict, step: int, n_runs: int, ua: np.ndarray, ub: np.ndarray,
    status: np.ndarray,
) -> None:  # fmt: skip
    """Replace the refinement checkpoint by the brackets after bisection step ``step``."""
    with replace_subgroup(path, _PROGRESS) as h5:
        g = h5["basins"].create_group(_PROGRESS)
        for name, data in (("u_a", ua[:, 0]), ("v_a", ua[:, 1]), ("u_b", ub[:, 0]),
                           ("v_b", ub[:, 1]), ("status", status.astype("i1"))):  # fmt: skip
            g.create_dataset(name, data=data)
        g.attrs.update(config=json.dumps(config), step=int(step), n_runs=int(n_runs))
        h5.flush()


def drop_refine_progress(h5: h5py.File) -> None:
    """Delete the refinement checkpoint of an open file (its refinement is stored)."""
    if _PROGRESS in h5.get("basins", {}):
        del h5["basins"][_PROGRESS]
