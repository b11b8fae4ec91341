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
import errno
import functools
import hashlib
import json
import math
import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from .poincare import STATUS_NAMES

__all__ = [
    "SCHEMA_VERSION",
    "ConfigMismatchError",
    "ResultFileError",
    "DiskFullError",
    "open_h5",
    "SweepLayout",
    "MemoryStore",
    "read_dataset",
    "sweep_summary",
    "verify_sweep",
    "file_kind",
    "SweepFile",
    "config_digest",
    "read_sweep",
    "PER_VALUE_FIELDS",
    "ANALYSES",
    "ANALYSIS_FIELDS",
    "write_trajectory",
    "read_trajectory",
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


class ResultFileError(ValueError):
    """A result file is not usable: not HDF5, truncated, or corrupted.

    The message names the file and what is wrong with it.
    """


class DiskFullError(OSError):
    """The file system refused to let a result file grow (disk full or file size limit).

    Raised *before* anything is written, so the file stays complete and
    resumable once there is space again.
    """


#: Attempts HDF5 makes to read a piece of metadata whose checksum fails while a
#: file is opened for SWMR reading. HDF5's default is 100 with a doubling sleep
#: between attempts (1 ns, 2 ns, ...), i.e. 2**100 ns: a corrupted or truncated
#: file then makes every reader sleep for ever. 2**25 ns = 34 ms of retries is
#: ample for a writer's flush in progress and bounds a corrupted read to ~70 ms.
SWMR_READ_ATTEMPTS = 25


@functools.lru_cache(maxsize=1)
def _hdf5_set_read_attempts():
    """``H5Pset_metadata_read_attempts`` of the HDF5 library h5py uses, or None."""
    import ctypes

    candidates = []
    try:
        with open("/proc/self/maps") as fh:  # the library actually mapped into this process
            for line in fh:
                lib = line.split()[-1]
                if "libhdf5" in os.path.basename(lib) and "_hl" not in os.path.basename(lib):
                    candidates.append(lib)
    except OSError:  # pragma: no cover - not Linux
        pass
    root = Path(h5py.__file__).parent
    for pattern in ("../h5py.libs/libhdf5*", ".dylibs/libhdf5*", "../h5py.libs/hdf5*.dll"):
        candidates += [str(p) for p in root.glob(pattern) if "_hl" not in p.name]
    probe = h5py.h5p.create(h5py.h5p.FILE_ACCESS)
    for lib in dict.fromkeys(candidates):
        try:
            fn = ctypes.CDLL(lib).H5Pset_metadata_read_attempts
        except (OSError, AttributeError):  # pragma: no cover
            continue
        fn.argtypes = [ctypes.c_int64, ctypes.c_uint]
        fn.restype = ctypes.c_int
        if fn(probe.id, 1) >= 0:  # the same library instance accepts h5py's identifiers
            return fn
    return None  # pragma: no cover - readers then rely on the truncation pre-check only


def _superblock_eof(path: Path) -> int | None:
    """End-of-file address stored in a version 2/3 superblock, or None."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(48)
    except OSError:
        return None
    if len(head) < 48 or head[:8] != b"\x89HDF\r\n\x1a\n" or head[8] not in (2, 3):
        return None
    size = head[9]
    if size != 8:
        return None
    return int.from_bytes(head[12 + 2 * size : 12 + 3 * size], "little")


def _truncation(path: Path) -> str | None:
    """A message when the file is shorter than its superblock says, else None."""
    stored = _superblock_eof(path)
    actual = path.stat().st_size
    if stored is not None and actual < stored:
        return (
            f"truncated: {actual} bytes on disk but the file records {stored} "
            "(cut short by a kill, a full disk or an incomplete copy)"
        )
    return None


def open_h5(path: str | Path, *, check_truncation: bool = True) -> h5py.File:
    """Open a result file for reading, safely and with bounded time.

    The file is opened in SWMR mode (so it can be read while a sweep appends to
    it, or after a writer was killed), with a bounded number of metadata read
    attempts (see :data:`SWMR_READ_ATTEMPTS`) so that a corrupted file fails
    within milliseconds instead of hanging.

    Parameters
    ----------
    path : str or Path
    check_truncation : bool
        Refuse a file shorter than its superblock records (default).

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ResultFileError
        If it is not an HDF5 file, is truncated, or its metadata is corrupted.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no such file: {path}")
    if path.is_dir():
        raise ResultFileError(f"{path} is a directory, not a result file")
    live = writer_alive(path)
    if check_truncation and not live:  # a live writer may have allocated past the end
        problem = _truncation(path)
        if problem:
            raise ResultFileError(f"{path}: {problem}")
    fapl = h5py.h5p.create(h5py.h5p.FILE_ACCESS)
    fapl.set_libver_bounds(h5py.h5f.LIBVER_LATEST, h5py.h5f.LIBVER_LATEST)
    setter = _hdf5_set_read_attempts()
    if setter is not None:
        setter(fapl.id, SWMR_READ_ATTEMPTS)
    try:
        fid = h5py.h5f.open(
            os.fsencode(path), h5py.h5f.ACC_RDONLY | h5py.h5f.ACC_SWMR_READ, fapl=fapl
        )
    except (OSError, RuntimeError) as exc:
        hint = "; a sweep is writing it now, try again" if live else ""
        raise ResultFileError(f"{path}: not a readable HDF5 file ({_short(exc)}){hint}") from None
    return h5py.File(fid)


def _short(exc: BaseException) -> str:
    """The first line of an HDF5 error message, without h5py's prefix noise."""
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    return text


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

    Reopening verifies the file: every chunk is read (Fletcher-32 and
    decompression checks), the swept values are checked against the SHA-256
    stored in the configuration, and the length against the superblock. A file
    left by a killed writer, or with unreadable chunks or a truncated tail, is
    rebuilt from what can be read; the values that could not be read are marked
    not done and recomputed (a warning says how many). Before each write the
    file's growth is reserved on disk, so a full disk raises
    :class:`DiskFullError` with the file complete and resumable.
    """

    def __init__(self, h5: h5py.File, layout: SweepLayout, lock: _WriterLock | None = None):
        self.h5 = h5
        self.layout = layout
        self._lock = lock
        self.path = Path(h5.filename)
        self._room_fd: int | None = None  # kept open: reserving costs ~0.2 ms, not ~1 ms
        self._chunk_info: dict | None = None

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
        # the resolved path: a symlink to a live file meets the same lock, and a
        # rebuild replaces the file itself, never the link
        path = Path(os.path.realpath(path))
        text, digest = config_digest(config)
        _make_parent(path)
        lock = _WriterLock(path)
        meta = (text, digest, config, title, notes, package_version)
        try:
            if path.exists() or path.is_symlink():
                h5 = cls._reopen(path, layout, meta)
            else:
                tmp = path.with_name(path.name + ".partial")
                try:
                    _new_file(tmp, layout, meta).close()
                except BaseException:
                    tmp.unlink(missing_ok=True)
                    raise
                tmp.replace(path)  # the file appears only once its layout is complete
                h5 = h5py.File(path, "r+", libver="latest")
            h5.swmr_mode = True
        except BaseException:
            lock.release()
            raise
        return cls(h5, layout, lock)

    @classmethod
    def _reopen(cls, path: Path, layout: SweepLayout, meta: tuple) -> h5py.File:
        """Open an existing file for appending after checking its configuration and data."""
        text, digest = meta[0], meta[1]
        if path.is_dir():
            raise ResultFileError(f"{path} is a directory; choose a file name for the output")
        try:
            src = open_h5(path, check_truncation=False)
        except ResultFileError as exc:
            raise ConfigMismatchError(
                f"{path} exists but is not a readable HDF5 file ({str(exc).split(': ', 1)[-1]}); "
                "remove it or choose another output path"
            ) from None
        with src:
            try:
                found = src.attrs.get("config_sha256")
                old = src.attrs.get("config")
                schema = src.attrs.get("schema_version")
            except (OSError, RuntimeError, KeyError) as exc:
                raise ResultFileError(
                    f"{path}: its configuration cannot be read ({_short(exc)}); the file is "
                    "corrupted. Remove it (or choose another output path) to start over."
                ) from None
            if found is None or old is None:
                why = _truncation(path) or "no 'config' attribute"
                raise ResultFileError(
                    f"{path}: its configuration cannot be read ({why}); it is not a complete "
                    "stickslip_fast result file. Remove it (or choose another output path) "
                    "to start over."
                )
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
            problems, bad = scan_sweep(src, layout, meta[2])
        truncated = _truncation(path)
        if truncated:
            problems.insert(0, truncated)
        if not problems:
            try:
                return h5py.File(path, "r+", libver="latest")
            except OSError as exc:
                if "already open for write" not in str(exc):
                    problems.append(f"cannot be opened for writing ({_short(exc)})")
        # A writer was killed (we hold the writer lock, so none is alive; HDF5 left the
        # file marked open), or parts of the file are unreadable: rebuild it from what
        # can be read, then append. Values that could not be read are computed again.
        _rebuild(path, layout, meta, bad)
        if problems:
            n_bad = int(np.count_nonzero(bad))
            warnings.warn(
                f"{path}: {'; '.join(problems)}. Recovered what could be read; "
                f"{n_bad} of {bad.size} value(s) could not be read and will be computed again.",
                UserWarning,
                stacklevel=4,
            )
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
                fletcher32=bool(chunks),
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
        each with the block's value axes first. ``done`` is set last. Room for
        the block is reserved on disk first: if the file cannot grow by that
        much, :class:`DiskFullError` is raised and nothing is written.
        """
        names = self.layout.result_fields
        self._reserve(index, names + ("done",))
        for name in names:
            self.h5[name][index] = data[name]
        self.h5.flush()
        self.h5["done"][index] = 1
        self.h5.flush()

    def _reserve(self, index: tuple, names: tuple[str, ...]) -> None:
        """Check that the file can grow by what writing ``names`` at ``index`` may need.

        HDF5 rewrites every compressed chunk a write touches, at a new address
        when it grows, and updates its chunk index. The bound is the
        uncompressed size of every touched chunk plus 4 KiB each, plus 64 KiB
        for metadata. A write that would fail for lack of space fails here
        (:func:`ensure_room`), before HDF5 has touched the file.
        """
        need = 64 * 1024
        if self._chunk_info is None:  # h5py property access is slow: read it once
            self._chunk_info = {}
            for n_ in _data_fields(self.layout):
                ds = self.h5[n_]
                self._chunk_info[n_] = (ds.shape, ds.chunks, ds.dtype.itemsize)
        for name in names:
            shape, chunks, itemsize = self._chunk_info[name]
            if chunks is None:
                continue
            n = 1
            for d, (size, c) in enumerate(zip(shape, chunks)):
                sel = index[d] if d < len(index) else slice(None)
                if isinstance(sel, slice):
                    lo, hi, _ = sel.indices(size)
                    n *= max(1, (max(hi, lo + 1) - 1) // c - lo // c + 1)
            need += n * (math.prod(chunks) * itemsize + 4096)
        if self._room_fd is None:
            self._room_fd = os.open(self.path, os.O_WRONLY)
        ensure_room(self.path, need, fd=self._room_fd)

    def close(self) -> None:
        if self._room_fd is not None:
            os.close(self._room_fd)
            self._room_fd = None
        if self.h5.id.valid:
            self.h5.close()
        if self._lock is not None:
            self._lock.release()
            self._lock = None

    def __enter__(self) -> SweepFile:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


_NO_ROOM = (errno.ENOSPC, errno.EFBIG, getattr(errno, "EDQUOT", errno.ENOSPC))


def ensure_room(path: Path, need: int, fd: int | None = None) -> None:
    """Raise :class:`DiskFullError` unless ``path`` can grow by ``need`` bytes now.

    The file size limit (``RLIMIT_FSIZE``) and the free space of the file
    system (``statvfs``) are checked first. When the disk is nearly full (less
    than 64 times ``need`` free), the room is also taken for real with
    ``posix_fallocate`` past the end of the file and given back, which catches
    quotas and file systems whose free-space figure is approximate.
    ``fd``: an open descriptor of ``path`` to use (default: open one).
    """
    own = fd is None
    if own:
        fd = os.open(path, os.O_WRONLY)
    try:
        size = os.fstat(fd).st_size
        try:
            import resource

            limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
            if limit == resource.RLIM_INFINITY:
                limit = -1
        except (ImportError, OSError, ValueError):  # pragma: no cover - not POSIX
            limit = -1
        if limit >= 0 and size + need > limit:
            raise disk_full(path, need, OSError(errno.EFBIG, os.strerror(errno.EFBIG)))
        try:
            st = os.fstatvfs(fd)
            free = st.f_bavail * st.f_frsize
        except OSError:  # pragma: no cover
            free = 0
        if free < need:
            raise disk_full(path, need, OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)))
        if free >= 64 * need:
            return
        try:
            try:
                os.posix_fallocate(fd, size, need)
            except OSError as exc:
                if exc.errno in _NO_ROOM:
                    raise
                # no fallocate on this file system: write the zeros
                block = bytes(min(need, 1 << 20))
                for at in range(size, size + need, len(block)):
                    os.pwrite(fd, block[: size + need - at], at)
        except OSError as exc:
            if exc.errno not in _NO_ROOM:
                raise
            raise disk_full(path, need, exc) from None
        finally:
            os.ftruncate(fd, size)
    finally:
        if own:
            os.close(fd)


