"""The sweep schema: per-value datasets (one description), descriptions, the in-memory store."""

from __future__ import annotations

import datetime as _dt
from dataclasses import dataclass
from typing import Any

import h5py
import numpy as np

from ..base.status import LABEL_RULES

SCHEMA_VERSION = 1


def write_root_attrs(attrs, text, digest, title, notes, package_version, kind=None) -> None:
    """The root attributes every result file opens with (``kind``: census and trajectory files)."""
    attrs["schema_version"] = SCHEMA_VERSION
    attrs["package_version"] = package_version
    attrs["label_rules"] = LABEL_RULES
    if kind is not None:
        attrs["kind"] = kind
    attrs["config"] = text
    attrs["config_sha256"] = digest
    attrs["created"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    attrs["title"] = title
    attrs["notes"] = notes
    attrs["Conventions"] = "CF-1.8"


def add_point_and_state_scales(h5, max_points: int, state_names, scales: dict) -> None:
    """The ``point`` and ``state`` coordinates (dimension scales) of sweep and census files."""
    d = h5.create_dataset("point", data=np.arange(max_points, dtype="i4"))
    d.make_scale("point")
    d.attrs["long_name"] = "index of the Poincare point, in time order"
    scales["point"] = d
    d = h5.create_dataset("state", data=np.array(state_names, dtype=object),
                          dtype=h5py.string_dtype())  # fmt: skip
    d.make_scale("state")
    d.attrs["long_name"] = "state variable"
    scales["state"] = d


def create_run_datasets(
    h5,
    specs: dict,
    chunks_of,
    descriptions: dict,
    scales: dict,
    status_names,
    fletcher32: bool = False,
) -> None:
    """Create the per-run datasets of a sweep or census file, and the ``status`` flag attributes.

    ``specs`` maps a name to ``(shape, dtype, dims, fill)``; ``chunks_of(name, shape)`` gives
    its chunk shape (None: contiguous, uncompressed). Chunked datasets are gzip-1 with the
    shuffle filter (and Fletcher-32 checksums where ``fletcher32``).
    """
    for name, (shape, dtype, dims, fill) in specs.items():
        chunks = chunks_of(name, shape)
        d = h5.create_dataset(
            name, shape=shape, dtype=dtype, fillvalue=fill, chunks=chunks,
            compression="gzip" if chunks else None,
            compression_opts=1 if chunks else None, shuffle=bool(chunks),
            fletcher32=bool(chunks) and fletcher32,
        )  # fmt: skip
        for i, dim in enumerate(dims):
            d.dims[i].attach_scale(scales[dim])
        d.attrs["description"] = descriptions[name]
    st = h5["status"]
    st.attrs["flag_values"] = np.arange(len(status_names), dtype="i1")
    st.attrs["flag_meanings"] = " ".join(status_names)
    st.attrs["missing_value"] = np.int8(-1)


#: Per-value integer datasets and their dtypes.
PER_VALUE_FIELDS = {
    "count": "i4",
    "period": "i4",
    "status": "i1",
    "n_steps": "i8",
    "n_rejected": "i8",
    "n_crossings": "i8",
}


#: Optional per-value analyses a sweep can store, and the float datasets each adds.
ANALYSES: dict[str, tuple[str, ...]] = {
    "sync": ("sync_error",),
    "lyapunov": ("lyapunov", "lyapunov_fit"),
}


#: Every optional analysis dataset (all float64, NaN where not computed).
ANALYSIS_FIELDS: tuple[str, ...] = tuple(f for fields in ANALYSES.values() for f in fields)


_DESCRIPTIONS = {
    "sync_error": "Mean distance between disk i's and disk 1's (x, dx, phi, dphi) at the "
    "Poincare points (analysis.sync_error); 0 for N = 1, NaN without points",
    "lyapunov": "Largest Lyapunov exponent, plain Benettin average over [t_transient, t_end] "
    "(analysis.largest_lyapunov)",
    "t_converged": "Converged stopping: time at which the run was found converged (its "
    "points repeat, or it has been at rest for the dwell time); NaN if it reached t_end first",
    "lyapunov_fit": "Largest Lyapunov exponent, least-squares slope of the cumulative log "
    "growth (analysis.largest_lyapunov exponent_fit)",
    "points": "Full state at each local minimum of x1 (upward zero crossing of dx1), "
    "in time order, NaN-padded; the most recent max_points after t_transient",
    "t_points": "Times of the Poincare points",
    "count": "Number of stored Poincare points",
    "period": (
        "Smallest p <= 64 with which the stored points repeat (0: none detected, or an "
        "oscillation dying out)"
    ),
    "status": "Outcome of the trajectory (see flag_meanings)",
    "n_steps": "Accepted integration steps",
    "n_rejected": "Rejected integration steps",
    "n_crossings": "All Poincare crossings after t_transient (may exceed max_points)",
    "final_state": "State at t_end (start of the next value in continuation modes)",
    "done": "1 when this value has been computed and written",
}


@dataclass
class SweepLayout:
    """Shape information a writer needs."""

    param_names: tuple[str, ...]
    axes: tuple[np.ndarray, ...]
    branches: bool
    max_points: int
    state_names: list[str]
    analyses: tuple[str, ...] = ()
    #: converged stopping: the file has a ``t_converged`` dataset
    converged: bool = False

    @property
    def analysis_fields(self) -> tuple[str, ...]:
        """The optional float datasets of this file (analyses, ``t_converged``)."""
        fields = tuple(f for a in self.analyses for f in ANALYSES[a])
        return fields + (("t_converged",) if self.converged else ())

    @property
    def grid_shape(self) -> tuple[int, ...]:
        return ((2,) if self.branches else ()) + tuple(len(a) for a in self.axes)

    @property
    def grid_dims(self) -> tuple[str, ...]:
        return (("branch",) if self.branches else ()) + self.param_names

    @property
    def result_fields(self) -> tuple[str, ...]:
        """The per-value datasets a computed block holds (all but ``done``)."""
        return ("points", "t_points", "final_state", *PER_VALUE_FIELDS, *self.analysis_fields)

    def dataset_specs(self) -> dict[str, tuple[tuple[int, ...], str, tuple[str, ...], Any]]:
        """Every per-value dataset: name -> (shape, dtype, dimension names, fill value).

        The one description of the result arrays, used by the HDF5 file and by
        the in-memory :class:`MemoryStore` alike.
        """
        grid = self.grid_shape
        gdims = self.grid_dims
        n_state = len(self.state_names)
        kp = self.max_points
        specs = {
            "points": (grid + (kp, n_state), "f8", gdims + ("point", "state"), np.nan),
            "t_points": (grid + (kp,), "f8", gdims + ("point",), np.nan),
            "final_state": (grid + (n_state,), "f8", gdims + ("state",), np.nan),
            "done": (grid, "u1", gdims, 0),
        }
        for name, dtype in PER_VALUE_FIELDS.items():
            specs[name] = (grid, dtype, gdims, -1 if name == "status" else 0)
        for name in self.analysis_fields:
            specs[name] = (grid, "f8", gdims, np.nan)
        return specs


class MemoryStore:
    """The in-memory twin of :class:`SweepFile`: the same arrays and methods, no file.

    Used by :func:`~stickslip_fast.sweep` when it is given no output path;
    :attr:`data` holds every dataset of :meth:`SweepLayout.dataset_specs`.
    """

    def __init__(self, layout: SweepLayout):
        self.layout = layout
        self.data = {
            name: np.full(shape, fill, dtype=dtype)
            for name, (shape, dtype, _, fill) in layout.dataset_specs().items()
        }

    def done_mask(self) -> np.ndarray:
        return self.data["done"].astype(bool)

    def final_state_at(self, index: tuple) -> np.ndarray:
        return self.data["final_state"][index]

    def write(self, index: tuple, data: dict[str, np.ndarray]) -> None:
        """Store one block of values at grid ``index``, as :meth:`SweepFile.write`."""
        for name in self.layout.result_fields:
            self.data[name][index] = data[name]
        self.data["done"][index] = 1

    def close(self) -> None:
        pass

    def __enter__(self) -> MemoryStore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
