"""Drop stale compiled kernels: Numba's disk cache does not see edits in other modules.

Numba keys a cached kernel on its own source file's timestamp only. A kernel
in trajectory.py that calls ``model.rhs`` is therefore loaded from the cache
unchanged after ``model.rhs`` is edited, and silently computes with the old
equations. :func:`check` runs at package import, before any kernel is called:
it compares a fingerprint of every source file of the package (and the Numba
version) with a stamp kept beside the package's cached kernels, and when they
differ it deletes those kernels (they recompile on first use) and writes the new
stamp. Set ``STICKSLIP_FAST_CACHE_GUARD=0`` to turn it off.
"""

from __future__ import annotations

import functools
import hashlib
import os
import warnings
from pathlib import Path

import numba

__all__ = ["fingerprint", "cache_dir", "cache_dirs", "check"]

_PKG = Path(__file__).resolve().parents[1]  # the package root (this file is in base/)
STAMP_NAME = "stickslip_fast.fingerprint"


@functools.lru_cache(maxsize=1)
def fingerprint() -> str:
    """Identity of the code that computes results: package sources + Numba version.

    Two processes with the same fingerprint compute the same bits from the same
    inputs (on the same kind of CPU). Computed once per process.

    Returns
    -------
    str
        SHA-256 (hex) of every ``*.py`` file of the package and its subpackages (sorted)
        and of the Numba version.
    """
    digest = hashlib.sha256(f"numba {numba.__version__}\n".encode())
    for path in sorted(_PKG.rglob("*.py")):
        digest.update(str(path.relative_to(_PKG)).encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def _cache_dir_of(folder: Path) -> Path:
    """Where Numba keeps the cached kernels of the modules in ``folder`` (as Numba locates it)."""
    import types

    from numba.core.caching import FunctionCache

    def probe() -> None:  # never compiled: only its source file's folder matters
        pass

    code = probe.__code__.replace(co_filename=str(folder / "__init__.py"))
    return Path(FunctionCache(types.FunctionType(code, {}, "probe"))._cache_path)


def cache_dir() -> Path:
    """Where Numba keeps the package root's cached kernels; the stamp lives there."""
    return _cache_dir_of(_PKG)


def cache_dirs() -> list[Path]:
    """Where Numba keeps the cached kernels of the package and of each of its subpackages.

    Numba caches a kernel beside its own module's folder, so a package in
    layers (model/, core/, ...) has one cache folder per subpackage.
    """
    folders = [_PKG] + sorted(p.parent for p in _PKG.glob("*/__init__.py"))
    return [_cache_dir_of(f) for f in folders]


def check() -> bool:
    """Delete the package's cached kernels if the sources changed; True if it did."""
    if os.environ.get("STICKSLIP_FAST_CACHE_GUARD", "1") == "0":
        return False
    try:
        where = cache_dir()
    except Exception:  # no usable cache location: Numba will not cache either
        return False
    stamp = where / STAMP_NAME
    current = fingerprint()
    try:
        if stamp.read_text() == current:
            return False
    except OSError:
        pass
    try:
        where.mkdir(parents=True, exist_ok=True)
        for folder in cache_dirs():
            for path in list(folder.glob("*.nbi")) + list(folder.glob("*.nbc")):
                path.unlink(missing_ok=True)
        tmp = where / f"{STAMP_NAME}.{os.getpid()}.tmp"
        tmp.write_text(current)
        os.replace(tmp, stamp)
    except OSError as exc:
        warnings.warn(
            f"stickslip_fast could not refresh its kernel cache in {where}: {exc}", stacklevel=2
        )
    return True
