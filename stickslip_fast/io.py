"""The HDF5 result file: schema, writer and reader (the one place that knows the layout).

A sweep file is a plain HDF5 file that also reads as a netCDF-4 style labelled
dataset (``xarray.open_dataset(path, engine="h5netcdf")``). Layout (schema 1),
for a sweep of parameter(s) ``P1[, P2]`` with ``n1[, n2]`` values::

    /P1            (n1,)   coordinate: values of the first parameter
    /P2            (n2,)   coordinate (2-D sweeps only)
    /branch        (2,)    "up", "down" (mode "continuation-both" only)
    /point         (K,)    0..K-1, K = max_points
    /state         (S,)    state names: x1, dx1, phi1, dphi1, ..., [vb]
    /points        (grid..., point, state)  Poincare points, time order, NaN-padded
    /t_points      (grid..., point)         their times
    /count         (grid...)   number of stored points
    /period        (grid...)   detected period (0: none)
    /status        (grid...)   int8 code; attrs flag_values / flag_meanings
    /n_steps, /n_rejected, /n_crossings (grid...)
    /final_state   (grid..., state)
    /done          (grid...)   1 once the value is written (for resume)

Optional analysis datasets (only when the sweep was asked for them with
``sweep(..., analyses=...)``; the list is part of the configuration and its hash)::

    /sync_error    (grid...)   f8  analyses=("sync",): mean distance between disk i's
                               and disk 1's (x, dx, phi, dphi) over the stored
                               Poincare points (analysis.sync_error; 0 for N = 1,
                               NaN where there are no points)
    /lyapunov      (grid...)   f8  analyses=("lyapunov",): largest Lyapunov exponent,
                               plain Benettin average (analysis.largest_lyapunov
                               with the sweep's t_end, t_transient, rtol, atol and
                               the value's own initial state)
    /lyapunov_fit  (grid...)   f8  the same run's least-squares slope estimate

``grid`` is ``[branch,] P1[, P2]``. Root attributes: ``schema_version``,
``package_version``, ``config`` (JSON of everything that determines the
results), ``config_sha256``, ``created``, ``title``, ``notes`` and a flat copy of
the main settings for quick inspection. The full description for collaborators
is docs/file-format.md.

Trajectory file (schema 1, root attribute ``kind = "trajectory"``), one run of
:func:`stickslip_fast.simulate`, written by :func:`write_trajectory`::

    /t             (t,)              coordinate: sample times (empty without sample_dt)
    /state         (state,)          state names x1, dx1, phi1, dphi1, ..., [vb]
    /y             (t, state)        samples on the uniform grid t_transient + k sample_dt
    /crossing      (crossing,)       0..k-1
    /t_poincare    (crossing,)       times of the Poincare points (local minima of x1)
    /poincare      (crossing, state) full state at those times
    /final_state   (state,)          state at t_end

Root attributes: ``schema_version``, ``package_version``, ``kind``, ``config``
(JSON: system, settings, y0, sample_dt and the TOML mapping it came from),
``config_sha256``, ``created``, ``title``, ``notes``, ``status``, ``period``,
``n_steps``, ``n_rejected``, ``n_crossings``, ``t_final``, ``amplitude``,
``method``. Like a sweep file it opens with
``xarray.open_dataset(path, engine="h5netcdf")``.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from .poincare import STATUS_NAMES

__all__ = [
    "SCHEMA_VERSION",
    "ConfigMismatchError",
    "SweepFile",
    "SweepLayout",
    "MemoryStore",
    "read_dataset",
    "sweep_summary",
    "config_digest",
    "read_sweep",
    "PER_VALUE_FIELDS",
    "ANALYSES",
    "ANALYSIS_FIELDS",
    "write_trajectory",
    "read_trajectory",
    "CensusLayout",
    "CensusFile",
    "read_census",
    "write_census_classification",
]

SCHEMA_VERSION = 1

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
    "period": "Smallest p <= 64 with which the stored points repeat (0: none detected)",
    "status": "Outcome of the trajectory (see flag_meanings)",
    "n_steps": "Accepted integration steps",
    "n_rejected": "Rejected integration steps",
    "n_crossings": "All Poincare crossings after t_transient (may exceed max_points)",
    "final_state": "State at t_end (start of the next value in continuation modes)",
    "done": "1 when this value has been computed and written",
}


class ConfigMismatchError(ValueError):
    """An existing result file was made by a different configuration."""


def _canonical(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _canonical(obj[k]) for k in sorted(obj)}
    if isinstance(obj, (list, tuple)):
        return [_canonical(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return [_canonical(v) for v in obj.tolist()]
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    return obj


def config_digest(config: dict) -> tuple[str, str]:
    """Canonical JSON text of a configuration and its SHA-256."""
    text = json.dumps(_canonical(config), sort_keys=True, separators=(",", ":"))
    return text, hashlib.sha256(text.encode()).hexdigest()


def _diff_keys(a: dict, b: dict, prefix: str = "") -> list[str]:
    keys = []
    for k in sorted(set(a) | set(b)):
        va, vb = a.get(k), b.get(k)
        if isinstance(va, dict) and isinstance(vb, dict):
            keys += _diff_keys(va, vb, f"{prefix}{k}.")
        elif va != vb:
            keys.append(f"{prefix}{k}")
    return keys


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


class SweepFile:
    """Create, check and append to a sweep result file.

    ``SweepFile.open(path, config, layout)`` creates the file, or reopens an
    existing one after checking that it was made by the same configuration
    (raising :class:`ConfigMismatchError` otherwise). Chunks are written with
    :meth:`write` and flushed at once; the file stays readable (SWMR) while a
    sweep appends to it, and a killed sweep loses only the chunks in flight.
    """

    def __init__(self, h5: h5py.File, layout: SweepLayout, lock: _WriterLock | None = None):
        self.h5 = h5
        self.layout = layout
        self._lock = lock

    # --------------------------------------------------------------- creation
    @classmethod
    def open(
        cls,
        path: str | Path,
        config: dict,
        layout: SweepLayout,
        *,
        title: str = "",
        notes: str = "",
        package_version: str = "",
    ) -> SweepFile:
        path = Path(path)
        text, digest = config_digest(config)
        path.parent.mkdir(parents=True, exist_ok=True)
        lock = _WriterLock(path)
        try:
            if path.exists():
                h5 = cls._reopen(path, text, digest)
            else:
                tmp = path.with_name(path.name + ".partial")
                h5 = h5py.File(tmp, "w", libver="latest")
                try:
                    cls._create_layout(
                        h5, layout, text, digest, config, title, notes, package_version
                    )
                    h5.close()
                    tmp.replace(path)  # the file appears only once its layout is complete
                except BaseException:
                    h5.close()
                    tmp.unlink(missing_ok=True)
                    raise
                h5 = h5py.File(path, "r+", libver="latest")
            h5.swmr_mode = True
        except BaseException:
            lock.release()
            raise
        return cls(h5, layout, lock)

    @classmethod
    def _reopen(cls, path: Path, text: str, digest: str) -> h5py.File:
        """Open an existing file for appending after checking its configuration."""
        try:
            h5 = h5py.File(path, "r", libver="latest", swmr=True)
        except OSError as exc:
            raise ConfigMismatchError(
                f"{path} exists but is not a readable HDF5 file ({exc}); "
                "remove it or choose another output path"
            ) from None
        with h5:
            found = h5.attrs.get("config_sha256")
            old = h5.attrs.get("config")
            schema = h5.attrs.get("schema_version")
        if found != digest:
            detail = ""
            if old is not None:
                try:
                    changed = _diff_keys(json.loads(old), json.loads(text))
                    detail = f" (differs in: {', '.join(changed) or 'unknown'})"
                except json.JSONDecodeError:
                    pass
            raise ConfigMismatchError(
                f"{path} was written by a different configuration{detail}; refusing to "
                "overwrite it. Use another output path, or delete the file to start over."
            )
        if schema != SCHEMA_VERSION:
            raise ConfigMismatchError(f"{path} has an unsupported schema version {schema!r}")
        try:
            return h5py.File(path, "r+", libver="latest")
        except OSError as exc:
            if "already open for write" not in str(exc):
                raise
        # A writer was killed (we hold the writer lock, so none is alive): HDF5 left
        # the file marked open. Rebuild it from what was flushed, then append.
        _rebuild(path)
        return h5py.File(path, "r+", libver="latest")

    @staticmethod
    def _create_layout(h5, layout, text, digest, config, title, notes, package_version):
        h5.attrs["schema_version"] = SCHEMA_VERSION
        h5.attrs["package_version"] = package_version
        h5.attrs["config"] = text
        h5.attrs["config_sha256"] = digest
        h5.attrs["created"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
        h5.attrs["title"] = title
        h5.attrs["notes"] = notes
        h5.attrs["Conventions"] = "CF-1.8"
        for key in ("mode", "method", "rtol", "atol", "h", "t_end", "t_transient", "max_points"):
            value = config.get("settings", {}).get(key, config.get(key))
            if value is not None:
                h5.attrs[key] = value
        h5.attrs["param"] = ",".join(layout.param_names)
        for key, value in config["system"].items():
            if value is not None:
                h5.attrs[f"system.{key}"] = value

        scales = {}
        if layout.branches:
            d = h5.create_dataset("branch", data=np.array(["up", "down"], dtype=object),
                                  dtype=h5py.string_dtype())  # fmt: skip
            d.make_scale("branch")
            d.attrs["long_name"] = "continuation direction (up: increasing values)"
            scales["branch"] = d
        for name, axis in zip(layout.param_names, layout.axes):
            d = h5.create_dataset(name, data=np.asarray(axis, dtype="f8"))
            d.make_scale(name)
            d.attrs["long_name"] = f"swept parameter {name} (nondimensional)"
            scales[name] = d
        d = h5.create_dataset("point", data=np.arange(layout.max_points, dtype="i4"))
        d.make_scale("point")
        d.attrs["long_name"] = "index of the Poincare point, in time order"
        scales["point"] = d
        d = h5.create_dataset("state", data=np.array(layout.state_names, dtype=object),
                              dtype=h5py.string_dtype())  # fmt: skip
        d.make_scale("state")
        d.attrs["long_name"] = "state variable"
        scales["state"] = d

        grid = layout.grid_shape
        kp = layout.max_points
        # chunk along the value axes so appending a sweep chunk touches few HDF5 chunks
        vchunk = tuple(min(s, 64) for s in grid)
        for name, (shape, dtype, dims, fill) in layout.dataset_specs().items():
            chunks = vchunk + tuple(min(s, 256) for s in shape[len(grid) :])
            if kp == 0 and name in ("points", "t_points"):
                chunks = None
            d = h5.create_dataset(
                name, shape=shape, dtype=dtype, fillvalue=fill, chunks=chunks,
                compression="gzip" if chunks else None,
                compression_opts=1 if chunks else None, shuffle=bool(chunks),
            )  # fmt: skip
            for i, dim in enumerate(dims):
                d.dims[i].attach_scale(scales[dim])
            d.attrs["description"] = _DESCRIPTIONS[name]
        st = h5["status"]
        st.attrs["flag_values"] = np.arange(len(STATUS_NAMES), dtype="i1")
        st.attrs["flag_meanings"] = " ".join(STATUS_NAMES)
        st.attrs["missing_value"] = np.int8(-1)

    # ----------------------------------------------------------------- access
    def done_mask(self) -> np.ndarray:
        return self.h5["done"][...].astype(bool)

    def final_state_at(self, index: tuple) -> np.ndarray:
        return self.h5["final_state"][index]

    def write(self, index: tuple, data: dict[str, np.ndarray]) -> None:
        """Write one block of values at grid ``index`` (ints and slices) and flush.

        ``data`` holds points, t_points, final_state and the PER_VALUE_FIELDS,
        each with the block's value axes first. ``done`` is set last.
        """
        for name in self.layout.result_fields:
            self.h5[name][index] = data[name]
        self.h5.flush()
        self.h5["done"][index] = 1
        self.h5.flush()

    def close(self) -> None:
        if self.h5.id.valid:
            self.h5.close()
        if self._lock is not None:
            self._lock.release()
            self._lock = None

    def __enter__(self) -> SweepFile:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class _WriterLock:
    """An exclusive OS lock on ``<file>.lock`` held while a sweep writes the file.

    The OS drops it when the process dies, which tells a crashed writer (resume
    is safe) from a live one (refuse). No-op where fcntl is unavailable.
    """

    def __init__(self, path: Path):
        self.path = path.with_name(path.name + ".lock")
        self.fd: int | None = None
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX
            return
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise ConfigMismatchError(
                f"another process is writing {path} (lock {self.path} is held); "
                "wait for it to finish or choose another output path"
            ) from None
        self.fd = fd

    def release(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None
            self.path.unlink(missing_ok=True)


def _copy_attrs(src, dst) -> None:
    for key, value in src.attrs.items():
        if key not in ("DIMENSION_LIST", "REFERENCE_LIST", "CLASS", "NAME"):
            dst.attrs[key] = value


def _rebuild(path: Path, slab: int = 4096) -> None:
    """Copy a crashed writer's file into a fresh one (same layout, flushed data only)."""
    tmp = path.with_name(path.name + ".recovering")
    with (
        h5py.File(path, "r", libver="latest", swmr=True) as src,
        h5py.File(tmp, "w", libver="latest") as dst,
    ):
        _copy_attrs(src, dst)
        for name, ds in src.items():
            if "CLASS" in ds.attrs and ds.attrs["CLASS"] == b"DIMENSION_SCALE":
                new = dst.create_dataset(name, data=ds[...], dtype=ds.dtype)
                new.make_scale(name)
                _copy_attrs(ds, new)
        for name, ds in src.items():
            if name in dst:
                continue
            new = dst.create_dataset(
                name, shape=ds.shape, dtype=ds.dtype, chunks=ds.chunks, fillvalue=ds.fillvalue,
                compression=ds.compression, compression_opts=ds.compression_opts,
                shuffle=ds.shuffle,
            )  # fmt: skip
            for i, dim in enumerate(ds.dims):
                for scale_name in dim.keys():
                    new.dims[i].attach_scale(dst[scale_name.lstrip("/")])
            _copy_attrs(ds, new)
            if ds.ndim == 0:
                new[()] = ds[()]
                continue
            for a in range(0, ds.shape[0], slab):
                new[a : a + slab] = ds[a : a + slab]
    tmp.replace(path)


