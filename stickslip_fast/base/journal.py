"""A checkpoint of a long computation: the journal of its costly kernel calls.

A continuation is a deterministic walk: the same call makes the same kernel calls with the
same inputs, in the same order, and gets the same bits back. Almost all of its time goes to
a few pure kernels, the variational integrations of return maps and shooting segments (and,
for a stable manifold's trace, the crossings of its plane's points). So a continuation
resumes from a *journal* of those calls. Inside :func:`journal`, each call
through :func:`call_journaled` is answered from the file when its inputs were seen before,
and otherwise computed and appended to the file at once. Run the same call again with the
same file after a kill, and the walk replays the recorded calls in seconds (only the linear
algebra around them runs again). It then goes on where it stopped, and the result is
bit-identical to that of a run that was never interrupted.

The file is append-only. Each record carries its length and a CRC-32, so a record cut short
by a kill is found and dropped when the file is opened again. A record is flushed to the
operating system as soon as it is written, which is enough to survive a killed process; a
power cut can lose the last second. The first record describes the call: the function, its
arguments and the fingerprint of the package's code. Opening the file for another call,
other arguments or other code is an error that names what differs. A lock keeps a second
process out of a file in use.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import logging
import os
import struct
import threading
import time
import zlib
from collections.abc import Callable, Iterator, Mapping
from contextvars import ContextVar
from pathlib import Path
from typing import Any

import numpy as np

from .interrupt import call_interruptible

__all__ = ["Journal", "journal", "checkpoint", "call_journaled", "describe"]

_log = logging.getLogger("stickslip_fast.checkpoint")

MAGIC = b"STICKSLIP_FAST_CHECKPOINT\n"
FORMAT = 1
_FRAME = struct.Struct("<II")  # payload length, CRC-32 of the payload
_KEY_BYTES = 32
#: Seconds between fsyncs; every record is flushed to the operating system at once.
FSYNC_INTERVAL = 1.0

#: The journal in force (None: calls are computed and not recorded).
_ACTIVE: ContextVar[Journal | None] = ContextVar("stickslip_fast_journal", default=None)


# ----------------------------------------------------------------- what a call is
def describe(value: Any) -> str:
    """A canonical text for an argument of a journaled call, equal for equal values.

    Numbers are written exactly (``repr`` of the float: 1 and 1.0 are one value), arrays as their shape, dtype and SHA-256,
    records (dataclasses) field by field, and a long description as its SHA-256.

    Raises
    ------
    TypeError
        For a value with no canonical text (a function, an open file, ...).
    """
    text = _describe(value)
    if len(text) > 200:
        text = f"{type(value).__name__} sha256:{hashlib.sha256(text.encode()).hexdigest()}"
    return text


def _describe(value: Any) -> str:
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or isinstance(value, (bool, complex, str)):
        return repr(value)
    if isinstance(value, (int, float)):  # 1 and 1.0 are the same setting
        return repr(float(value))
    if isinstance(value, np.ndarray):
        data = np.ascontiguousarray(value)
        if data.dtype.hasobject:
            raise TypeError("an array of Python objects has no canonical description")
        digest = hashlib.sha256(data.tobytes()).hexdigest()
        return f"array{tuple(data.shape)} {data.dtype.str} sha256:{digest}"
    if isinstance(value, os.PathLike):
        return repr(os.fspath(value))
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = (f"{f.name}={_describe(getattr(value, f.name))}"
                  for f in dataclasses.fields(value) if f.init)  # fmt: skip
        return f"{type(value).__name__}({', '.join(fields)})"
    if isinstance(value, Mapping):
        items = sorted((str(k), _describe(v)) for k, v in value.items())
        return "{" + ", ".join(f"{k}: {v}" for k, v in items) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_describe(v) for v in value) + "]"
    raise TypeError(f"a {type(value).__name__} has no canonical description")


def _key(kernel: Callable, args: tuple) -> bytes:
    """The identity of a call: the kernel's name and every argument's type and bits."""
    fn = getattr(kernel, "py_func", kernel)
    h = hashlib.blake2b(digest_size=_KEY_BYTES)
    h.update(f"{fn.__module__}.{fn.__qualname__}\0".encode())
    for a in args:
        _feed(h, a)
    return h.digest()


def _feed(h, a: Any) -> None:
    """Add one argument's type and bits to the hash ``h``."""
    if isinstance(a, np.ndarray):
        if a.dtype.hasobject:
            raise TypeError("a journaled call takes no arrays of Python objects")
        h.update(f"a{a.dtype.str}{a.shape}\0".encode())
        h.update(np.ascontiguousarray(a).tobytes())
    elif isinstance(a, (bool, int, float, str)):
        h.update(f"{type(a).__name__}:{a!r}\0".encode())
    elif isinstance(a, np.generic):
        h.update(f"{a.dtype.str}:{a.item()!r}\0".encode())
    elif isinstance(a, tuple):
        h.update(f"t{len(a)}(".encode())
        for item in a:
            _feed(h, item)
        h.update(b")")
    else:
        raise TypeError(f"a journaled call takes no {type(a).__name__} argument")


