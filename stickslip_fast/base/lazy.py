"""A package's submodules as its attributes, imported on first use (PEP 562).

``import stickslip_fast`` imports only what a first ``simulate`` needs, so most
submodules are not yet bound as attributes of their layer. Each layer's
``__init__`` sets ``__getattr__ = submodule_getattr(__name__)``: then
``stickslip_fast.analysis.census.default_box`` works after a plain
``import stickslip_fast``, as it did when the package imported everything.
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable
from types import ModuleType

__all__ = ["submodule_getattr"]


def submodule_getattr(package: str) -> Callable[[str], ModuleType]:
    """A module-level ``__getattr__`` for ``package`` that imports its submodules.

    Parameters
    ----------
    package : str
        The package's full name (its ``__name__``).

    Returns
    -------
    callable
        ``__getattr__(name)``: the submodule ``package.name``, imported now (and bound
        as the package's attribute by the import); ``AttributeError`` naming
        ``name`` if there is no such submodule.
    """

    def __getattr__(name: str) -> ModuleType:
        # dunders are asked for by introspection (copy, pickle, inspect): never modules
        if not name.startswith("__") and importlib.util.find_spec(f"{package}.{name}"):
            return importlib.import_module(f"{package}.{name}")
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__
