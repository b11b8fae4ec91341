"""The optional groups of a basins file: the refined boundary, the saddle check and a stable
manifold (``/basins/boundary``, ``/basins/edge``, ``/basins/manifold``; the layout is in
:mod:`.basins`' docstring and docs/basins.md).

This layer knows nothing of the analysis records (``Boundary``, ``EdgeCheck``,
``StableManifold``): the writers read the record's attributes by name, and the readers
return a dict of its fields, from which the analysis layer builds the record."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from .basins import drop_refine_progress, replace_subgroup, write_group

__all__ = [
    "store_extra", "read_basins_extras", "store_manifold_scan", "read_manifold_scan",
    "manifold_scan_summary",
]  # fmt: skip


def _boundary_columns(g: h5py.Group, b: Any) -> None:
    seg = ("segment",)
    write_group(
        g, {"segment": (np.arange(len(b.u), dtype="i4"), "refined boundary segment")},
        {
            "u": (b.u, seg, "refined boundary point, first axis"),
            "v": (b.v, seg, "refined boundary point, second axis"),
            "u_a": (b.ua[:, 0], seg, "bracket end reaching label_a, first axis"),
            "v_a": (b.ua[:, 1], seg, "bracket end reaching label_a, second axis"),
            "u_b": (b.ub[:, 0], seg, "bracket end reaching label_b, first axis"),
            "v_b": (b.ub[:, 1], seg, "bracket end reaching label_b, second axis"),
            "label_a": (b.label_a.astype("i4"), seg, "attractor id on side a"),
            "label_b": (b.label_b.astype("i4"), seg, "attractor id on side b"),
            "status": (b.status.astype("i1"), seg,
                       "0: refined to tol; 1: a third outcome met (bracket stopped)"),
        },
        {"tol": b.tol, "n_pairs": b.n_pairs, "n_runs": b.n_runs, "seed": b.seed},
    )  # fmt: skip


def _read_boundary(g: h5py.Group) -> dict[str, Any]:
    r = {k: g[k][...] for k in ("u", "v", "u_a", "v_a", "u_b", "v_b", "label_a", "label_b",
                                "status")}  # fmt: skip
    a = g.attrs
    return {
        "u": r["u"], "v": r["v"], "ua": np.stack([r["u_a"], r["v_a"]], 1),
        "ub": np.stack([r["u_b"], r["v_b"]], 1), "label_a": r["label_a"],
        "label_b": r["label_b"], "status": r["status"], "tol": float(a["tol"]),
        "n_pairs": int(a["n_pairs"]), "n_runs": int(a["n_runs"]), "seed": int(a["seed"]),
    }  # fmt: skip


def _edge_columns(g: h5py.Group, e: Any) -> None:
    mult = np.asarray(e.saddle_multipliers)
    tr, ctl = ("track",), ("control",)
    write_group(
        g,
        {"track": (np.arange(len(e.u), dtype="i4"), "boundary trajectory"),
         "control": (np.arange(len(e.control_min_distance), dtype="i4"), "control"),
         "crossing": (np.arange(e.distances.shape[1], dtype="i4"), "Poincare crossing"),
         "saddle_point": (np.arange(len(e.saddle_points), dtype="i4"), "saddle point"),
         "state": (g.parent["state"][...], "state variable")},
        {"u": (e.u, tr, "start, first axis"),
         "v": (e.v, tr, "start, second axis"),
         "min_distance": (e.min_distance, tr, "closest approach to the saddle"),
         "t_min": (e.t_min, tr, "time of the closest approach"),
         "n_near": (e.n_near.astype("i4"), tr, "crossings within near"),
         "split_crossing": (e.split_crossing.astype("i4"), tr,
                            "first crossing where the bracket's two runs differ by > split"),
         "t_split": (e.t_split, tr, "time of that crossing"),
         "distances": (e.distances, ("track", "crossing"), "distance per crossing"),
         "control_min_distance": (e.control_min_distance, ctl,
                                  "closest approach from cells away from the boundary"),
         "control_n_near": (e.control_n_near.astype("i4"), ctl,
                            "crossings within near, controls"),
         "saddle_points": (e.saddle_points, ("saddle_point", "state"),
                           "the saddle orbit's Poincare points")},
        {"saddle_period": e.saddle_period, "saddle_T": e.saddle_T,
         "saddle_status": e.saddle_status, "near": e.near, "split": e.split,
         "saddle_multipliers": json.dumps([[z.real, z.imag] for z in mult.tolist()])},
    )  # fmt: skip


def _read_edge(g: h5py.Group) -> dict[str, Any]:
    a = g.attrs
    arrays = ("saddle_points", "u", "v", "min_distance", "t_min", "n_near",
              "control_min_distance", "control_n_near", "split_crossing", "t_split",
              "distances")  # fmt: skip
    out: dict[str, Any] = {k: g[k][...] for k in arrays}
    out.update(
        saddle_period=int(a["saddle_period"]), saddle_T=float(a["saddle_T"]),
        saddle_multipliers=np.array([complex(*z) for z in json.loads(a["saddle_multipliers"])]),
        saddle_status=str(a["saddle_status"]), near=float(a["near"]), split=float(a["split"]),
    )  # fmt: skip
    return out


def _manifold_columns(g: h5py.Group, m: Any) -> None:
    pt = ("manifold_point",)
    write_group(
        g,
        {"manifold_point": (np.arange(len(m.u), dtype="i4"), "point of the curve"),
         "saddle_point": (np.arange(len(m.saddle_points), dtype="i4"), "saddle point"),
         "state": (g.parent["state"][...], "state variable")},
        {"u": (m.u, pt, "curve point, first axis"),
         "v": (m.v, pt, "curve point, second axis"),
         "branch": (m.branch.astype("i4"), pt, "traced branch of the point"),
         "n": (m.n.astype("i4"), pt, "crossings n of the condition w.(P^n(p) - x*) = 0"),
         "target": (m.target.astype("i4"), pt, "orbit point P^n(p) lands near"),
         "residual": (m.residual, pt, "|w.(P^n(p) - x*)|, the unstable coordinate"),
         "distance": (m.distance, pt, "max-norm distance of P^n(p) to x*"),
         "mu": (m.mu, ("saddle_point",), "unstable multiplier at the orbit point"),
         "saddle_points": (m.saddle_points, ("saddle_point", "state"),
                           "the saddle orbit's points")},
        {"saddle_period": m.saddle_period, "r_local": m.r_local, "tol": m.tol,
         "ds": m.ds, "n_evals": m.n_evals,
         "branch_status": json.dumps(list(m.branch_status)),
         "settings": json.dumps(m.settings)},
    )  # fmt: skip


def _read_manifold(g: h5py.Group) -> dict[str, Any]:
    a = g.attrs
    out: dict[str, Any] = {k: g[k][...] for k in ("u", "v", "branch", "n", "target", "residual",
                                                  "distance", "saddle_points", "mu")}  # fmt: skip
    out.update(
        branch_status=json.loads(a["branch_status"]), saddle_period=int(a["saddle_period"]),
        r_local=float(a["r_local"]), tol=float(a["tol"]), ds=float(a["ds"]),
        n_evals=int(a["n_evals"]), settings=json.loads(a["settings"]),
    )  # fmt: skip
    return out


_WRITERS = {"boundary": _boundary_columns, "edge": _edge_columns, "manifold": _manifold_columns}
_READERS = {"boundary": _read_boundary, "edge": _read_edge, "manifold": _read_manifold}


def store_extra(path: str | Path, name: str, record: Any) -> None:
    """Write ``record`` as ``/basins/<name>`` of a basins file, replacing one there.

    ``name``: "boundary" (a refined boundary; the refinement's checkpoint is dropped
    with it), "edge" (the saddle check) or "manifold" (a stable manifold).
    """
    if name not in _WRITERS:
        raise ValueError(f"name must be one of {sorted(_WRITERS)}, got {name!r}")
    with replace_subgroup(path, name) as h5:
        _WRITERS[name](h5["basins"].create_group(name), record)
        if name == "boundary":
            drop_refine_progress(h5)


def read_basins_extras(path: str | Path) -> tuple[dict | None, dict | None, dict | None]:
    """The fields of the refined boundary, the saddle check and the stable manifold of a
    basins file, each a dict (the record's fields by name) or None where the file has none.
    """
    with h5py.File(path, "r", libver="latest", swmr=True) as h5:
        g = h5.get("basins")
        found = [
            _READERS[name](g[name]) if g is not None and name in g else None
            for name in ("boundary", "edge", "manifold")
        ]
    return found[0], found[1], found[2]


#: The seed scan of a stable manifold (``stable_manifold(..., seeds="scan")``), kept so that
#: a second trace of the same saddle in the same plane need not scan again.
SCAN_GROUP = "manifold_scan"


def store_manifold_scan(path: str | Path, key: str, scan: dict[str, Any]) -> None:
    """Write a seed scan (:func:`~stickslip_fast.bifurcation.stable_manifold.manifold_seeds`'s
    dict) as ``/basins/manifold_scan``, replacing one there; ``key`` (text) names the
    scan's inputs, and :func:`read_manifold_scan` gives the scan back only for that key."""
    with replace_subgroup(path, SCAN_GROUP) as h5:
        g = h5["basins"].create_group(SCAN_GROUP)
        seed, edge = ("seed",), ("edge",)
        status = np.array(list(scan["edge_status"]), dtype=h5py.string_dtype())
        write_group(
            g,
            {"seed": (np.arange(len(scan["uv"]), dtype="i4"), "seed on the manifold"),
             "edge": (np.arange(len(scan["edge_n"]), dtype="i4"), "sign-change edge"),
             "end": (np.arange(2, dtype="i4"), "end of an edge"),
             "axis": (np.arange(2, dtype="i4"), "axis of the plane"),
             "g1": (scan["g1"], "the scan's grid, first axis"),
             "g2": (scan["g2"], "the scan's grid, second axis")},
            {"uv": (scan["uv"], ("seed", "axis"), "the seed (plane coordinates)"),
             "n": (np.asarray(scan["n"], "i4"), seed, "crossings n of the seed's condition"),
             "target": (np.asarray(scan["target"], "i4"), seed, "orbit point it lands near"),
             "residual": (scan["residual"], seed, "|g_n| at the seed"),
             "distance": (scan["distance"], seed, "max-norm distance of P^n to the orbit point"),
             "edges": (scan["edges"], ("edge", "end", "axis"), "the edge's two grid nodes"),
             "edge_n": (np.asarray(scan["edge_n"], "i4"), edge, "n of the sign change"),
             "edge_target": (np.asarray(scan["edge_target"], "i4"), edge,
                             "orbit point of the sign change"),
             "edge_status": (status, edge, "seed, or why none came of the edge"),
             "closest": (scan["closest"], ("g1", "g2"),
                         "a node's smallest distance of its images to the orbit")},
            {"r_scan": float(scan["r_scan"]), "n_max": int(scan["n_max"]),
             "n_evals": int(scan["n_evals"]), "key": key},
        )  # fmt: skip


def read_manifold_scan(path: str | Path, key: str) -> dict[str, Any] | None:
    """The seed scan stored in a basins file under ``key``, or None (none, or another key)."""
    with h5py.File(path, "r", libver="latest", swmr=True) as h5:
        g = h5.get(f"basins/{SCAN_GROUP}")
        if g is None or g.attrs.get("key") != key:
            return None
        out: dict[str, Any] = {k: g[k][...] for k in ("uv", "residual", "distance", "edges",
                                                      "closest", "g1", "g2")}  # fmt: skip
        for k in ("n", "target", "edge_n", "edge_target"):
            out[k] = g[k][...].astype(int)
        out["edge_status"] = [x.decode() if isinstance(x, bytes) else str(x)
                              for x in g["edge_status"][...]]  # fmt: skip
        out.update(r_scan=float(g.attrs["r_scan"]), n_max=int(g.attrs["n_max"]),
                   n_evals=int(g.attrs["n_evals"]))  # fmt: skip
    return out


def manifold_scan_summary(path: str | Path) -> dict[str, Any] | None:
    """What the seed scan stored in a basins file holds, whatever its key: ``grid``
    (n1, n2), ``seeds``, ``edges``, ``n_evals``; None without one (for reports)."""
    with h5py.File(path, "r", libver="latest", swmr=True) as h5:
        g = h5.get(f"basins/{SCAN_GROUP}")
        if g is None:
            return None
        return {"grid": tuple(int(k) for k in g["closest"].shape), "seeds": len(g["uv"]),
                "edges": len(g["edge_n"]), "n_evals": int(g.attrs["n_evals"])}  # fmt: skip
