"""The package's cached kernels and problem records defined outside it.

The generic driver (:func:`stickslip_fast.core.driver.drive`) and the problem
functions it calls are cached functions of the package, compiled for every problem
record they meet, also for a user's own record defined in a script (the recipe of
:mod:`stickslip_fast.core.problems`, "Adding a problem"). Numba's cache has two blind
spots there, and :func:`install` closes both for the package's own cache folders:

*An index that names a module that is gone.* Numba keeps, beside each cached function,
an index of its compiled versions, pickled with the types of their arguments, so the
driver's index names the script's module. Once the script is renamed, moved or edited
so that the record is gone, loading the index raises (``ModuleNotFoundError``,
``AttributeError``), and so does every later compile that calls the driver,
``simulate`` included, until the cache is cleared by hand. Such an index is now read
as empty, with an :class:`UnreadableCacheIndex` warning that names it: its versions
recompile, and the next save writes a fresh index.

*An edit of the record's functions.* Numba keys a cached version on the function's
own source file and its argument types. An edit of the script's ``problem_f`` leaves
both unchanged, so the driver's cached version, with the old right-hand side compiled
into it, was loaded again: silently wrong results. The key of a cached version of the
package's now also holds the modification time and size of each source file outside
the package that defines a record type among its arguments, as Numba's own key holds
those of the function's file. (Edits inside the package are the stale-cache guard's,
:mod:`.cache_guard`.)

Indexes and keys of other packages are left to Numba's own behaviour.
"""

from __future__ import annotations

import functools
import os
import sys
import warnings

from numba.core import caching, types

from .cache_guard import _PKG, cache_dirs

__all__ = ["install", "installed", "UnreadableCacheIndex", "record_sources"]

_ORIGINAL_LOAD = caching.IndexDataCacheFile._load_index
_ORIGINAL_KEY = caching.Cache._index_key


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
        return _ORIGINAL_LOAD(self)
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


def _source_stamp(module_name: str):
    """(module, mtime, size) of a module's source file outside the package, else None."""
    path = getattr(sys.modules.get(module_name), "__file__", None)
    if not path:
        return None
    path = os.path.abspath(path)
    if path.startswith(str(_PKG) + os.sep):
        return None
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (module_name, st.st_mtime, st.st_size)


def record_sources(arg_types) -> tuple:
    """The source stamps of the records among ``arg_types`` defined outside the package.

    Parameters
    ----------
    arg_types : tuple of numba types, or a signature
        A compiled version's argument types.

    Returns
    -------
    tuple
        Sorted ``(module, mtime, size)`` of each source file outside the package that
        defines a named-tuple record among the types (nested ones included).
    """
    found = set()
    todo = list(getattr(arg_types, "args", arg_types))
    while todo:
        t = todo.pop()
        if isinstance(t, types.BaseNamedTuple):
            stamp = _source_stamp(t.instance_class.__module__)
            if stamp is not None:
                found.add(stamp)
        if isinstance(t, types.BaseTuple):
            todo.extend(t.types)
    return tuple(sorted(found))


def _keyed_index_key(self, sig, codegen):
    key = _ORIGINAL_KEY(self, sig, codegen)
    if not _of_package(self._cache_path):
        return key
    sources = record_sources(sig)
    return key + (sources,) if sources else key


def install() -> None:
    """Close both blind spots for the package's cache folders (idempotent)."""
    caching.IndexDataCacheFile._load_index = _tolerant_load_index
    caching.Cache._index_key = _keyed_index_key


def installed() -> bool:
    """Whether :func:`install` is in effect."""
    return (
        caching.IndexDataCacheFile._load_index is _tolerant_load_index
        and caching.Cache._index_key is _keyed_index_key
    )
