"""Plumbing every layer uses: Numba options and borrowed records, status codes, Ctrl-C and
the stale-cache guard.
"""

from .lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__)  # submodules as attributes on first use