def disk_full(path: Path, need: int | None, exc: BaseException) -> DiskFullError:
    """The one-line error for a file that cannot grow."""
    reason = getattr(exc, "strerror", None) or _short(exc)
    room = f" by {need / 1024:.0f} KiB" if need else ""
    err = DiskFullError(
        f"cannot write {path}: no room to grow it{room} ({reason}). Everything written so "
        "far is safe: free some space (or raise the file size limit) and run the same "
        "command again to resume"
    )
    err.errno = getattr(exc, "errno", None) or errno.ENOSPC
    return err


def _is_no_room(exc: BaseException) -> bool:
    """An HDF5/OS error that means the disk or the file size limit is full."""
    if isinstance(exc, OSError) and exc.errno in _NO_ROOM:
        return True
    text = str(exc)
    return any(
        key in text
        for key in ("No space left", "File too large", "errno = 28", "errno = 27", "Disk quota")
    )


def _make_parent(path: Path) -> None:
    """Create the output's folder, with a one-line error naming it when that fails."""
    parent = path.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise NotADirectoryError(
            f"cannot write {path}: {_first_file(parent)} is a file, not a directory"
        ) from None
    except NotADirectoryError:
        raise NotADirectoryError(
            f"cannot write {path}: {_first_file(parent)} is a file, not a directory"
        ) from None
    except PermissionError:
        raise PermissionError(f"cannot create the directory {parent}: permission denied") from None
    if not os.access(parent, os.W_OK | os.X_OK):
        raise PermissionError(f"cannot write {path}: the directory {parent} is not writable")