# ----------------------------------------------------------------- what a call returns
def _encode(out: Any) -> bytes:
    """A kernel's result (a tuple of arrays and scalars, or one of them) as bytes."""
    items, single = ((out,), True) if not isinstance(out, tuple) else (out, False)
    parts = [struct.pack("<?I", single, len(items))]
    for item in items:
        arr = np.asarray(item)
        if arr.dtype.hasobject:
            raise TypeError(f"a journaled kernel returned a {type(item).__name__}")
        scalar = not isinstance(item, np.ndarray)
        dtype = arr.dtype.str.encode()
        parts.append(struct.pack("<?B", scalar, len(dtype)) + dtype)
        parts.append(struct.pack(f"<B{arr.ndim}Q", arr.ndim, *arr.shape))
        parts.append(np.ascontiguousarray(arr).tobytes())
    return b"".join(parts)


def _decode(data: bytes) -> Any:
    """The inverse of :func:`_encode`: fresh, writable arrays, Python scalars."""
    single, count = struct.unpack_from("<?I", data, 0)
    pos, items = struct.calcsize("<?I"), []
    for _ in range(count):
        scalar, n_dtype = struct.unpack_from("<?B", data, pos)
        pos += 2
        dtype = np.dtype(data[pos : pos + n_dtype].decode())
        pos += n_dtype
        (ndim,) = struct.unpack_from("<B", data, pos)
        shape = struct.unpack_from(f"<{ndim}Q", data, pos + 1)
        pos += 1 + 8 * ndim
        size = dtype.itemsize * int(np.prod(shape, dtype=np.int64))
        arr = np.frombuffer(data, dtype=dtype, count=size // dtype.itemsize, offset=pos)
        arr = arr.reshape(shape).copy()
        pos += size
        items.append(arr[()].item() if scalar else arr)
    return items[0] if single else tuple(items)


# ----------------------------------------------------------------- the file
class Journal:
    """An open checkpoint file: the recorded calls, and the file to append new ones to.

    Use :func:`journal` rather than this class. ``hits`` and ``misses`` count the calls
    answered from the file and those computed (and appended) since it was opened;
    ``recorded`` is the number of calls the file held when it was opened.
    """

    def __init__(self, path: str | os.PathLike, header: Mapping[str, Any]) -> None:
        self.path = Path(path)
        self.hits = self.misses = 0
        self._records: dict[bytes, bytes] = {}
        self._last_sync = time.monotonic()
        # calls may come from several threads at once (the segments of multiple shooting)
        self._guard = threading.Lock()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file = open(self.path, "a+b")  # noqa: SIM115 - closed by close()
        try:
            _lock(self._file, self.path)
            self._load(dict(header))
        except BaseException:
            self._file.close()
            raise
        self.recorded = len(self._records)

    def _load(self, header: dict[str, Any]) -> None:
        f = self._file
        f.seek(0)
        if not f.read(len(MAGIC)):  # a new file: its header first
            f.write(MAGIC)
            self._append(json.dumps(header, sort_keys=True).encode())
            return
        f.seek(0)
        if f.read(len(MAGIC)) != MAGIC:
            raise ValueError(f"checkpoint {self.path} is not a stickslip_fast checkpoint file")
        first = _read_record(f)
        if first is None:  # killed while it was being created: start it again
            f.truncate(0)
            f.write(MAGIC)
            self._append(json.dumps(header, sort_keys=True).encode())
            return
        _check_header(self.path, json.loads(first.decode()), header)
        good = f.tell()
        while (payload := _read_record(f)) is not None:
            self._records[payload[:_KEY_BYTES]] = payload[_KEY_BYTES:]
            good = f.tell()
        f.seek(0, os.SEEK_END)
        if f.tell() != good:  # a record cut short by a kill: drop it
            _log.info("checkpoint %s: dropped %d bytes of an unfinished record",
                      self.path, f.tell() - good)  # fmt: skip
            f.truncate(good)

    def _append(self, payload: bytes) -> None:
        f = self._file
        f.seek(0, os.SEEK_END)
        f.write(_FRAME.pack(len(payload), zlib.crc32(payload)) + payload)
        f.flush()
        now = time.monotonic()
        if now - self._last_sync >= FSYNC_INTERVAL:
            os.fsync(f.fileno())
            self._last_sync = now

    def call(self, kernel: Callable, args: tuple, abort: np.ndarray) -> Any:
        """``kernel(*args, abort)``, from the file if recorded, else computed and recorded."""
        key = _key(kernel, args)
        with self._guard:
            data = self._records.get(key)
            if data is not None:
                self.hits += 1
        if data is not None:
            return _decode(data)
        out = call_interruptible(kernel, *args, abort=abort)
        if abort[0]:
            # stopped by Ctrl-C in a worker thread (the main thread raises it): a result
            # cut short must not be replayed as the call's answer
            raise KeyboardInterrupt
        data = _encode(out)
        with self._guard:
            self._append(key + data)
            self._records[key] = data
            self.misses += 1
        return out

    def close(self) -> None:
        """Sync and close the file (releasing its lock)."""
        if not self._file.closed:
            self._file.flush()
            os.fsync(self._file.fileno())
            self._file.close()


def _read_record(f) -> bytes | None:
    """The next whole, intact record's payload, or None (end of file, or a damaged tail)."""
    frame = f.read(_FRAME.size)
    if len(frame) < _FRAME.size:
        return None
    size, crc = _FRAME.unpack(frame)
    payload = f.read(size)
    if len(payload) < size or zlib.crc32(payload) != crc:
        return None
    return payload


def _lock(f, path: Path) -> None:
    """An exclusive lock on the open file, or an error naming it (where locks exist)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - no advisory locks here
        return
    try:
        fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        raise RuntimeError(
            f"checkpoint {path} is in use by another process; wait for it to end or "
            "give another path"
        ) from None


def _check_header(path: Path, old: dict[str, Any], new: dict[str, Any]) -> None:
    """Refuse a file written for another call, other arguments or other code."""
    if old.get("format") != new["format"]:
        raise ValueError(f"checkpoint {path} has format {old.get('format')!r}, this "
                         f"stickslip_fast writes {new['format']!r}; delete it")  # fmt: skip
    if old.get("call") != new["call"]:
        raise ValueError(f"checkpoint {path} was written by {old.get('call')}, not "
                         f"{new['call']}; give another path")  # fmt: skip
    was, now = old.get("arguments", {}), new["arguments"]
    for name in sorted(set(was) | set(now)):
        if was.get(name) != now.get(name):
            raise ValueError(
                f"checkpoint {path} was written for another configuration: argument "
                f"{name!r} was {was.get(name, '(not given)')}, now {now.get(name, '(not given)')}; "
                "give the same arguments to resume, or another path"
            )
    if old.get("code") != new["code"]:
        raise ValueError(
            f"checkpoint {path} was written by other code (stickslip_fast "
            f"{old.get('version')}, fingerprint {str(old.get('code'))[:12]}; this is "
            f"{new['version']}, {new['code'][:12]}): its results may differ; delete it"
        )


@contextlib.contextmanager
def journal(
    path: str | os.PathLike | None, call: str, arguments: Mapping[str, Any]
) -> Iterator[Journal | None]:
    """Journal the kernel calls made inside to ``path`` (nothing, when ``path`` is None).

    Parameters
    ----------
    path : str or os.PathLike or None
        The checkpoint file: created if missing, resumed from if it holds a journal of
        the same call with the same arguments and the same code. A file that ends
        with no call recorded (an equilibrium's continuation integrates nothing, or
        the call failed before its first integration) is removed.
    call : str
        The name of the journaled computation.
    arguments : mapping
        Its arguments (:func:`describe` gives each one's identity in the header).

    Raises
    ------
    ValueError
        For a file of another call, arguments or code (naming what differs), or not a
        checkpoint file.
    RuntimeError
        For a file in use by another process.
    """
    if path is None:
        yield None
        return
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"checkpoint must be a path or None, got {path!r}")
    from .cache_guard import fingerprint
    from .version import package_version

    header = {"format": FORMAT, "call": call, "version": package_version(),
              "code": fingerprint(),
              "arguments": {k: describe(v) for k, v in arguments.items()}}  # fmt: skip
    j = Journal(path, header)
    if j.recorded:
        _log.info("checkpoint %s: resuming from %d recorded kernel calls", j.path, j.recorded)
    token = _ACTIVE.set(j)
    try:
        yield j
    finally:
        _ACTIVE.reset(token)
        j.close()
        _log.info("checkpoint %s: %d of %d calls from the file, %d computed", j.path, j.hits,
                  j.hits + j.misses, j.misses)  # fmt: skip
        if not (j.recorded or j.misses):  # nothing was integrated: leave no empty file
            j.path.unlink(missing_ok=True)


@contextlib.contextmanager
def checkpoint(path: str | os.PathLike, **config: Any) -> Iterator[Journal]:
    """Record the integrations of every continuation inside in one file, for a script.

    A script that runs several branches, curves or manifolds one after another (and
    whatever it computes between them) resumes after a kill when run again: each call
    inside replays its recorded integrations and goes on, bit-identically. A call
    given a ``checkpoint`` of its own records into that one instead.

    Parameters
    ----------
    path : str or os.PathLike
        The checkpoint file (created, or resumed from).
    **config
        What the script's results depend on beyond its calls' arguments (a preset,
        a grid...): a file written for other values is refused, naming the key. The
        records themselves are keyed by every input of their integration, so a
        changed call can never be answered with another's result; ``config`` only
        keeps runs apart.

    Yields
    ------
    Journal
        ``recorded`` (calls in the file when it was opened), ``hits`` and
        ``misses`` (calls answered from it, and computed, so far).

    Raises
    ------
    ValueError
        For a file written for another ``config``, by other code, or not a
        checkpoint file.
    RuntimeError
        For a file in use by another process.

    Examples
    --------
    >>> with ssf.checkpoint("fold_curves.ckpt", preset="asymmetric"):  # doctest: +SKIP
    ...     branch = ssf.continue_orbit(orbit, "eta", (3.2, 3.4))
    ...     fold = next(b for b in branch.bifurcations if b.kind == "fold")
    ...     curve = ssf.continue_bifurcation(branch, fold, "k12", (-0.95, -0.6))
    """
    if path is None:
        raise ValueError("checkpoint needs a path, got None")
    with journal(path, "checkpoint", config) as j:
        yield j


def call_journaled(kernel: Callable[..., Any], *args: Any, abort: np.ndarray) -> Any:
    """:func:`~stickslip_fast.base.interrupt.call_interruptible`, through the journal in
    force, if any. Only for kernels whose result depends on their arguments alone and
    that change none of them (their outputs are the values they return)."""
    j = _ACTIVE.get()
    if j is None:
        return call_interruptible(kernel, *args, abort=abort)
    return j.call(kernel, args, abort)