def _open_read(path: str | Path) -> h5py.File:
    """Open a result file for reading (also while a sweep is appending to it)."""
    return h5py.File(path, "r", libver="latest", swmr=True)


def read_dataset(path: str | Path, name: str) -> np.ndarray:
    """One whole dataset of a result file (KeyError naming the file if it has none)."""
    with _open_read(path) as h5:
        if name not in h5:
            raise KeyError(f"{path} has no {name!r} dataset")
        return h5[name][...]


def sweep_summary(path: str | Path) -> dict[str, Any]:
    """What ``stickslip-fast info`` shows of a sweep file, read in one go.

    Returns
    -------
    dict
        ``config`` (parsed), ``attrs`` (the root attributes ``title``,
        ``package_version``, ``schema_version``, ``created`` where present),
        ``axes`` (name -> values), ``done`` (bool), ``status`` and ``period``.
    """
    with _open_read(path) as h5:
        config = json.loads(h5.attrs["config"])
        keys = ("title", "package_version", "schema_version", "created")
        return {
            "config": config,
            "attrs": {k: h5.attrs[k] for k in keys if k in h5.attrs},
            "axes": {name: h5[name][...] for name in config["param"]},
            "done": h5["done"][...].astype(bool),
            "status": h5["status"][...],
            "period": h5["period"][...],
        }


