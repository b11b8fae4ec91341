"""Periodic orbits and equilibria by Newton's method, their multipliers, and their continuation
with bifurcation detection and branch switching.
"""

from ..base.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__)  # submodules as attributes on first use