def _first_file(path: Path) -> Path:
    """The first component of ``path`` that exists and is not a directory."""
    for p in reversed([path, *path.parents]):
        if p.exists() and not p.is_dir():
            return p
    return path


def _data_fields(layout: SweepLayout) -> tuple[str, ...]:
    return (*layout.result_fields, "done")


def scan_sweep(
    h5: h5py.File, layout: SweepLayout | None = None, config: dict | None = None
) -> tuple[list[str], np.ndarray]:
    """Verify a sweep file by reading every chunk of every per-value dataset.

    Reading checks each chunk's Fletcher-32 checksum and its compression; the
    swept values are checked against their SHA-256 in the stored configuration.

    Parameters
    ----------
    h5 : h5py.File
        An open sweep file.
    layout : SweepLayout, optional
        The expected layout (default: taken from the file).
    config : dict, optional
        The expected configuration (default: the file's own, after checking it
        against the stored ``config_sha256``).

    Returns
    -------
    problems : list of str
        What is wrong, one phrase each (empty for a sound file).
    bad : ndarray of bool, grid shape
        Values with at least one unreadable piece.
    """
    problems: list[str] = []
    if config is None:
        cfg = stored_config(h5)
    else:
        cfg = json.loads(config_digest(config)[0])
        try:
            stored_config(h5)
        except ResultFileError as exc:
            problems.append(str(exc).split(": ", 1)[-1])
    params = list(cfg["param"])
    if layout is None:
        fields = ("points", "t_points", "final_state", "done", *PER_VALUE_FIELDS)
        fields += tuple(f for a in cfg.get("analyses", ()) for f in ANALYSES[a])
        if "t_converged" in h5:
            fields += ("t_converged",)
        grid = (2,) if cfg["mode"] == "continuation-both" else ()
        grid += tuple(int(n) for n in cfg["n_values"])
    else:
        fields = _data_fields(layout)
        grid = layout.grid_shape
    for name, want in zip(params, cfg.get("values_sha256", ())):
        try:
            got = hashlib.sha256(np.ascontiguousarray(h5[name][...], dtype="<f8").tobytes())
            if got.hexdigest() != want:
                problems.append(
                    f"the stored values of {name!r} do not match their SHA-256 in the "
                    "configuration (corrupted coordinate)"
                )
        except (OSError, RuntimeError, KeyError, ValueError) as exc:
            problems.append(f"the values of {name!r} cannot be read ({_short(exc)})")
    bad = np.zeros(grid, dtype=bool)
    g = len(grid)
    unreadable: list[str] = []
    first = ""
    for name in fields:
        try:
            ds = h5[name]
            if ds.shape[:g] != grid:
                raise ValueError(f"shape {ds.shape} does not match the grid {grid}")
            chunks = list(ds.iter_chunks()) if ds.chunks else [(slice(None),) * ds.ndim]
        except (OSError, RuntimeError, KeyError, ValueError) as exc:
            problems.append(f"dataset {name!r} cannot be read ({_short(exc)})")
            bad[...] = True
            continue
        n_bad = 0
        for sel in chunks:
            try:
                ds[sel]
            except (OSError, RuntimeError, ValueError) as exc:
                bad[sel[:g]] = True
                n_bad += 1
                first = first or _short(exc)
        if n_bad:
            unreadable.append(f"{name} ({n_bad} of {len(chunks)})")
    if unreadable:
        problems.append(
            f"unreadable chunks (checksum or decompression failed: {first}) in "
            + ", ".join(unreadable)
        )
    return problems, bad


