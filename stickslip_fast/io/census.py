"""Census result files: runs per (value, start) or (cell, start) of a plane, classification, tracks."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from ..core.poincare import STATUS_NAMES
from .layout import (
    _DESCRIPTIONS,
    PER_VALUE_FIELDS,
    SCHEMA_VERSION,
    add_point_and_state_scales,
    create_run_datasets,
    write_root_attrs,
)
from .sweepfile import SweepFile

#: Per-run integer datasets of a census file and their dtypes.
CENSUS_RUN_FIELDS = PER_VALUE_FIELDS


@dataclass
class CensusLayout:
    """Shape information of a census file (``param2``/``values2``: a census over a plane)."""

    param: str
    values: np.ndarray
    starts: np.ndarray
    max_points: int
    state_names: list[str]
    converged: bool = False  # stop="converged": also a t_converged dataset
    param2: str | None = None
    values2: np.ndarray | None = None

    @property
    def value_shape(self) -> tuple[int, ...]:
        """(n_values,), or (n1, n2) for a plane."""
        if self.param2 is None:
            return (len(self.values),)
        return (len(self.values), len(self.values2))

    @property
    def grid_shape(self) -> tuple[int, ...]:
        """The leading shape of every per-run dataset in the file."""
        return (*self.value_shape, len(self.starts))

    @property
    def run_shape(self) -> tuple[int, int]:
        """(n_cells, n_starts): the runs as the census computes them (cells in C order)."""
        return (int(np.prod(self.value_shape)), len(self.starts))

    @property
    def result_fields(self) -> tuple[str, ...]:
        """The per-run datasets (what a resume checks and a rebuild copies)."""
        extra = ("t_converged",) if self.converged else ()
        return ("points", "final_state", *CENSUS_RUN_FIELDS, *extra)


class CensusFile(SweepFile):
    """Create, check and append to a census file (see the census schema above).

    Opening, resuming, the configuration check and the writer lock are those
    of :class:`SweepFile`; only the layout and the writes differ.
    """

    @staticmethod
    def empty_arrays(layout: CensusLayout) -> dict[str, np.ndarray]:
        """In-memory arrays of a census without a file (the file's fill values)."""
        grid = layout.run_shape
        n = len(layout.state_names)
        out = {
            "points": np.full(grid + (layout.max_points, n), np.nan),
            "t_points": np.full(grid + (layout.max_points,), np.nan),
            "final_state": np.full(grid + (n,), np.nan),
            "done": np.zeros(grid, dtype="u1"),
        }
        for k, v in CENSUS_RUN_FIELDS.items():
            out[k] = np.full(grid, -1 if k == "status" else 0, dtype=v)
        if layout.converged:
            out["t_converged"] = np.full(grid, np.nan)
        return out

    @staticmethod
    def _create_layout(h5, layout, text, digest, config, title, notes, package_version):
        a = h5.attrs
        write_root_attrs(a, text, digest, title, notes, package_version, kind="census")
        a["param"] = layout.param
        if layout.param2 is not None:
            a["param2"] = layout.param2
        a["classified"] = 0
        for key in ("method", "rtol", "atol", "h", "t_end", "t_transient", "max_points"):
            a[key] = config["settings"][key]
        a["stop"] = config["stop"]
        for key, value in config["system"].items():
            if value is not None:
                a[f"system.{key}"] = value
        scales = {}
        axes = [(layout.param, layout.values)]
        if layout.param2 is not None:
            axes.append((layout.param2, layout.values2))
        for name, values in axes:
            d = h5.create_dataset(name, data=np.asarray(values, dtype="f8"))
            d.make_scale(name)
            d.attrs["long_name"] = f"swept parameter {name} (nondimensional)"
            scales[name] = d
        n_s = len(layout.starts)
        d = h5.create_dataset("start", data=np.arange(n_s, dtype="i4"))
        d.make_scale("start")
        d.attrs["long_name"] = "index of the initial state"
        scales["start"] = d
        add_point_and_state_scales(h5, layout.max_points, layout.state_names, scales)
        d = h5.create_dataset("initial_state", data=np.asarray(layout.starts, dtype="f8"))
        d.dims[0].attach_scale(scales["start"])
        d.dims[1].attach_scale(scales["state"])
        d.attrs["description"] = "The initial state of every start"

        grid = layout.grid_shape
        gdims = (*(name for name, _ in axes), "start")
        n = len(layout.state_names)
        kp = layout.max_points
        specs = {
            "points": (grid + (kp, n), "f8", gdims + ("point", "state"), np.nan),
            "final_state": (grid + (n,), "f8", gdims + ("state",), np.nan),
            "done": (grid, "u1", gdims, 0),
            "label": (grid, "i4", gdims, -2),
        }
        for name, dtype in CENSUS_RUN_FIELDS.items():
            specs[name] = (grid, dtype, gdims, -1 if name == "status" else 0)
        if layout.converged:
            specs["t_converged"] = (grid, "f8", gdims, np.nan)
        descriptions = dict(_DESCRIPTIONS)
        descriptions["t_converged"] = (
            "stop='converged': time at which the run was found converged (NaN: never)"
        )
        descriptions["label"] = (
            "Track id of the attractor each run reached; -1: failed or no crossings; "
            "-2: not classified yet"
        )
        descriptions["final_state"] = "State at t_end"
        lead = len(gdims) - 1  # the value axes (one, or two for a plane)

        def chunks_of(name, shape):
            if kp == 0 and name == "points":
                return None
            return (1,) * lead + (min(n_s, 256),) + tuple(min(s, 256) for s in shape[lead + 1 :])

        create_run_datasets(h5, specs, chunks_of, descriptions, scales, STATUS_NAMES)

    def write_pairs(self, flat: np.ndarray, data: dict[str, np.ndarray]) -> None:
        """Write runs at sorted flat (cell, start) indices and flush; ``done`` last.

        A cell of a plane is ``i * n2 + j`` (C order), as :attr:`CensusLayout.run_shape`.
        """
        shape = self.h5["done"].shape
        vi, si = np.divmod(np.asarray(flat), shape[-1])
        runs = []
        a = 0
        for j in range(1, len(flat) + 1):
            if j == len(flat) or vi[j] != vi[a] or si[j] != si[j - 1] + 1:
                lead = tuple(int(x) for x in np.unravel_index(int(vi[a]), shape[:-1]))
                runs.append((lead, slice(int(si[a]), int(si[j - 1]) + 1), slice(a, j)))
                a = j
        names = ["points", "final_state", *CENSUS_RUN_FIELDS]
        if "t_converged" in self.h5:
            names.append("t_converged")
        for name in names:
            ds = self.h5[name]
            for v, s, part in runs:
                ds[(*v, s)] = data[name][part]
        self.h5.flush()
        for v, s, _ in runs:
            self.h5["done"][(*v, s)] = 1
        self.h5.flush()


def read_census(path: str | Path) -> dict[str, Any]:
    """Read a census file's runs and configuration into memory."""
    out: dict[str, Any] = {}
    with h5py.File(path, "r", libver="latest", swmr=True) as h5:
        if h5.attrs.get("kind") != "census" or h5.attrs.get("schema_version") != SCHEMA_VERSION:
            raise ValueError(f"{path}: not a stickslip_fast census file")
        out["config"] = json.loads(h5.attrs["config"])
        out["attrs"] = {k: (v.item() if hasattr(v, "item") else v) for k, v in h5.attrs.items()}
        param = str(h5.attrs["param"])
        out["param"] = param
        out["values"] = h5[param][...]
        if "param2" in h5.attrs:  # a census over a plane: runs are (n1, n2, n_starts, ...)
            out["param2"] = str(h5.attrs["param2"])
            out["values2"] = h5[out["param2"]][...]
        out["starts"] = h5["initial_state"][...]
        out["state_names"] = [s.decode() if isinstance(s, bytes) else s for s in h5["state"][...]]
        # done first: a run flagged done then has all its data flushed (the writer
        # sets done after the data), even while a census is appending to the file
        for name in ("done", "points", "final_state", "label", *CENSUS_RUN_FIELDS):
            out[name] = h5[name][...]
        if "t_converged" in h5:
            out["t_converged"] = h5["t_converged"][...]
    return out


def write_census_classification(
    path: str | Path, labels: np.ndarray, attractors: list, tracks: list, kinds: tuple,
    settings: dict[str, float], *, track_columns: dict[str, tuple] | None = None,
) -> None:  # fmt: skip
    """Store labels, the attractor table and the track table in a finished census file.

    Replaces an earlier classification (the groups are rewritten whole). For a
    census over a plane ``labels`` is (n1, n2, n_starts), ``attractors`` is
    nested per cell (``attractors[i][j]``) and ``track_columns`` gives the
    track table's columns (name: (array, description)); the attractor table
    then has ``value_index`` and ``value_index2`` columns.
    """
    cells = [((i,), atts) for i, atts in enumerate(attractors)]
    if labels.ndim == 3:
        cells = [((i, j), atts) for i, row in enumerate(attractors) for j, atts in enumerate(row)]
    rows = [a for _, atts in cells for a in atts]
    cidx = np.array([c for c, atts in cells for _ in atts], dtype="i4")
    cidx = cidx.reshape(len(rows), labels.ndim - 1)
    with h5py.File(path, "r+", libver="latest") as h5:
        h5.attrs["classified"] = 0
        h5.flush()
        h5["label"][...] = labels
        for name in ("attractors", "tracks"):
            if name in h5:
                del h5[name]
        _write_attractor_table(h5, rows, cidx, kinds)
        t = h5.create_group("tracks")
        t.attrs["description"] = "Attractors matched over neighbouring values"
        sc = t.create_dataset("track", data=np.arange(len(tracks), dtype="i4"))
        sc.make_scale("track")
        for name, (arr, desc) in (track_columns or _track_columns(tracks, kinds)).items():
            kw = {"dtype": h5py.string_dtype()} if arr.dtype == object else {}
            d = t.create_dataset(name, data=arr, **kw)
            d.dims[0].attach_scale(sc)
            if desc:
                d.attrs["description"] = desc
        t["kind"].attrs["flag_values"] = np.arange(len(kinds), dtype="i1")
        t["kind"].attrs["flag_meanings"] = " ".join(kinds)
        for key, value in settings.items():
            h5.attrs[key] = value
        h5.flush()
        h5.attrs["classified"] = 1


def _track_columns(tracks: list, kinds: tuple) -> dict[str, tuple]:
    """The track table of a one-parameter census: (array, description) per column."""
    return {
        "kind": (np.array([kinds.index(x.kind) for x in tracks], dtype="i1"), ""),
        "birth": (np.array([x.birth for x in tracks], dtype="i4"),
                  "index of the first value where the track exists"),
        "death": (np.array([x.death for x in tracks], dtype="i4"),
                  "index of the last value where the track exists"),
        "born": (np.array([x.born for x in tracks], dtype="u1"),
                 "1: born inside the range (birth > 0)"),
        "dies": (np.array([x.dies for x in tracks], dtype="u1"),
                 "1: dies inside the range (death < n_values - 1)"),
        "periods": (np.array([",".join(map(str, x.periods)) for x in tracks], dtype=object), ""),
    }  # fmt: skip


def _write_attractor_table(h5, rows: list, cidx: np.ndarray, kinds: tuple) -> None:
    """The ``/attractors`` group: one row per attractor of every value (or cell)."""
    n = len(h5["state"])
    width = max([1, *(len(a.points) for a in rows)])
    g = h5.create_group("attractors")
    g.attrs["description"] = "Every attractor at every value (one row each)"
    sc = g.create_dataset("attractor", data=np.arange(len(rows), dtype="i4"))
    sc.make_scale("attractor")
    op = g.create_dataset("orbit_point", data=np.arange(width, dtype="i4"))
    op.make_scale("orbit_point")
    st = g.create_dataset("state", data=h5["state"][...], dtype=h5py.string_dtype())
    st.make_scale("state")
    pts = np.full((len(rows), width, n), np.nan)
    for r, a in enumerate(rows):
        pts[r, : len(a.points)] = a.points
    cols = {"value_index": (cidx[:, 0], "index of the value (0-based)")}
    if cidx.shape[1] == 2:
        cols["value_index"] = (cidx[:, 0], "index of the cell's first parameter (0-based)")
        cols["value_index2"] = (cidx[:, 1], "index of the cell's second parameter (0-based)")
    cols.update({
        "track": (np.array([a.id for a in rows], dtype="i4"), "track id"),
        "kind": (np.array([kinds.index(a.kind) for a in rows], dtype="i1"), "kind"),
        "period": (np.array([a.period for a in rows], dtype="i4"), "period (0: none)"),
        "count": (np.array([a.count for a in rows], dtype="i4"), "starts reaching it"),
        "fraction": (np.array([a.fraction for a in rows], dtype="f8"), "basin fraction"),
        "first_start": (np.array([a.first_start for a in rows], dtype="i4"),
                        "lowest start reaching it (its points come from that run)"),
    })  # fmt: skip
    for name, (arr, desc) in cols.items():
        d = g.create_dataset(name, data=arr)
        d.dims[0].attach_scale(sc)
        d.attrs["description"] = desc
    g["kind"].attrs["flag_values"] = np.arange(len(kinds), dtype="i1")
    g["kind"].attrs["flag_meanings"] = " ".join(kinds)
    d = g.create_dataset("points", data=pts)
    for i, s in enumerate((sc, op, st)):
        d.dims[i].attach_scale(s)
    d.attrs["description"] = (
        "orbit: its Poincare points rotated to begin at the smallest x1; equilibrium, "
        "stalled: the state (one row); unresolved: the last points of its first run"
    )
