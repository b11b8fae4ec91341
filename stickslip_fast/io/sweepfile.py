"""The sweep result file: create, check, resume (with salvage), write."""

from __future__ import annotations

import json
import math
import os
import warnings
from pathlib import Path

import h5py
import numpy as np

from ..base.status import LABEL_RULES
from ..core.poincare import STATUS_NAMES
from .base import (
    ConfigMismatchError,
    ResultFileError,
    _diff_keys,
    _is_no_room,
    _make_parent,
    _os_error,
    _short,
    _truncation,
    _WriterLock,
    config_digest,
    disk_full,
    ensure_room,
    open_h5,
)
from .label_rules import check_label_rules
from .layout import (
    _DESCRIPTIONS,
    SCHEMA_VERSION,
    SweepLayout,
    add_point_and_state_scales,
    create_run_datasets,
    write_root_attrs,
)
from .verify import _data_fields, scan_sweep, stored_config  # noqa: F401 (re-exported)


def _for_appending(path: Path) -> h5py.File:
    """Open a checked file for writing; its labels are now those of the current rules."""
    h5 = h5py.File(path, "r+", libver="latest")
    try:
        if h5.attrs.get("label_rules") != LABEL_RULES:
            h5.attrs["label_rules"] = LABEL_RULES
    except BaseException:
        h5.close()
        raise
    return h5


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
                    _new_file(tmp, layout, meta, cls).close()
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
            check_label_rules(path, src)
            problems, bad = scan_sweep(src, layout, meta[2])
        truncated = _truncation(path)
        if truncated:
            problems.insert(0, truncated)
        if not problems:
            try:
                return _for_appending(path)
            except OSError as exc:
                if "already open for write" not in str(exc):
                    problems.append(f"cannot be opened for writing ({_short(exc)})")
        # A writer was killed (we hold the writer lock, so none is alive; HDF5 left the
        # file marked open), or parts of the file are unreadable: rebuild it from what
        # can be read, then append. Values that could not be read are computed again.
        _rebuild(path, layout, meta, bad, cls)
        if problems:
            n_bad = int(np.count_nonzero(bad))
            warnings.warn(
                f"{path}: {'; '.join(problems)}. Recovered what could be read; "
                f"{n_bad} of {bad.size} value(s) could not be read and will be computed again.",
                UserWarning,
                stacklevel=4,
            )
        return _for_appending(path)

    @staticmethod
    def _create_layout(h5, layout, text, digest, config, title, notes, package_version):
        write_root_attrs(h5.attrs, text, digest, title, notes, package_version)
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
        add_point_and_state_scales(h5, layout.max_points, layout.state_names, scales)

        grid = layout.grid_shape
        kp = layout.max_points
        # chunk along the value axes so appending a sweep chunk touches few HDF5 chunks
        vchunk = tuple(min(s, 64) for s in grid)

        def chunks_of(name, shape):
            if kp == 0 and name in ("points", "t_points"):
                return None
            return vchunk + tuple(min(s, 256) for s in shape[len(grid) :])

        create_run_datasets(
            h5, layout.dataset_specs(), chunks_of, _DESCRIPTIONS, scales, STATUS_NAMES,
            fletcher32=True,
        )  # fmt: skip

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


def _new_file(
    path: Path, layout: SweepLayout, meta: tuple, writer: type[SweepFile] | None = None
) -> h5py.File:
    """A fresh sweep file with the complete layout and no values (open for writing).

    ``writer`` is the file class that lays it out (``SweepFile``, or its
    subclass ``CensusFile`` for a census: the caller's ``cls``, so that this
    module never imports the census module, which imports it).
    """
    text, digest, config, title, notes, package_version = meta
    writer = SweepFile if writer is None else writer
    try:
        h5 = h5py.File(path, "w", libver="latest")
    except OSError as exc:
        raise _os_error(path, exc) from None
    try:
        writer._create_layout(h5, layout, text, digest, config, title, notes, package_version)
        h5.flush()
    except BaseException as exc:
        h5.close()
        if isinstance(exc, (OSError, RuntimeError)) and _is_no_room(exc):
            raise disk_full(path, None, exc) from None
        raise
    return h5


def _rebuild(
    path: Path,
    layout: SweepLayout,
    meta: tuple,
    bad: np.ndarray,
    writer: type[SweepFile] | None = None,
) -> None:
    """Copy what can be read of a damaged or crashed writer's file into a fresh one.

    The fresh file gets the layout this sweep would create (coordinates from the
    caller, whose values match the stored SHA-256); every readable chunk of the
    per-value datasets is copied; values marked ``bad`` are set not done.
    """
    tmp = path.with_name(path.name + ".recovering")
    try:
        with (
            open_h5(path, check_truncation=False) as src,
            _new_file(tmp, layout, meta, writer) as dst,
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
