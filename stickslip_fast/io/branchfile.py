"""The HDF5 file of a continued branch (``Branch.to_hdf5``; schema: docs/orbits.md, "Branch
files").

The layer below :mod:`stickslip_fast.bifurcation` knows nothing of the ``Branch`` record:
it writes and reads a dict of arrays and attributes, as :mod:`.curvefile` does for curves."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import h5py
import numpy as np

from .base import atomic_h5, check_kind

#: Version of the layout written by :func:`write_branch`.
BRANCH_SCHEMA = 2

#: Older schemas this version still reads (see :func:`read_branch`).
READABLE_BRANCH_SCHEMAS = (1, 2)

#: Root attributes of a branch file (besides ``kind`` and ``schema_version``).
BRANCH_ATTRS = ("param", "period", "status", "system")


def write_branch(path: str | Path, data: dict[str, Any]) -> Path:
    """Write a branch atomically (a ``.partial`` file renamed at the end).

    ``data``: the attributes of BRANCH_ATTRS (``system`` a JSON string); ``values`` (k,),
    ``points`` (k, n_state), ``T`` (k,), ``multipliers`` (k, m) complex, ``stable`` (k,);
    ``bifurcation_kind`` (list of str), ``bifurcation_value``, ``bifurcation_index`` and
    ``bifurcation_point`` (b, n_state); ``stick_count`` and ``stick_time`` (k,) or None;
    ``segments``: per point None or (mesh (s + 1,), starts (s, n_state)), or None.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    points = np.asarray(data["points"])
    with atomic_h5(path) as h5:
        h5.attrs["kind"] = "branch"
        h5.attrs["schema_version"] = BRANCH_SCHEMA
        h5.attrs["param"] = data["param"]
        h5.attrs["period"] = int(data["period"])
        h5.attrs["status"] = data["status"]
        h5.attrs["system"] = data["system"]
        h5["values"] = data["values"]
        h5["points"] = points
        h5["T"] = data["T"]
        h5["multipliers_real"] = np.asarray(data["multipliers"]).real
        h5["multipliers_imag"] = np.asarray(data["multipliers"]).imag
        h5["stable"] = np.asarray(data["stable"]).astype("i1")
        kinds = list(data["bifurcation_kind"])
        h5["bifurcation_kind"] = np.array(kinds, dtype=h5py.string_dtype())
        h5["bifurcation_value"] = np.array(data["bifurcation_value"], "f8")
        h5["bifurcation_index"] = np.array(data["bifurcation_index"], "i8")
        h5["bifurcation_point"] = np.array(data["bifurcation_point"], "f8").reshape(
            len(kinds), points.shape[1]
        )
        if data.get("stick_count") is not None:
            h5["stick_count"] = np.asarray(data["stick_count"], "i8")
            h5["stick_time"] = np.asarray(data["stick_time"], "f8")
        segments = data.get("segments")
        if segments is not None and any(x is not None for x in segments):
            _write_segments(h5, segments, points.shape[1])
    return path


def read_branch(path: str | Path) -> dict[str, Any]:
    """The dict :func:`write_branch` wrote.

    Schema 1 files (before 2026-11-23) stored no bifurcation points: their
    ``bifurcation_point`` rows are the branch points just before the events.

    Raises
    ------
    ValueError
        If the file is not a branch file of a known schema (naming what is wrong).
    """
    with h5py.File(path, "r") as h5:
        check_kind(path, h5, "branch", READABLE_BRANCH_SCHEMAS)
        out: dict[str, Any] = {name: h5.attrs[name] for name in BRANCH_ATTRS}
        out["bifurcation_kind"] = [k.decode() if isinstance(k, bytes) else str(k)
                                   for k in h5["bifurcation_kind"][()]]  # fmt: skip
        for name in ("values", "points", "T", "bifurcation_value", "bifurcation_index"):
            out[name] = h5[name][()]
        out["multipliers"] = h5["multipliers_real"][()] + 1j * h5["multipliers_imag"][()]
        out["stable"] = h5["stable"][()].astype(bool)
        if "bifurcation_point" in h5:
            out["bifurcation_point"] = h5["bifurcation_point"][()]
        else:  # schema 1: the branch point before the event
            last = len(out["points"]) - 1
            out["bifurcation_point"] = [out["points"][min(int(i), last)]
                                        for i in out["bifurcation_index"]]  # fmt: skip
        for name in ("stick_count", "stick_time"):
            out[name] = h5[name][()] if name in h5 else None
        out["segments"] = _read_segments(h5) if "segment_offsets" in h5 else None
    return out


def _write_segments(h5: h5py.File, segments: list, n_state: int) -> None:
    """Every point's (mesh, starts) as three flat datasets: point i's segments are rows
    ``segment_offsets[i]:segment_offsets[i + 1]`` (none: no segments) of
    ``segment_mesh`` (each segment's start as a fraction of T; the last ends at 1) and
    ``segment_starts``."""
    counts = [0 if x is None else len(x[0]) - 1 for x in segments]
    h5["segment_offsets"] = np.r_[0, np.cumsum(counts)].astype("i8")
    h5["segment_mesh"] = np.concatenate([x[0][:-1] for x in segments if x is not None])
    starts = [np.asarray(x[1], "f8") for x in segments if x is not None]
    h5["segment_starts"] = np.concatenate(starts).reshape(-1, n_state)


def _read_segments(h5: h5py.File) -> list:
    """The ``segments`` list of :func:`_write_segments`' datasets."""
    off = h5["segment_offsets"][()]
    mesh, starts = h5["segment_mesh"][()], h5["segment_starts"][()]
    return [
        None if b == a else (np.r_[mesh[a:b], 1.0], starts[a:b].copy())
        for a, b in zip(off[:-1], off[1:])
    ]
