"""The HDF5 file of a two-parameter curve (``Curve.to_hdf5``; schema: docs/file-format.md).

The layer below :mod:`stickslip_fast.bifurcation` knows nothing of the ``Curve`` record:
it writes and reads a dict of arrays and attributes."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import h5py
import numpy as np

from .base import atomic_h5, check_kind

#: Version of the layout written by :func:`write_curve`.
CURVE_SCHEMA = 1

#: Datasets of a curve file (all per curve point, except the codim2_* ones).
CURVE_DATASETS = ("values", "points", "T", "multipliers_real", "multipliers_imag")
CURVE_ATTRS = ("param", "param2", "curve_kind", "period", "status", "system")

#: Datasets present only on some kinds of curve (absent, or None in the dict, elsewhere):
#: "theta" (k,) of a Neimark-Sacker curve, "event_time" (k,) of a stick-phase curve.
CURVE_OPTIONAL = ("theta", "event_time")

#: Attributes present only on some kinds of curve: "event" (a JSON string) of a
#: stick-phase curve.
CURVE_OPTIONAL_ATTRS = ("event",)


def write_curve(path: str | Path, data: dict[str, Any]) -> Path:
    """Write ``data`` (the arrays of CURVE_DATASETS, ``codim2_kind`` (list of str),
    ``codim2_values`` (k, 2), ``codim2_index`` (k,), ``codim2_point`` (k, n_state), and the
    attributes of CURVE_ATTRS; those of CURVE_OPTIONAL where not None) atomically (a ``.partial`` file renamed at the end)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_h5(path) as h5:
        h5.attrs["kind"] = "curve"
        h5.attrs["schema_version"] = CURVE_SCHEMA
        for name in CURVE_ATTRS:
            h5.attrs[name] = data[name]
        for name in CURVE_DATASETS:
            h5[name] = np.asarray(data[name], dtype="f8")
        h5["codim2_kind"] = np.array(list(data["codim2_kind"]), dtype=h5py.string_dtype())
        h5["codim2_values"] = np.asarray(data["codim2_values"], "f8").reshape(-1, 2)
        h5["codim2_index"] = np.asarray(data["codim2_index"], "i8")
        n = np.asarray(data["points"]).shape[1]
        h5["codim2_point"] = np.asarray(data["codim2_point"], "f8").reshape(-1, n)
        for name in CURVE_OPTIONAL:
            if data.get(name) is not None:
                h5[name] = np.asarray(data[name], dtype="f8")
        for name in CURVE_OPTIONAL_ATTRS:
            if data.get(name) is not None:
                h5.attrs[name] = data[name]
    return path


def read_curve(path: str | Path) -> dict[str, Any]:
    """The dict :func:`write_curve` wrote.

    Raises
    ------
    ValueError
        If the file is not a curve file of a known schema (naming what is wrong).
    """
    with h5py.File(path, "r") as h5:
        check_kind(path, h5, "curve", (CURVE_SCHEMA,))
        out: dict[str, Any] = {name: h5.attrs[name] for name in CURVE_ATTRS}
        out.update({name: h5[name][()] for name in CURVE_DATASETS})
        out["codim2_kind"] = [k.decode() if isinstance(k, bytes) else str(k)
                              for k in h5["codim2_kind"][()]]  # fmt: skip
        for name in ("codim2_values", "codim2_index", "codim2_point"):
            out[name] = h5[name][()]
        for name in CURVE_OPTIONAL:
            out[name] = h5[name][()] if name in h5 else None
        for name in CURVE_OPTIONAL_ATTRS:
            out[name] = h5.attrs[name] if name in h5.attrs else None
    return out