def stored_config(h5: h5py.File) -> dict:
    """The configuration stored in a result file, checked against its SHA-256.

    Raises
    ------
    ResultFileError
        If the attribute is missing, is not JSON, or does not match
        ``config_sha256``.
    """
    name = h5.filename
    try:
        text = h5.attrs["config"]
        want = h5.attrs.get("config_sha256")
    except (OSError, RuntimeError, KeyError) as exc:
        raise ResultFileError(f"{name}: the configuration cannot be read ({_short(exc)})") from None
    if isinstance(text, bytes):
        text = text.decode("utf-8", "replace")
    if want is not None and hashlib.sha256(str(text).encode()).hexdigest() != want:
        raise ResultFileError(
            f"{name}: the stored configuration does not match its SHA-256 (corrupted attribute)"
        )
    try:
        return json.loads(text)
    except (TypeError, ValueError):
        raise ResultFileError(f"{name}: the stored configuration is not valid JSON") from None


def _new_file(path: Path, layout: SweepLayout, meta: tuple) -> h5py.File:
    """A fresh sweep file with the complete layout and no values (open for writing)."""
    text, digest, config, title, notes, package_version = meta
    try:
        h5 = h5py.File(path, "w", libver="latest")
    except OSError as exc:
        raise _os_error(path, exc) from None
    try:
        SweepFile._create_layout(h5, layout, text, digest, config, title, notes, package_version)
        h5.flush()
    except BaseException as exc:
        h5.close()
        if isinstance(exc, (OSError, RuntimeError)) and _is_no_room(exc):
            raise disk_full(path, None, exc) from None
        raise
    return h5