def read_sweep(path: str | Path) -> dict[str, Any]:
    """Read a whole sweep file into memory: arrays, coordinates and configuration."""
    out: dict[str, Any] = {}
    with _open_read(path) as h5:
        if h5.attrs.get("schema_version") != SCHEMA_VERSION:
            raise ValueError(f"{path}: not a stickslip_fast sweep file (schema_version missing)")
        out["config"] = json.loads(h5.attrs["config"])
        out["attrs"] = {k: (v.item() if hasattr(v, "item") else v) for k, v in h5.attrs.items()}
        params = tuple(str(h5.attrs["param"]).split(","))
        out["param"] = params
        out["axes"] = tuple(h5[p][...] for p in params)
        out["branches"] = "branch" in h5
        out["state_names"] = [s.decode() if isinstance(s, bytes) else s for s in h5["state"][...]]
        for name in ("points", "t_points", "final_state", "done", *PER_VALUE_FIELDS):
            out[name] = h5[name][...]
        out["analyses"] = {
            name: h5[name][...] for name in (*ANALYSIS_FIELDS, "t_converged") if name in h5
        }
    return out


# ------------------------------------------------------------- single runs
def _jsonable(obj: Any) -> Any:
    """Plain JSON-compatible values (arrays to lists, Paths to str)."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    return obj


def write_trajectory(path: str | Path, result: Any, config: Any = None) -> Path:
    """Store one :class:`~stickslip_fast.SimulationResult` in an HDF5 file.

    The layout is the trajectory schema in this module's docstring. The file is
    written to ``<path>.partial`` and renamed, so it appears only when complete;
    an existing file is replaced.

    Parameters
    ----------
    path : str or Path
        Output file (``.h5``).
    result : SimulationResult
        What :func:`~stickslip_fast.simulate` returned (with ``sample_dt`` for
        the time grid ``t``, ``y``; without it they are stored empty).
    config : RunConfig or dict, optional
        The run's configuration: a :class:`~stickslip_fast.config.RunConfig`
        (its TOML mapping, title, notes, y0 and sample_dt are stored) or any
        JSON-serialisable mapping (stored under ``"user"``).

    Returns
    -------
    Path
        The written file.
    """
    from . import __version__

    path = Path(path)
    system = result.system
    cfg: dict[str, Any] = {
        "system": system.to_dict(),
        "settings": result.settings.to_dict(),
        "method": result.method,
    }
    title = notes = ""
    if config is not None and hasattr(config, "raw") and hasattr(config, "system"):
        cfg["source"] = config.raw
        cfg["y0"] = None if config.y0 is None else np.asarray(config.y0).tolist()
        cfg["sample_dt"] = config.sample_dt
        title, notes = config.title, config.notes
    elif isinstance(config, dict):
        cfg["user"] = config
        title = str(config.get("title", ""))
        notes = str(config.get("notes", ""))
    elif config is not None:
        raise TypeError(f"config must be a RunConfig or a dict, got {type(config).__name__}")
    if result.t is not None and len(result.t) > 1:
        cfg.setdefault("sample_dt", float(result.t[1] - result.t[0]))
    text, digest = config_digest(_jsonable(cfg))
    n_state = len(result.state_names)
    t = np.zeros(0) if result.t is None else np.asarray(result.t, dtype="f8")
    y = np.zeros((0, n_state)) if result.y is None else np.asarray(result.y, dtype="f8")
    tp = np.asarray(result.t_poincare, dtype="f8")
    pts = np.asarray(result.poincare, dtype="f8").reshape(len(tp), n_state)

    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".partial")
    try:
        with h5py.File(tmp, "w", libver="latest") as h5:
            a = h5.attrs
            a["schema_version"] = SCHEMA_VERSION
            a["package_version"] = __version__
            a["kind"] = "trajectory"
            a["config"] = text
            a["config_sha256"] = digest
            a["created"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
            a["title"] = title
            a["notes"] = notes
            a["Conventions"] = "CF-1.8"
            a["status"] = result.status
            a["period"] = int(result.period)
            a["method"] = result.method
            for key in ("n_steps", "n_rejected", "n_crossings"):
                a[key] = int(getattr(result, key))
            a["t_final"] = float(result.t_final)
            a["amplitude"] = float(result.amplitude)
            for key, value in system.to_dict().items():
                a[f"system.{key}"] = value

            def scale(name: str, data: np.ndarray, long_name: str, **kw: Any) -> h5py.Dataset:
                d = h5.create_dataset(name, data=data, **kw)
                d.make_scale(name)
                d.attrs["long_name"] = long_name
                return d

            st = scale("state", np.array(result.state_names, dtype=object), "state variable",
                       dtype=h5py.string_dtype())  # fmt: skip
            ts = scale("t", t, "time (nondimensional)", maxshape=(None,))
            cs = scale("crossing", np.arange(len(tp), dtype="i4"),
                       "index of the Poincare point, in time order", maxshape=(None,))  # fmt: skip
            specs = {
                "y": (y, (ts, st), "State sampled every sample_dt from t_transient"),
                "t_poincare": (tp, (cs,), "Times of the Poincare points (local minima of x1)"),
                "poincare": (pts, (cs, st), "Full state at each Poincare point"),
                "final_state": (np.asarray(result.final_state, dtype="f8"), (st,),
                                "State at t_end"),
            }  # fmt: skip
            for name, (data, dims, desc) in specs.items():
                d = h5.create_dataset(
                    name, data=data, maxshape=(None,) * data.ndim,
                    compression="gzip" if data.size else None,
                    compression_opts=1 if data.size else None,
                )  # fmt: skip
                for i, sc in enumerate(dims):
                    d.dims[i].attach_scale(sc)
                d.attrs["description"] = desc
        tmp.replace(path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def read_trajectory(path: str | Path) -> dict[str, Any]:
    """Read a file written by :func:`write_trajectory`.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    dict
        ``t``, ``y``, ``t_poincare``, ``poincare``, ``final_state`` (arrays),
        ``state_names``, ``status``, ``period``, ``title``, ``notes``,
        ``config`` (the stored JSON, parsed), ``attrs`` (all root attributes),
        ``system`` (a :class:`~stickslip_fast.System`) and ``result`` (a
        :class:`~stickslip_fast.SimulationResult` rebuilt from the file).

    Raises
    ------
    ValueError
        If the file is not a trajectory file of this schema.
    """
    from .settings import Settings
    from .simulate import SimulationResult
    from .system import System

    with h5py.File(path, "r") as h5:
        if h5.attrs.get("schema_version") != SCHEMA_VERSION or h5.attrs.get("kind") != "trajectory":
            raise ValueError(f"{path}: not a stickslip_fast trajectory file")
        attrs = {k: (v.item() if hasattr(v, "item") else v) for k, v in h5.attrs.items()}
        data = {name: h5[name][...] for name in ("t", "y", "t_poincare", "poincare", "final_state")}
        names = [s.decode() if isinstance(s, bytes) else str(s) for s in h5["state"][...]]
    config = json.loads(attrs["config"])
    system = System.from_dict(config["system"])
    result = SimulationResult(
        system=system,
        method=str(attrs["method"]),
        state_names=names,
        t_poincare=data["t_poincare"],
        poincare=data["poincare"],
        n_crossings=int(attrs["n_crossings"]),
        period=int(attrs["period"]),
        status=str(attrs["status"]),
        n_steps=int(attrs["n_steps"]),
        n_rejected=int(attrs["n_rejected"]),
        t_final=float(attrs["t_final"]),
        final_state=data["final_state"],
        amplitude=float(attrs["amplitude"]),
        t=data["t"],
        y=data["y"],
        settings=Settings.from_dict(config["settings"]),
    )
    return {
        **data,
        "state_names": names,
        "status": result.status,
        "period": result.period,
        "title": str(attrs.get("title", "")),
        "notes": str(attrs.get("notes", "")),
        "config": config,
        "attrs": attrs,
        "system": system,
        "result": result,
    }


# =====================================================================================
# Census files (stickslip_fast.census): every start at every value, and the attractors
# =====================================================================================
# A census file (schema 1, root attribute ``kind = "census"``) holds the raw runs of
# :func:`stickslip_fast.census.census`, streamed and resumable like a sweep file, and,
# once every run is done, their classification. For a census of parameter P with V
# values and S starts::
#
#     /P              (V,)   coordinate: the values, in the order tracks follow them
#     /start          (S,)   coordinate: 0..S-1 (start 0 is the zero state when included)
#     /point          (K,)   0..K-1, K = max_points
#     /state          (n,)   state names x1, dx1, phi1, dphi1, ..., [vb]
#     /initial_state  (start, state)          the starts
#     /points         (P, start, point, state) Poincare points, time order, NaN-padded
#     /count, /period, /status, /n_steps, /n_rejected, /n_crossings  (P, start)
#     /final_state    (P, start, state)
#     /done           (P, start)   1 once the run is written (resume uses it)
#     /t_converged    (P, start)   f8, only with stop="converged" (NaN: never converged)
#     /label          (P, start)   i4: track id of the attractor reached; -1 failed or no
#                                  crossings; -2 not classified yet
#     /attractors     group (one row per attractor per value; open with group="attractors")
#         attractor (A,) coordinate; value_index, track, kind (int8, flag_meanings),
#         period, count (A,) i4; fraction (A,) f8; points (attractor, orbit_point, state)
#         NaN-padded, orbit_point = 0..max(max_period, rows)-1
#     /tracks         group: track (T,) coordinate; kind (int8), birth, death (value
#                     indices, i4), born, dies (u1: inside the range), periods (str)
#
# Root attributes as a sweep file's (config, config_sha256, ...), plus ``kind``,
# ``classified`` (1 once /label and the groups are written) and the classification
# settings ``identity_tol`` and ``track_threshold``.

#: Per-run integer datasets of a census file and their dtypes.
CENSUS_RUN_FIELDS = PER_VALUE_FIELDS


@dataclass
class CensusLayout:
    """Shape information of a census file."""

    param: str
    values: np.ndarray
    starts: np.ndarray
    max_points: int
    state_names: list[str]
    converged: bool = False  # stop="converged": also a t_converged dataset

    @property
    def grid_shape(self) -> tuple[int, int]:
        return (len(self.values), len(self.starts))


class CensusFile(SweepFile):
    """Create, check and append to a census file (see the census schema above).

    Opening, resuming, the configuration check and the writer lock are those
    of :class:`SweepFile`; only the layout and the writes differ.
    """

    @staticmethod
    def empty_arrays(layout: CensusLayout) -> dict[str, np.ndarray]:
        """In-memory arrays of a census without a file (the file's fill values)."""
        grid = layout.grid_shape
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
        a["schema_version"] = SCHEMA_VERSION
        a["package_version"] = package_version
        a["kind"] = "census"
        a["config"] = text
        a["config_sha256"] = digest
        a["created"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
        a["title"] = title
        a["notes"] = notes
        a["Conventions"] = "CF-1.8"
        a["param"] = layout.param
        a["classified"] = 0
        for key in ("method", "rtol", "atol", "h", "t_end", "t_transient", "max_points"):
            a[key] = config["settings"][key]
        a["stop"] = config["stop"]
        for key, value in config["system"].items():
            if value is not None:
                a[f"system.{key}"] = value
        scales = {}
        d = h5.create_dataset(layout.param, data=np.asarray(layout.values, dtype="f8"))
        d.make_scale(layout.param)
        d.attrs["long_name"] = f"swept parameter {layout.param} (nondimensional)"
        scales[layout.param] = d
        n_s = len(layout.starts)
        d = h5.create_dataset("start", data=np.arange(n_s, dtype="i4"))
        d.make_scale("start")
        d.attrs["long_name"] = "index of the initial state"
        scales["start"] = d
        d = h5.create_dataset("point", data=np.arange(layout.max_points, dtype="i4"))
        d.make_scale("point")
        d.attrs["long_name"] = "index of the Poincare point, in time order"
        scales["point"] = d
        d = h5.create_dataset("state", data=np.array(layout.state_names, dtype=object),
                              dtype=h5py.string_dtype())  # fmt: skip
        d.make_scale("state")
        d.attrs["long_name"] = "state variable"
        scales["state"] = d
        d = h5.create_dataset("initial_state", data=np.asarray(layout.starts, dtype="f8"))
        d.dims[0].attach_scale(scales["start"])
        d.dims[1].attach_scale(scales["state"])
        d.attrs["description"] = "The initial state of every start"

        grid = layout.grid_shape
        gdims = (layout.param, "start")
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
        for name, (shape, dtype, dims, fill) in specs.items():
            chunks = (1, min(n_s, 256)) + tuple(min(s, 256) for s in shape[2:])
            if kp == 0 and name == "points":
                chunks = None
            d = h5.create_dataset(
                name, shape=shape, dtype=dtype, fillvalue=fill, chunks=chunks,
                compression="gzip" if chunks else None,
                compression_opts=1 if chunks else None, shuffle=bool(chunks),
            )  # fmt: skip
            for i, dim in enumerate(dims):
                d.dims[i].attach_scale(scales[dim])
            d.attrs["description"] = descriptions[name]
        st = h5["status"]
        st.attrs["flag_values"] = np.arange(len(STATUS_NAMES), dtype="i1")
        st.attrs["flag_meanings"] = " ".join(STATUS_NAMES)
        st.attrs["missing_value"] = np.int8(-1)

    def write_pairs(self, flat: np.ndarray, data: dict[str, np.ndarray]) -> None:
        """Write runs at sorted flat (value, start) indices and flush; ``done`` last."""
        n_s = self.h5["done"].shape[1]
        vi, si = np.divmod(np.asarray(flat), n_s)
        runs = []
        a = 0
        for j in range(1, len(flat) + 1):
            if j == len(flat) or vi[j] != vi[a] or si[j] != si[j - 1] + 1:
                runs.append((int(vi[a]), slice(int(si[a]), int(si[j - 1]) + 1), slice(a, j)))
                a = j
        names = ["points", "final_state", *CENSUS_RUN_FIELDS]
        if "t_converged" in self.h5:
            names.append("t_converged")
        for name in names:
            ds = self.h5[name]
            for v, s, part in runs:
                ds[v, s] = data[name][part]
        self.h5.flush()
        for v, s, _ in runs:
            self.h5["done"][v, s] = 1
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
    settings: dict[str, float],
) -> None:  # fmt: skip
    """Store labels, the attractor table and the track table in a finished census file.

    Replaces an earlier classification (the groups are rewritten whole).
    """
    rows = [a for atts in attractors for a in atts]
    vidx = [i for i, atts in enumerate(attractors) for _ in atts]
    with h5py.File(path, "r+", libver="latest") as h5:
        n = len(h5["state"])
        h5.attrs["classified"] = 0
        h5.flush()
        h5["label"][...] = labels
        for name in ("attractors", "tracks"):
            if name in h5:
                del h5[name]
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
        cols = {
            "value_index": (np.array(vidx, dtype="i4"), "index of the value (0-based)"),
            "track": (np.array([a.id for a in rows], dtype="i4"), "track id"),
            "kind": (np.array([kinds.index(a.kind) for a in rows], dtype="i1"), "kind"),
            "period": (np.array([a.period for a in rows], dtype="i4"), "period (0: none)"),
            "count": (np.array([a.count for a in rows], dtype="i4"), "starts reaching it"),
            "fraction": (np.array([a.fraction for a in rows], dtype="f8"), "basin fraction"),
            "first_start": (np.array([a.first_start for a in rows], dtype="i4"),
                            "lowest start reaching it (its points come from that run)"),
        }  # fmt: skip
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
        t = h5.create_group("tracks")
        t.attrs["description"] = "Attractors matched over neighbouring values"
        sc = t.create_dataset("track", data=np.arange(len(tracks), dtype="i4"))
        sc.make_scale("track")
        tcols = {
            "kind": np.array([kinds.index(x.kind) for x in tracks], dtype="i1"),
            "birth": np.array([x.birth for x in tracks], dtype="i4"),
            "death": np.array([x.death for x in tracks], dtype="i4"),
            "born": np.array([x.born for x in tracks], dtype="u1"),
            "dies": np.array([x.dies for x in tracks], dtype="u1"),
            "periods": np.array([",".join(map(str, x.periods)) for x in tracks], dtype=object),
        }
        for name, arr in tcols.items():
            kw = {"dtype": h5py.string_dtype()} if arr.dtype == object else {}
            d = t.create_dataset(name, data=arr, **kw)
            d.dims[0].attach_scale(sc)
        t["kind"].attrs["flag_values"] = np.arange(len(kinds), dtype="i1")
        t["kind"].attrs["flag_meanings"] = " ".join(kinds)
        t["birth"].attrs["description"] = "index of the first value where the track exists"
        t["death"].attrs["description"] = "index of the last value where the track exists"
        t["born"].attrs["description"] = "1: born inside the range (birth > 0)"
        t["dies"].attrs["description"] = "1: dies inside the range (death < n_values - 1)"
        for key, value in settings.items():
            h5.attrs[key] = value
        h5.flush()
        h5.attrs["classified"] = 1
