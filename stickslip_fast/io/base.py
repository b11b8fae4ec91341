"""HDF5 access shared by every result file: bounded opens, digests, disk room, the writer lock."""

from __future__ import annotations

import errno
import functools
import hashlib
import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import h5py
import numpy as np


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


@contextmanager
def atomic_h5(path: str | Path, **kw: Any) -> Iterator[h5py.File]:
    """A new HDF5 file for writing that appears at ``path`` only once complete.

    It is written as ``<path>.partial`` and renamed when the block ends; on any error
    (or Ctrl-C) the partial file is removed and ``path`` is left as it was. ``kw`` go
    to ``h5py.File`` (e.g. ``libver``).
    """
    path = Path(path)
    tmp = path.with_name(path.name + ".partial")
    try:
        with h5py.File(tmp, "w", **kw) as h5:
            yield h5
        tmp.replace(path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def check_kind(path: str | Path, h5: h5py.File, kind: str, readable: tuple[int, ...]) -> int:
    """The ``schema_version`` of an open file whose root ``kind`` must be ``kind``.

    Raises
    ------
    ValueError
        Naming the file: its ``kind`` is another, or its version is not in ``readable``.
    """
    found = h5.attrs.get("kind")
    if found != kind:
        raise ValueError(f"{path}: not a {kind} file (kind = {found!r})")
    version = int(h5.attrs.get("schema_version", -1))
    if version not in readable:
        raise ValueError(
            f"{path}: {kind} schema_version {version}; this version reads "
            f"{', '.join(map(str, readable))}"
        )
    return version


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
