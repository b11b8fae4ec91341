"""Compilation options shared by every compiled module, and the record-type test.

``error_model="numpy"`` makes a division by zero give inf/NaN instead of
raising: no kernel can raise (see docs/developing.md, "The kernel rules").
"""

from __future__ import annotations

from numba import types

__all__ = ["JIT", "OVERLOAD", "is_record"]

#: Options of every ``@njit`` of the package.
JIT = dict(cache=True, nogil=True, error_model="numpy")
#: Options of every ``@overload`` implementation.
OVERLOAD = dict(jit_options=JIT)


def is_record(typ, cls) -> bool:
    """At compile time: is the Numba type ``typ`` the namedtuple record class ``cls``?"""
    return isinstance(typ, types.BaseNamedTuple) and typ.instance_class is cls
