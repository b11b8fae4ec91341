"""A cache index that names a type nobody can import any more is a cache miss, not a crash.

Numba keeps, beside each cached function, an index of its compiled specialisations,
pickled with the types of their arguments. The generic driver
(:func:`stickslip_fast.core.driver.drive`) and the problem functions it calls are
compiled for every problem record they meet, also for a user's own record defined
in a script (the recipe of :mod:`stickslip_fast.core.problems`, "Adding a
problem"). Their indexes then name that script's module. Once the script is
renamed, moved or edited so that the record is gone, loading the index raises
(``ModuleNotFoundError``, ``AttributeError``), and so does every later compile that
calls the driver, ``simulate`` included, until the cache is cleared by hand.

:func:`install` makes Numba read such an index of the package's own functions as
empty, with a :class:`RuntimeWarning` that names it: the specialisations recompile,
and the next save writes a fresh index. Indexes of other packages are left to
Numba's own behaviour.
"""

from __future__ import annotations

import functools
import os
import warnings

from numba.core import caching

from .cache_guard import cache_dirs

__all__ = ["install", "installed", "UnreadableCacheIndex"]

_ORIGINAL = caching.IndexDataCacheFile._load_index


class UnreadableCacheIndex(RuntimeWarning):
    """A Numba cache index of the package could not be read; it is rebuilt."""


@functools.lru_cache(maxsize=1)
def _package_cache_dirs() -> frozenset[str]:
    try:
        return frozenset(os.path.normcase(os.path.abspath(d)) for d in cache_dirs())
    except Exception:  # noqa: BLE001 - no usable cache location: nothing is the package's
        return frozenset()


def _of_package(cache_path: str) -> bool:
    """Whether a cache folder is one of the package's (as Numba locates them)."""
    return os.path.normcase(os.path.abspath(cache_path)) in _package_cache_dirs()


def _tolerant_load_index(self):
    try:
        return _ORIGINAL(self)
    except Exception as exc:  # noqa: BLE001 - whatever unpickling raised
        if not _of_package(self._cache_path):
            raise
        warnings.warn(
            f"the Numba cache index {self._index_path} could not be read "
            f"({type(exc).__name__}: {exc}); most likely one of its compiled versions was "
            "for a problem record whose module is gone. It is rebuilt: those functions "
            "compile again once.",
            UnreadableCacheIndex,
            stacklevel=2,
        )
        return {}


def install() -> None:
    """Read unreadable cache indexes of the package as empty (idempotent)."""
    caching.IndexDataCacheFile._load_index = _tolerant_load_index


def installed() -> bool:
    """Whether :func:`install` is in effect."""
    return caching.IndexDataCacheFile._load_index is _tolerant_load_index