def _os_error(path: Path, exc: OSError) -> OSError:
    """h5py's OSError for a file that cannot be created, as one line naming the path."""
    if _is_no_room(exc):
        return disk_full(path, None, exc)
    text = str(exc)
    if "Permission denied" in text or "errno = 13" in text:
        return PermissionError(f"cannot write {path}: permission denied")
    if "Is a directory" in text or "errno = 21" in text:
        return IsADirectoryError(f"cannot write {path}: it is a directory")
    return OSError(f"cannot write {path}: {_short(exc)}")


class _WriterLock:
    """An exclusive OS lock on ``<file>.lock`` held while a sweep writes the file.

    The OS drops it when the process dies, which tells a crashed writer (resume
    is safe) from a live one (refuse). ``path`` must be resolved (symlinks
    followed), so that every name of a file meets the same lock. No-op where
    fcntl is unavailable.
    """

    def __init__(self, path: Path):
        self.path = path.with_name(path.name + ".lock")
        self.fd: int | None = None
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX
            return
        for _ in range(10):
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            except OSError as exc:
                raise _lock_error(self.path, exc) from None
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                os.close(fd)
                raise ConfigMismatchError(
                    f"another process is writing {path} (lock {self.path} is held); "
                    "wait for it to finish or choose another output path"
                ) from None
            # the previous holder may have removed the lock file between our open and
            # flock: then we hold a lock on a deleted file; take the new one instead
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(self.path))
            except FileNotFoundError:
                same = False
            if same:
                self.fd = fd
                return
            os.close(fd)
        raise ConfigMismatchError(f"cannot take the lock {self.path} (it keeps changing)")

    def release(self) -> None:
        if self.fd is not None:
            # remove the file while still holding the lock, then let it go
            self.path.unlink(missing_ok=True)
            os.close(self.fd)
            self.fd = None


def _lock_error(path: Path, exc: OSError) -> OSError:
    if isinstance(exc, PermissionError):
        return PermissionError(f"cannot create the lock {path}: permission denied")
    return OSError(f"cannot create the lock {path}: {exc.strerror or exc}")


def writer_alive(path: str | Path) -> bool:
    """Whether a live process holds the writer lock of the result file ``path``."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        return False
    real = Path(os.path.realpath(path))
    lock = real.with_name(real.name + ".lock")
    try:
        fd = os.open(lock, os.O_RDONLY)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except OSError:
        return True
    finally:
        os.close(fd)
    return False


def _rebuild(path: Path, layout: SweepLayout, meta: tuple, bad: np.ndarray) -> None:
    """Copy what can be read of a damaged or crashed writer's file into a fresh one.

    The fresh file gets the layout this sweep would create (coordinates from the
    caller, whose values match the stored SHA-256); every readable chunk of the
    per-value datasets is copied; values marked ``bad`` are set not done.
    """
    tmp = path.with_name(path.name + ".recovering")
    try:
        with (
            open_h5(path, check_truncation=False) as src,
            _new_file(tmp, layout, meta) as dst,
        ):
            for key in ("created", "package_version"):
                try:
                    if key in src.attrs:
                        dst.attrs[key] = src.attrs[key]
                except (OSError, RuntimeError):
                    pass
            for name in _data_fields(layout):
                try:
                    sds = src[name]
                    chunks = list(sds.iter_chunks()) if sds.chunks else [(slice(None),) * sds.ndim]
                    if sds.shape != dst[name].shape:
                        continue
                except (OSError, RuntimeError, KeyError, ValueError):
                    continue
                fill = dst[name].fillvalue
                for sel in chunks:
                    try:
                        block = sds[sel]
                    except (OSError, RuntimeError, ValueError):
                        continue
                    empty = np.all(np.isnan(block)) if np.isnan(fill) else np.all(block == fill)
                    if not empty:
                        dst[name][sel] = block
            if bad.any():
                done = dst["done"][...]
                done[bad] = 0
                dst["done"][...] = done
        tmp.replace(path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def read_dataset(path: str | Path, name: str) -> np.ndarray:
    """One whole dataset of a result file (KeyError naming the file if it has none).

    Raises
    ------
    ResultFileError
        If the file or the dataset cannot be read (truncated or corrupted).
    """
    with open_h5(path) as h5:
        if name not in h5:
            raise KeyError(f"{path} has no {name!r} dataset")
        try:
            return h5[name][...]
        except (OSError, RuntimeError) as exc:
            raise ResultFileError(
                f"{path}: {name!r} cannot be read ({_short(exc)}); the file is corrupted"
            ) from None


def sweep_summary(path: str | Path) -> dict[str, Any]:
    """What ``stickslip-fast info`` shows of a sweep file, read in one go.

    Returns
    -------
    dict
        ``config`` (parsed, checked against its SHA-256), ``attrs`` (the root
        attributes ``title``, ``package_version``, ``schema_version``,
        ``created`` where present), ``axes`` (name -> values), ``done`` (bool),
        ``status`` and ``period``.

    Raises
    ------
    ResultFileError
        If the file is not a sweep file, or what the summary needs cannot be read.
    """
    with open_h5(path) as h5:
        try:
            if "config" not in h5.attrs or "done" not in h5:
                raise ResultFileError(
                    f"{path}: an HDF5 file, but not a stickslip_fast sweep file "
                    "(no 'config' attribute or 'done' dataset)"
                )
            config = stored_config(h5)
            keys = ("title", "package_version", "schema_version", "created")
            return {
                "config": config,
                "attrs": {k: h5.attrs[k] for k in keys if k in h5.attrs},
                "axes": {name: h5[name][...] for name in config["param"]},
                "done": h5["done"][...].astype(bool),
                "status": h5["status"][...],
                "period": h5["period"][...],
                "fletcher32": bool(h5["done"].fletcher32),
            }
        except (OSError, RuntimeError, KeyError) as exc:
            raise ResultFileError(
                f"{path}: cannot be summarised, the file is damaged ({_short(exc)})"
            ) from None


def file_kind(path: str | Path) -> str:
    """``"trajectory"`` for a ``simulate -o`` file, ``"sweep"`` for anything else."""
    with open_h5(path) as h5:
        try:
            kind = h5.attrs.get("kind")
        except (OSError, RuntimeError, KeyError):
            return "sweep"  # the sweep reader reports what is wrong
    return "trajectory" if kind == "trajectory" else "sweep"


def verify_sweep(path: str | Path) -> tuple[list[str], np.ndarray]:
    """Read every chunk of a sweep file and check its SHA-256s (see :func:`scan_sweep`)."""
    with open_h5(path) as h5:
        return scan_sweep(h5)


def read_sweep(path: str | Path) -> dict[str, Any]:
    """Read a whole sweep file into memory: arrays, coordinates and configuration.

    Raises
    ------
    ResultFileError
        If the file is not a sweep file, is truncated or corrupted (the message
        names the file, and the dataset that cannot be read).
    """
    out: dict[str, Any] = {}
    with open_h5(path) as h5:
        name = "attributes"
        try:
            if h5.attrs.get("schema_version") != SCHEMA_VERSION:
                raise ResultFileError(
                    f"{path}: not a stickslip_fast sweep file (schema_version missing)"
                )
            if h5.attrs.get("kind") == "trajectory":
                raise ResultFileError(
                    f"{path} is a trajectory file (simulate -o); read it with read_trajectory"
                )
            out["config"] = stored_config(h5)
            out["attrs"] = {k: (v.item() if hasattr(v, "item") else v) for k, v in h5.attrs.items()}
            params = tuple(str(h5.attrs["param"]).split(","))
            out["param"] = params
            name = "coordinates"
            out["axes"] = tuple(h5[p][...] for p in params)
            out["branches"] = "branch" in h5
            out["state_names"] = [
                s.decode() if isinstance(s, bytes) else s for s in h5["state"][...]
            ]
            for name in ("points", "t_points", "final_state", "done", *PER_VALUE_FIELDS):
                out[name] = h5[name][...]
            out["analyses"] = {}
            for name in (*ANALYSIS_FIELDS, "t_converged"):
                if name in h5:
                    out["analyses"][name] = h5[name][...]
        except (OSError, RuntimeError, KeyError, ValueError) as exc:
            if isinstance(exc, ResultFileError):
                raise
            raise ResultFileError(
                f"{path}: {name!r} cannot be read ({_short(exc)}); the file is corrupted"
            ) from None
    for p, axis, want in zip(params, out["axes"], out["config"].get("values_sha256", ())):
        got = hashlib.sha256(np.ascontiguousarray(axis, dtype="<f8").tobytes()).hexdigest()
        if got != want:
            raise ResultFileError(
                f"{path}: the stored values of {p!r} do not match their SHA-256 in the "
                "configuration; the file is corrupted"
            )
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

    _make_parent(path)
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
                    compression_opts=1 if data.size else None, fletcher32=True,
                )  # fmt: skip
                for i, sc in enumerate(dims):
                    d.dims[i].attach_scale(sc)
                d.attrs["description"] = desc
        tmp.replace(path)
    except BaseException as exc:
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError) and not exc.filename:
            raise _os_error(path, exc) from None
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

    with open_h5(path) as h5:
        if h5.attrs.get("schema_version") != SCHEMA_VERSION or h5.attrs.get("kind") != "trajectory":
            raise ResultFileError(f"{path}: not a stickslip_fast trajectory file")
        try:
            attrs = {k: (v.item() if hasattr(v, "item") else v) for k, v in h5.attrs.items()}
            data = {
                name: h5[name][...] for name in ("t", "y", "t_poincare", "poincare", "final_state")
            }
            names = [s.decode() if isinstance(s, bytes) else str(s) for s in h5["state"][...]]
        except (OSError, RuntimeError, KeyError) as exc:
            raise ResultFileError(f"{path}: corrupted ({_short(exc)})") from None
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
